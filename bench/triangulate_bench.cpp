// Triangulation throughput on evenly spaced spheres (Fibonacci spiral), spacing estimate
// included, as the issue asks. Run:
//   build/bench/triangulate_bench --benchmark_counters_tabular=true
#include <benchmark/benchmark.h>

#include "particlemesh/sample/shapes.h"
#include "particlemesh/surface/reconstruct.h"
#include "particlemesh/surface/spacing.h"
#include "particlemesh/surface/triangulate.h"

using namespace particlemesh;

static void BM_TriangulateRaw(benchmark::State& state) {
  const PointCloud c = fibonacci_sphere(size_t(state.range(0)));
  TriangulateOptions o;
  o.threads = int(state.range(1));
  size_t kept = 0;
  for (auto _ : state) {
    TriangulateResult r = triangulate_raw(c, o);
    kept = r.mesh.triangles.size();
    benchmark::DoNotOptimize(r);
  }
  state.SetItemsProcessed(int64_t(state.iterations()) * state.range(0));
  state.counters["points/s"] = benchmark::Counter(double(state.range(0)), benchmark::Counter::kIsIterationInvariantRate);
  state.counters["triangles"] = double(kept);
}
BENCHMARK(BM_TriangulateRaw)
    ->ArgNames({"points", "threads"})
    ->Args({10000, 0})
    ->Args({100000, 0})
    ->Args({1000000, 0})
    ->Args({1000000, 1})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

// The whole chain of issue 3 (raw test + normals + extraction + repair + orientation), to set
// beside BM_TriangulateRaw on the same points. Normals: estimated (the cloud's are dropped),
// the slower and more general path.
static void BM_ReconstructSurface(benchmark::State& state) {
  PointCloud c = fibonacci_sphere(size_t(state.range(0)));
  c.normals.clear();
  SurfaceOptions o;
  o.threads = int(state.range(1));
  SurfaceStats last;
  for (auto _ : state) {
    SurfaceResult r = reconstruct_surface(c, o);
    last = r.surface;
    benchmark::DoNotOptimize(r);
  }
  state.counters["points/s"] = benchmark::Counter(double(state.range(0)), benchmark::Counter::kIsIterationInvariantRate);
  state.counters["normals_s"] = last.seconds_normals;
  state.counters["extract_s"] = last.seconds_extraction;
  state.counters["repair_s"] = last.seconds_repair;
}
BENCHMARK(BM_ReconstructSurface)
    ->ArgNames({"points", "threads"})
    ->Args({100000, 0})
    ->Args({1000000, 0})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

static void BM_EstimateSpacing(benchmark::State& state) {
  const PointCloud c = fibonacci_sphere(size_t(state.range(0)));
  for (auto _ : state) benchmark::DoNotOptimize(estimate_spacing(c.positions.data(), c.size()));
  state.counters["points/s"] = benchmark::Counter(double(state.range(0)), benchmark::Counter::kIsIterationInvariantRate);
}
BENCHMARK(BM_EstimateSpacing)->Arg(1000000)->Unit(benchmark::kMillisecond)->UseRealTime();

BENCHMARK_MAIN();
