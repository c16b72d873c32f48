// The topology report the CLI writes for every output (particlemesh/mesh/topology_report.h)
// beside the serial version it replaced (kept in tests/ as the tests' reference), on the
// meshes the CLI makes: a closed torus grid and a Loop-smoothed sphere (level 2).
//
//   build/bench/topology_bench [--benchmark_repetitions=5 --benchmark_report_aggregates_only=true]
//
// The target: about 50 ms per million triangles on this machine's cores.
#include <benchmark/benchmark.h>
#include <tbb/task_arena.h>

#include "mesh/topology_report_reference.h"
#include "particlemesh/mesh/topology_report.h"
#include "particlemesh/sample/shapes.h"
#include "particlemesh/smooth/subdivide.h"

using namespace particlemesh;

namespace {

const TriMesh& mesh_of(int which) {
  static const TriMesh torus = torus_mesh(1.0, 0.3, 1000, 500);  // 1 000 000 triangles
  static const TriMesh sphere = [] {
    SmoothOptions o;
    o.levels = 2;
    return smooth_mesh(icosphere_mesh(6), o).mesh;  // 81 920 x 16 = 1 310 720 triangles
  }();
  return which == 0 ? torus : sphere;
}

void BM_TopologyReport(benchmark::State& state) {
  const TriMesh& m = mesh_of(int(state.range(0)));
  const int threads = int(state.range(1)) == 0 ? tbb::this_task_arena::max_concurrency() : int(state.range(1));
  tbb::task_arena arena(threads);
  for (auto _ : state) benchmark::DoNotOptimize(arena.execute([&] { return topology_report(m); }));
  state.counters["triangles"] = double(m.triangles.size());
  state.counters["Mtri_per_s"] =
      benchmark::Counter(double(m.triangles.size()) * 1e-6, benchmark::Counter::kIsIterationInvariantRate);
}

void BM_TopologyReportSerialReference(benchmark::State& state) {
  const TriMesh& m = mesh_of(int(state.range(0)));
  for (auto _ : state) benchmark::DoNotOptimize(reference::topology_report(m));
  state.counters["triangles"] = double(m.triangles.size());
  state.counters["Mtri_per_s"] =
      benchmark::Counter(double(m.triangles.size()) * 1e-6, benchmark::Counter::kIsIterationInvariantRate);
}

}  // namespace

// mesh: 0 = torus grid (1M triangles), 1 = Loop level-2 sphere (1.3M); threads: 0 = all.
BENCHMARK(BM_TopologyReport)->ArgsProduct({{0, 1}, {0, 1}})->ArgNames({"mesh", "threads"})->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_TopologyReportSerialReference)->ArgsProduct({{0, 1}})->ArgNames({"mesh"})->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK_MAIN();
