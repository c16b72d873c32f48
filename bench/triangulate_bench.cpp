// Triangulation throughput on evenly spaced spheres (Fibonacci spiral), spacing estimate
// included, as the issue asks. Run:
//   build/bench/triangulate_bench --benchmark_counters_tabular=true
#include <benchmark/benchmark.h>

#include <algorithm>
#include <random>

#include "particlemesh/sample/shapes.h"
#include "particlemesh/surface/reconstruct.h"
#include "particlemesh/spatial/spacing.h"
#include "particlemesh/surface/triangulate.h"

using namespace particlemesh;

// The same points in a random order (a fixed seed): particles as a simulation or a merged
// scan lists them, with no locality in their indices.
static PointCloud shuffled(PointCloud c) {
  std::vector<size_t> perm(c.size());
  for (size_t i = 0; i < perm.size(); ++i) perm[i] = i;
  std::shuffle(perm.begin(), perm.end(), std::mt19937_64(7));
  PointCloud s;
  for (size_t i : perm) s.positions.push_back(c.positions[i]);
  return s;
}

static void BM_TriangulateRaw(benchmark::State& state) {
  const PointCloud c = state.range(2) ? shuffled(fibonacci_sphere(size_t(state.range(0)))) : fibonacci_sphere(size_t(state.range(0)));
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
    ->ArgNames({"points", "threads", "shuffled"})
    ->Args({10000, 0, 0})
    ->Args({100000, 0, 0})
    ->Args({1000000, 0, 0})
    ->Args({1000000, 1, 0})
    ->Args({100000, 0, 1})
    ->Args({1000000, 0, 1})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

// The whole finished surface (raw test + normals + extraction + repair + orientation), to set
// beside BM_TriangulateRaw on the same points. Normals: estimated (the cloud's are dropped),
// the slower and more general path.
static void BM_ReconstructSurface(benchmark::State& state) {
  PointCloud c = state.range(2) ? shuffled(fibonacci_sphere(size_t(state.range(0)))) : fibonacci_sphere(size_t(state.range(0)));
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
    ->ArgNames({"points", "threads", "shuffled"})
    ->Args({100000, 0, 0})
    ->Args({1000000, 0, 0})
    ->Args({100000, 0, 1})
    ->Args({1000000, 0, 1})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

static void BM_EstimateSpacing(benchmark::State& state) {
  const PointCloud c = fibonacci_sphere(size_t(state.range(0)));
  for (auto _ : state) benchmark::DoNotOptimize(estimate_spacing(c.positions.data(), c.size()));
  state.counters["points/s"] = benchmark::Counter(double(state.range(0)), benchmark::Counter::kIsIterationInvariantRate);
}
BENCHMARK(BM_EstimateSpacing)->Arg(1000000)->Unit(benchmark::kMillisecond)->UseRealTime();

BENCHMARK_MAIN();
