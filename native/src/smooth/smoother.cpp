#include "particlemesh/smooth/smoother.h"

#include <chrono>
#include <cstring>
#include <string>

#include <opensubdiv/far/primvarRefiner.h>
#include <tbb/parallel_invoke.h>

#include "core/parallel.h"
#include "core/progress_tracker.h"
#include "particlemesh/core/error.h"
#include "smooth/control_mesh.h"
#include "smooth/loop_limit.h"
#include "smooth/loop_refiner.h"
#include "smooth/schemes.h"

namespace PM_NAMESPACE {

namespace {

using Clock = std::chrono::steady_clock;
double seconds_since(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }
using PrimvarRefiner = OpenSubdiv::Far::PrimvarRefinerReal<double>;

/// One level's stencils: refined vertex r is the sum, in order, of weight[k] x (vertex
/// index[k] of the level before) for k in [start[r], start[r] + count[r]), exactly as
/// PrimvarRefiner::Interpolate adds them.
struct Stencils {
  std::vector<uint32_t> start, count, index;
  std::vector<double> weight;
};

/// What PrimvarRefiner::Interpolate is given to record its stencils: a source vertex is its
/// index; a destination vertex appends the weights it is given. PrimvarRefiner clears a
/// refined vertex and adds all its weights before it goes on to the next one.
struct SourceIndex {
  uint32_t i;
};
struct SourceIndices {
  SourceIndex operator[](int i) const { return {uint32_t(i)}; }
};
struct Recorder {
  Stencils* s;
  uint32_t row;
  void Clear() {
    s->start[row] = uint32_t(s->index.size());
    s->count[row] = 0;
  }
  void AddWithWeight(const SourceIndex& src, double w) {
    if (s->start[row] + s->count[row] != s->index.size())
      throw Error(Status::Internal, "OpenSubdiv interleaved the weights of two refined vertices");
    s->index.push_back(src.i);
    s->weight.push_back(w);
    ++s->count[row];
  }
  // Refined vertices from refined face centres: Catmull-Clark's, never Loop's.
  void AddWithWeight(const Recorder&, double) {
    throw Error(Status::Internal, "a Loop stencil referred to a face centre");
  }
};
struct Recorders {
  Stencils* s;
  Recorder operator[](int i) const { return {s, uint32_t(i)}; }
};

}  // namespace

struct Smoother::Impl {
  SmoothOptions options;
  size_t input_vertices = 0;
  std::vector<Triangle> input_triangles;
  std::vector<VertexAttribute> input_corner_attributes, corner_attributes;  // given, subdivided
  detail::ControlMesh control;  // its positions and attributes are dropped after construction
  SmoothStats stats;            // of the construction (checks, refinement)
  // Loop:
  std::vector<Stencils> levels;
  std::vector<Triangle> triangles;  // of the last level
  bool own_limit = false;
  detail::LoopRings rings;
  std::unique_ptr<detail::LoopLimitMasks> masks;
  std::unique_ptr<OpenSubdiv::Far::TopologyRefiner> refiner;  // kept for OpenSubdiv's limit only

