// Loop subdivision: particlemesh's smooth_mesh (OpenSubdiv) against OpenMesh's own LoopT
// subdivider on the same meshes in the same run; butterfly (OpenMesh's ModifiedButterflyT
// behind smooth_mesh) for reference.
//
//   build/bench/smooth_bench --benchmark_counters_tabular=true
//
// Meshes: closed tori of 100k and 1M triangles. "regular" splits every grid quad the same
// way (all valence 6); "irregular" picks each quad's diagonal at random (valences 4..8, like
// a particle triangulation), which takes Loop's extraordinary-vertex masks.
//
// What each row times, all from flat arrays (TriMesh) to flat arrays:
//   Loop_particlemesh           checks + OpenSubdiv refinement + interpolation + output
//                               (limit=false: the refined points, the same surface points as
//                               OpenMesh's LoopT) and area-weighted normals;
//   Loop_particlemesh_limit     the default: exact limit positions and normals;
//   Loop_OpenMesh_LoopT         build OpenMesh's half-edge mesh, LoopT, copy out;
//   Loop_OpenMesh_LoopT_only    LoopT alone (mesh building and copying outside the timing).
#include <benchmark/benchmark.h>

#include <OpenMesh/Core/Mesh/TriMesh_ArrayKernelT.hh>
#include <OpenMesh/Tools/Subdivider/Uniform/LoopT.hh>

#include <cmath>
#include <map>
#include <random>
#include <stdexcept>

#include "particlemesh/smooth/smoother.h"
#include "particlemesh/smooth/subdivide.h"

using namespace particlemesh;

