// Triangulation throughput on evenly spaced spheres (Fibonacci spiral), spacing estimate
// included, as the issue asks. Run:
//   build/bench/triangulate_bench --benchmark_counters_tabular=true
#include <benchmark/benchmark.h>

#include "particlemesh/sample/shapes.h"
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

static void BM_EstimateSpacing(benchmark::State& state) {
  const PointCloud c = fibonacci_sphere(size_t(state.range(0)));
  for (auto _ : state) benchmark::DoNotOptimize(estimate_spacing(c.positions.data(), c.size()));
  state.counters["points/s"] = benchmark::Counter(double(state.range(0)), benchmark::Counter::kIsIterationInvariantRate);
}
BENCHMARK(BM_EstimateSpacing)->Arg(1000000)->Unit(benchmark::kMillisecond)->UseRealTime();

BENCHMARK_MAIN();