  SmoothResult evaluate_loop(std::vector<Vec3> pos, const std::vector<VertexAttribute>& attributes) const;
};

Smoother::Smoother(const TriMesh& mesh, const SmoothOptions& options) : impl_(std::make_unique<Impl>()) {
  Impl& m = *impl_;
  detail::check_smooth_options(options, mesh.triangles.size());
  m.options = options;
  m.options.progress = {};
  m.input_vertices = mesh.positions.size();
  m.input_triangles = mesh.triangles;
  detail::ProgressTracker tracker(options.progress);
  detail::with_threads(options.threads, [&] {
    const auto t0 = Clock::now();
    tracker.stage("checking the mesh", 0.0, 0.1);
    detail::check_corner_attributes(mesh);
    m.control = detail::prepare_control_mesh(mesh, options.scheme == SmoothScheme::Loop);
    m.input_corner_attributes = mesh.corner_attributes;
    m.corner_attributes = detail::subdivide_corner_attributes(mesh, m.control, options.levels);
    SmoothStats& st = m.stats;
    st.input_vertices = mesh.positions.size();
    st.dropped_vertices = m.control.dropped_vertices;
    st.control_vertices = m.control.positions.size();
    st.control_triangles = m.control.triangles.size();
    st.control_edges = m.control.edges.size();
    st.boundary_edges = m.control.boundary_edges;
    st.nonmanifold_edges = m.control.nonmanifold_edges;
    st.nonmanifold_vertices = m.control.nonmanifold_vertices;
    st.reoriented_triangles = m.control.reoriented_triangles;
    st.levels = options.levels;
    std::vector<std::pair<uint32_t, uint32_t>> crease_pairs;
    std::vector<float> crease_sharpness;
    detail::resolve_creases(m.control, options, &crease_pairs, &crease_sharpness);
    st.creases = crease_pairs.size();
    st.seconds_prepare = seconds_since(t0);
    tracker.check();
    if (options.scheme != SmoothScheme::Loop) {
      tracker.finish();
      return;  // butterfly: evaluate() subdivides the control mesh again
    }

    const auto t1 = Clock::now();
    tracker.stage("refining topology (OpenSubdiv)", 0.1, 0.5);
    m.own_limit = detail::own_loop_limit(m.control, options, crease_pairs.size());
    std::unique_ptr<OpenSubdiv::Far::TopologyRefiner> refiner =
        detail::loop_refiner(m.control, options, crease_pairs, crease_sharpness, options.limit && !m.own_limit);
    tracker.check();
    tracker.stage("recording the stencils", 0.5, 0.8);
    const PrimvarRefiner primvar(*refiner);
    m.levels.resize(size_t(options.levels));
    for (int l = 1; l <= options.levels; ++l) {
      Stencils& s = m.levels[size_t(l - 1)];
      const size_t n = size_t(refiner->GetLevel(l).GetNumVertices());
      s.start.assign(n, 0);
      s.count.assign(n, 0);
      const SourceIndices src;
      Recorders dst{&s};
      primvar.Interpolate(l, src, dst);
      s.index.shrink_to_fit();
      s.weight.shrink_to_fit();
      tracker.check();
    }
    const auto last = refiner->GetLevel(options.levels);
    detail::copy_triangles(last, m.triangles);
    const size_t n_out = size_t(last.GetNumVertices());
    if (m.own_limit) {
      tracker.stage("limit rings", 0.8, 1.0);
      if (detail::build_loop_rings(m.triangles, n_out, &m.rings)) {
        m.masks = std::make_unique<detail::LoopLimitMasks>(m.rings.max_valence);
      } else {
        // Not one closed fan at every vertex after all (cannot happen on a checked closed
        // 2-manifold): OpenSubdiv's limit, on the full last level.
        m.own_limit = false;
        refiner = detail::loop_refiner(m.control, options, crease_pairs, crease_sharpness, true);
      }
    }
    if (options.limit && !m.own_limit) m.refiner = std::move(refiner);
    st.seconds_refine = seconds_since(t1);
    m.control.positions = {};
    m.control.attributes = {};
    tracker.finish();
  });
}

Smoother::~Smoother() = default;
Smoother::Smoother(Smoother&&) noexcept = default;
Smoother& Smoother::operator=(Smoother&&) noexcept = default;

size_t Smoother::vertex_count() const { return impl_->input_vertices; }
size_t Smoother::triangle_count() const { return impl_->input_triangles.size(); }
const SmoothOptions& Smoother::options() const { return impl_->options; }

bool Smoother::matches(const std::vector<Triangle>& triangles, size_t vertex_count) const {
  return vertex_count == impl_->input_vertices && triangles.size() == impl_->input_triangles.size() &&
         std::memcmp(triangles.data(), impl_->input_triangles.data(), triangles.size() * sizeof(Triangle)) == 0;
}

SmoothResult Smoother::evaluate(const std::vector<Vec3>& positions, const std::vector<VertexAttribute>& attributes) const {
  const Impl& m = *impl_;
  if (positions.size() != m.input_vertices)
    throw Error(Status::InvalidInput, "evaluate() was given " + std::to_string(positions.size()) +
                                          " positions for a mesh of " + std::to_string(m.input_vertices) + " vertices");
  return detail::with_threads(m.options.threads, [&] {
    const bool same_orientation = detail::same_volume_decisions(m.control, m.input_triangles, positions);
    if (m.options.scheme != SmoothScheme::Loop || !same_orientation) {
      // Butterfly, or moved vertices that turn a repaired component the other way: the
      // whole subdivision, as smooth_mesh() (which then agrees by construction).
      TriMesh mesh;
      mesh.positions = positions;
      mesh.triangles = m.input_triangles;
      mesh.attributes = attributes;
      mesh.corner_attributes = m.input_corner_attributes;
      return smooth_mesh(mesh, m.options);
    }
    std::vector<Vec3> pos;
    std::vector<VertexAttribute> attr;
    detail::compact_vertex_values(positions, attributes, m.control.original_vertex, &pos, &attr);
    SmoothResult out = m.evaluate_loop(std::move(pos), attr);
    out.mesh.corner_attributes = m.corner_attributes;
    return out;
  });
}

SmoothResult Smoother::Impl::evaluate_loop(std::vector<Vec3> pos, const std::vector<VertexAttribute>& attributes) const {
  SmoothResult out;
  out.stats = stats;
  const auto t0 = Clock::now();
  // Attribute channels, vertex-major, as loop_subdivide interpolates them.
  int channels = 0;
  std::vector<double> attr = detail::interleave_channels(attributes, pos.size(), &channels);
  const size_t k = size_t(channels);
  // Level by level: each refined vertex the weighted sum PrimvarRefiner forms.
  std::vector<Vec3> pos_next;
  std::vector<double> attr_next;
  for (const Stencils& s : levels) {
    const size_t n = s.start.size();
    pos_next.resize(n);
    attr_next.resize(n * k);
    detail::parallel_blocks(n, 4096, [&](size_t b, size_t e) {
      for (size_t r = b; r < e; ++r) {
        const uint32_t begin = s.start[r], end = begin + s.count[r];
        double p[3] = {0, 0, 0};
        for (uint32_t q = begin; q < end; ++q) {
          const double w = s.weight[q];
          const Vec3& src = pos[s.index[q]];
          p[0] += w * src.x;
          p[1] += w * src.y;
          p[2] += w * src.z;
        }
        pos_next[r] = {p[0], p[1], p[2]};
        if (k == 0) continue;
        double* d = attr_next.data() + r * k;
        std::fill(d, d + k, 0.0);
        for (uint32_t q = begin; q < end; ++q) {
          const double w = s.weight[q];
          const double* src = attr.data() + size_t(s.index[q]) * k;
          for (size_t j = 0; j < k; ++j) d[j] += w * src[j];
        }
      }
    });
    pos.swap(pos_next);
    attr.swap(attr_next);
  }
  pos_next = {};
  attr_next = {};
  out.stats.seconds_refine = seconds_since(t0);

  // The limit.
  const auto t1 = Clock::now();
  const size_t n_out = pos.size();
  TriMesh& mesh = out.mesh;
  if (options.limit && own_limit) {
    std::vector<Vec3> lim;
    std::vector<double> attr_lim(n_out * k);
    tbb::parallel_invoke([&] { detail::loop_limit_positions(rings, *masks, pos, lim, mesh.normals); },
                         [&] {
                           if (k > 0) detail::loop_limit_channels(rings, *masks, attr.data(), channels, attr_lim.data());
                         });
    pos.swap(lim);
    attr.swap(attr_lim);
    out.stats.limit = true;
  } else if (options.limit) {
    detail::opensubdiv_limit(*refiner, pos, attr, channels, mesh.normals);
    out.stats.limit = true;
  }
  out.stats.seconds_limit = seconds_since(t1);

  // The mesh, as smooth_mesh() finishes it.
  const auto t2 = Clock::now();
  mesh.positions = std::move(pos);
  mesh.triangles = triangles;
  mesh.attributes = detail::split_channels(attributes, attr, channels, n_out);
  detail::finish_smooth_normals(mesh);
  out.original_vertex = control.original_vertex;
  out.stats.vertices = mesh.positions.size();
  out.stats.triangles = mesh.triangles.size();
  out.stats.seconds_output = seconds_since(t2);
  return out;
}

}  // namespace particlemesh