namespace {

struct OMTraits : OpenMesh::DefaultTraits {
  typedef OpenMesh::Vec3d Point;
  typedef OpenMesh::Vec3d Normal;
};
using OMMesh = OpenMesh::TriMesh_ArrayKernelT<OMTraits>;

/// A closed torus with nu x nv quads, each split along a diagonal (random if `irregular`).
TriMesh torus(int nu, int nv, bool irregular) {
  TriMesh m;
  const double R = 1.0, r = 0.35, pi = 3.14159265358979323846;
  for (int i = 0; i < nu; ++i)
    for (int j = 0; j < nv; ++j) {
      const double u = 2 * pi * i / nu, v = 2 * pi * j / nv;
      m.positions.push_back({(R + r * std::cos(v)) * std::cos(u), (R + r * std::cos(v)) * std::sin(u), r * std::sin(v)});
    }
  auto id = [&](int i, int j) { return uint32_t(((i + nu) % nu) * nv + (j + nv) % nv); };
  std::mt19937_64 rng(12345);
  for (int i = 0; i < nu; ++i)
    for (int j = 0; j < nv; ++j) {
      const uint32_t a = id(i, j), b = id(i + 1, j), c = id(i + 1, j + 1), d = id(i, j + 1);
      if (irregular && (rng() & 1)) {
        m.triangles.push_back({a, b, d});
        m.triangles.push_back({b, c, d});
      } else {
        m.triangles.push_back({a, b, c});
        m.triangles.push_back({a, c, d});
      }
    }
  return m;
}

const TriMesh& mesh_for(int64_t triangles, bool irregular) {
  static std::map<std::pair<int64_t, bool>, TriMesh> cache;
  auto key = std::make_pair(triangles, irregular);
  auto it = cache.find(key);
  if (it != cache.end()) return it->second;
  // nu * nv * 2 = triangles with nu = 2 nv (100k: 316 x 158 ~ 99 856; 1M: 1000 x 500).
  const int nv = triangles == 1000000 ? 500 : int(std::lround(std::sqrt(double(triangles) / 4)));
  const int nu = triangles == 1000000 ? 1000 : int(std::lround(double(triangles) / (2.0 * nv)));
  return cache.emplace(key, torus(nu, nv, irregular)).first->second;
}

OMMesh to_openmesh(const TriMesh& m) {
  OMMesh om;
  om.reserve(m.positions.size(), 3 * m.triangles.size() / 2, m.triangles.size());
  for (const auto& p : m.positions) om.add_vertex(OMMesh::Point(p.x, p.y, p.z));
  for (const auto& t : m.triangles)
    om.add_face(OMMesh::VertexHandle(int(t[0])), OMMesh::VertexHandle(int(t[1])), OMMesh::VertexHandle(int(t[2])));
  return om;
}

TriMesh from_openmesh(const OMMesh& om) {
  TriMesh out;
  out.positions.resize(om.n_vertices());
  for (size_t i = 0; i < om.n_vertices(); ++i) {
    const auto& p = om.point(OMMesh::VertexHandle(int(i)));
    out.positions[i] = {p[0], p[1], p[2]};
  }
  out.triangles.resize(om.n_faces());
  for (size_t f = 0; f < om.n_faces(); ++f) {
    auto h = om.halfedge_handle(OMMesh::FaceHandle(int(f)));
    for (int c = 0; c < 3; ++c, h = om.next_halfedge_handle(h)) out.triangles[f][size_t(c)] = uint32_t(om.to_vertex_handle(h).idx());
  }
  return out;
}

void counters(benchmark::State& state, int64_t in_tris, int levels) {
  const double out = double(in_tris) * double(int64_t(1) << (2 * levels));
  state.counters["in_tris"] = double(in_tris);
  state.counters["out_tris"] = out;
  state.counters["out_tris/s"] = benchmark::Counter(out, benchmark::Counter::kIsIterationInvariantRate);
}

// Args: input triangles, levels, irregular (0/1), threads (0 = all)
void Loop_particlemesh(benchmark::State& state) {
  const TriMesh& m = mesh_for(state.range(0), state.range(2) != 0);
  SmoothOptions o;
  o.levels = int(state.range(1));
  o.limit = false;
  o.threads = int(state.range(3));
  for (auto _ : state) benchmark::DoNotOptimize(smooth_mesh(m, o));
  counters(state, int64_t(m.triangles.size()), o.levels);
}

void Loop_particlemesh_limit(benchmark::State& state) {
  const TriMesh& m = mesh_for(state.range(0), state.range(2) != 0);
  SmoothOptions o;
  o.levels = int(state.range(1));
  o.limit = true;
  o.threads = int(state.range(3));
  for (auto _ : state) benchmark::DoNotOptimize(smooth_mesh(m, o));
  counters(state, int64_t(m.triangles.size()), o.levels);
}

// Refine once, evaluate many (smooth/smoother.h): the Smoother made outside the timing, then
// evaluate() of moved positions (each iteration a new frame) -- the same mesh smooth_mesh
// gives, for the default limit=true. The row to set against Loop_particlemesh_limit.
void Loop_Smoother_evaluate(benchmark::State& state) {
  const TriMesh& m = mesh_for(state.range(0), state.range(2) != 0);
  SmoothOptions o;
  o.levels = int(state.range(1));
  o.limit = true;
  o.threads = int(state.range(3));
  const Smoother smoother(m, o);
  std::vector<Vec3> p = m.positions;
  double t = 0;
  for (auto _ : state) {
    state.PauseTiming();
    t += 0.1;
    for (size_t i = 0; i < p.size(); ++i) p[i] = m.positions[i] * (1.0 + 0.01 * std::sin(t + double(i)));
    state.ResumeTiming();
    benchmark::DoNotOptimize(smoother.evaluate(p));
  }
  counters(state, int64_t(m.triangles.size()), o.levels);
}

// Making the Smoother: the checks, OpenSubdiv's refinement and the stencils' recording.
void Loop_Smoother_make(benchmark::State& state) {
  const TriMesh& m = mesh_for(state.range(0), state.range(2) != 0);
  SmoothOptions o;
  o.levels = int(state.range(1));
  o.limit = true;
  o.threads = int(state.range(3));
  for (auto _ : state) benchmark::DoNotOptimize(Smoother(m, o));
  counters(state, int64_t(m.triangles.size()), o.levels);
}

void Loop_OpenMesh_LoopT(benchmark::State& state) {
  const TriMesh& m = mesh_for(state.range(0), state.range(2) != 0);
  const int levels = int(state.range(1));
  for (auto _ : state) {
    OMMesh om = to_openmesh(m);
    OpenMesh::Subdivider::Uniform::LoopT<OMMesh, double> loop;
    loop.attach(om);
    if (!loop(size_t(levels))) throw std::runtime_error("LoopT failed");
    loop.detach();
    benchmark::DoNotOptimize(from_openmesh(om));
  }
  counters(state, int64_t(m.triangles.size()), levels);
}

void Loop_OpenMesh_LoopT_only(benchmark::State& state) {
  const TriMesh& m = mesh_for(state.range(0), state.range(2) != 0);
  const int levels = int(state.range(1));
  for (auto _ : state) {
    state.PauseTiming();
    OMMesh om = to_openmesh(m);
    state.ResumeTiming();
    OpenMesh::Subdivider::Uniform::LoopT<OMMesh, double> loop;
    loop.attach(om);
    if (!loop(size_t(levels))) throw std::runtime_error("LoopT failed");
    loop.detach();
    state.PauseTiming();
    om = OMMesh();
    state.ResumeTiming();
  }
  counters(state, int64_t(m.triangles.size()), levels);
}

void Butterfly_particlemesh(benchmark::State& state) {
  const TriMesh& m = mesh_for(state.range(0), state.range(2) != 0);
  SmoothOptions o;
  o.scheme = SmoothScheme::Butterfly;
  o.levels = int(state.range(1));
  o.threads = int(state.range(3));
  for (auto _ : state) benchmark::DoNotOptimize(smooth_mesh(m, o));
  counters(state, int64_t(m.triangles.size()), o.levels);
}

void loop_args(benchmark::internal::Benchmark* b) {
  for (int64_t tris : {100000, 1000000})
    for (int64_t levels : {1, 2})
      for (int64_t irregular : {0, 1}) b->Args({tris, levels, irregular, 0});
  b->ArgNames({"tris", "levels", "irregular", "threads"});
  b->Unit(benchmark::kMillisecond)->UseRealTime()->MeasureProcessCPUTime();
}

void openmesh_args(benchmark::internal::Benchmark* b) {
  for (int64_t tris : {100000, 1000000})
    for (int64_t levels : {1, 2})
      for (int64_t irregular : {0, 1}) b->Args({tris, levels, irregular, 1});
  b->ArgNames({"tris", "levels", "irregular", "threads"});
  b->Unit(benchmark::kMillisecond)->UseRealTime()->MeasureProcessCPUTime();
}

void one_thread_args(benchmark::internal::Benchmark* b) {
  for (int64_t levels : {1, 2}) b->Args({1000000, levels, 1, 1});
  b->ArgNames({"tris", "levels", "irregular", "threads"});
  b->Unit(benchmark::kMillisecond)->UseRealTime()->MeasureProcessCPUTime();
}

void butterfly_args(benchmark::internal::Benchmark* b) {
  for (int64_t levels : {1, 2}) b->Args({100000, levels, 1, 0});
  b->ArgNames({"tris", "levels", "irregular", "threads"});
  b->Unit(benchmark::kMillisecond)->UseRealTime()->MeasureProcessCPUTime();
}

}  // namespace

BENCHMARK(Loop_particlemesh)->Apply(loop_args);
BENCHMARK(Loop_particlemesh_limit)->Apply(loop_args);
BENCHMARK(Loop_OpenMesh_LoopT)->Apply(openmesh_args);
BENCHMARK(Loop_OpenMesh_LoopT_only)->Apply(openmesh_args);
BENCHMARK(Loop_particlemesh)->Name("Loop_particlemesh_1thread")->Apply(one_thread_args);
BENCHMARK(Butterfly_particlemesh)->Apply(butterfly_args);
BENCHMARK(Loop_Smoother_evaluate)->Apply(loop_args);
BENCHMARK(Loop_Smoother_make)->Apply(loop_args);

BENCHMARK_MAIN();
