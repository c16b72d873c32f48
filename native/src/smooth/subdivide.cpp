#include "particlemesh/smooth/subdivide.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <string>

#include "core/parallel.h"
#include "core/progress_tracker.h"
#include "particlemesh/core/error.h"
#include "smooth/control_mesh.h"
#include "smooth/schemes.h"

namespace PM_NAMESPACE {

namespace {

using Clock = std::chrono::steady_clock;
double seconds_since(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }

constexpr uint64_t kMaxTrianglesCeiling = uint64_t(1) << 30;  // OpenSubdiv indexes with int
constexpr float kInfiniteSharpness = 10.0f;                   // Sdc::Crease::SHARPNESS_INFINITE

void check_options(const SmoothOptions& o) {
  if (o.scheme != SmoothScheme::Loop && o.scheme != SmoothScheme::Butterfly)
    throw Error(Status::InvalidArgument, "scheme must be Loop (0) or Butterfly (1), got " + std::to_string(int(o.scheme)));
  if (o.levels < 0 || o.levels > kMaxSmoothLevels)
    throw Error(Status::InvalidArgument, "levels must be in [0, " + std::to_string(kMaxSmoothLevels) + "], got " +
                                             std::to_string(o.levels) + " (each level multiplies the triangles by 4)");
  if (o.boundary != BoundaryRule::EdgeAndCorner && o.boundary != BoundaryRule::EdgeOnly)
    throw Error(Status::InvalidArgument, "boundary must be EdgeAndCorner (0) or EdgeOnly (1), got " +
                                             std::to_string(int(o.boundary)));
  if (o.crease_method != CreaseMethod::Uniform && o.crease_method != CreaseMethod::Chaikin)
    throw Error(Status::InvalidArgument, "crease_method must be Uniform (0) or Chaikin (1), got " +
                                             std::to_string(int(o.crease_method)));
  if (o.max_triangles == 0 || o.max_triangles > kMaxTrianglesCeiling)
    throw Error(Status::InvalidArgument, "max_triangles must be in [1, 2^30], got " + std::to_string(o.max_triangles));
  if (o.threads < 0) throw Error(Status::InvalidArgument, "threads must be >= 0 (0 = all cores)");
  if (o.scheme == SmoothScheme::Butterfly && !o.creases.empty())
    throw Error(Status::InvalidArgument, "creases are supported by the Loop scheme only (OpenMesh's butterfly "
                                         "subdivider has no creases)");
  for (size_t i = 0; i < o.creases.size(); ++i) {
    const float s = o.creases[i].sharpness;
    if (std::isnan(s) || s < 0)
      throw Error(Status::InvalidArgument, "creases[" + std::to_string(i) + "].sharpness is " + std::to_string(s) +
                                               " (must be >= 0; infinity = infinitely sharp)");
  }
}

void check_size(size_t triangles, const SmoothOptions& o) {
  // F * 4^levels with F < 2^31 and levels <= 10 fits in 64 bits.
  const uint64_t out = uint64_t(triangles) << (2 * o.levels);
  if (out > o.max_triangles)
    throw Error(Status::LimitExceeded,
                std::to_string(o.levels) + " levels on " + std::to_string(triangles) + " triangles would make " +
                    std::to_string(out) + " triangles, more than max_triangles = " +
                    std::to_string(o.max_triangles) + " (each level multiplies the triangles by 4)");
}

}  // namespace

namespace detail {

void check_corner_attributes(const TriMesh& mesh) {
  const size_t corners = 3 * mesh.triangles.size();
  for (const VertexAttribute& a : mesh.corner_attributes) {
    const std::string name = "corner attribute '" + a.name + "'";
    if (a.components < 1 || a.components > 64)
      throw Error(Status::InvalidInput, name + " has " + std::to_string(a.components) + " components (1 to 64)");
    if (a.values.size() != corners * size_t(a.components))
      throw Error(Status::InvalidInput, name + " has " + std::to_string(a.values.size()) + " values, not " +
                                            std::to_string(a.components) + " for each of the 3 x " +
                                            std::to_string(mesh.triangles.size()) + " triangle corners");
    for (size_t i = 0; i < a.values.size(); ++i)
      if (!(std::abs(a.values[i]) <= kMaxSmoothAttribute))
        throw Error(Status::InvalidInput, name + " of triangle " + std::to_string(i / size_t(a.components) / 3) +
                                              " is " + std::to_string(a.values[i]) + " (finite, at most 1e30)");
  }
}

/// The corner attributes through `levels` splits, linear over each input triangle: in the
/// layout both schemes share (subdivide.h), a child corner at a parent's corner takes its
/// value, one at an edge's new vertex the mean of the edge's two corners. (Both schemes alike:
/// OpenSubdiv's face-varying channels would cover Loop only.) A triangle the orientation
/// repair turned is (a, c, b) in the control mesh, and so are its corners' values.
std::vector<VertexAttribute> subdivide_corner_attributes(const TriMesh& mesh, const ControlMesh& cm, int levels) {
  std::vector<VertexAttribute> out;
  const size_t nf = mesh.triangles.size();
  std::vector<uint8_t> turned(nf);
  for (size_t f = 0; f < nf; ++f) turned[f] = cm.triangles[f][1] != cm.control_index[mesh.triangles[f][1]];
  for (const VertexAttribute& a : mesh.corner_attributes) {
    const size_t k = size_t(a.components);
    std::vector<float> level(a.values.size());
    for (size_t f = 0; f < nf; ++f)
      for (size_t c = 0; c < 3; ++c) {
        const size_t from = turned[f] && c > 0 ? 3 - c : c;
        std::copy_n(&a.values[(3 * f + from) * k], k, &level[(3 * f + c) * k]);
      }
    for (int l = 0; l < levels; ++l) {
      const size_t n = level.size() / (3 * k);
      std::vector<float> next(4 * level.size());
      parallel_blocks(n, 4096, [&](size_t begin, size_t end) {
        for (size_t t = begin; t < end; ++t) {
          const float* p = &level[3 * t * k];
          float* q = &next[12 * t * k];
          // Corners a, b, c, then the edges' points ab, bc, ca: slots 0..5.
          auto value = [&](int slot, size_t j) -> float {
            if (slot < 3) return p[size_t(slot) * k + j];
            const size_t u = size_t(slot - 3), v = (u + 1) % 3;
            return float(0.5 * (double(p[u * k + j]) + double(p[v * k + j])));
          };
          static constexpr int kChildren[4][3] = {{0, 3, 5}, {3, 1, 4}, {5, 4, 2}, {4, 5, 3}};
          for (int child = 0; child < 4; ++child)
            for (int c = 0; c < 3; ++c)
              for (size_t j = 0; j < k; ++j) *q++ = value(kChildren[child][c], j);
        }
      });
      level.swap(next);
    }
    out.push_back({a.name, a.components, std::move(level)});
  }
  return out;
}

void check_smooth_options(const SmoothOptions& options, size_t triangles) {
  check_options(options);
  if (triangles > size_t(INT32_MAX)) throw Error(Status::LimitExceeded, "more than 2^31 - 1 triangles");
  check_size(triangles, options);
}

void resolve_creases(const ControlMesh& cm, const SmoothOptions& options,
                     std::vector<std::pair<uint32_t, uint32_t>>* pairs, std::vector<float>* sharpness) {
  // Input indices -> control indices; each must be an edge of the mesh.
  for (size_t i = 0; i < options.creases.size(); ++i) {
    const CreaseEdge& c = options.creases[i];
    const std::pair<uint32_t, uint32_t> key{std::min(c.a, c.b), std::max(c.a, c.b)};
    if (!std::binary_search(cm.edges.begin(), cm.edges.end(), key))
      throw Error(Status::InvalidArgument, "creases[" + std::to_string(i) + "] = (" + std::to_string(c.a) + ", " +
                                               std::to_string(c.b) + ") is not an edge of the mesh");
    pairs->push_back({cm.control_index[c.a], cm.control_index[c.b]});
    sharpness->push_back(std::min(c.sharpness, kInfiniteSharpness));
  }
}

void finish_smooth_normals(TriMesh& m) {
  // Loop's limit normals where they exist, area-weighted ones elsewhere.
  const bool any_zero = std::any_of(m.normals.begin(), m.normals.end(), [](const Vec3& n) { return n == Vec3{}; });
  if (m.normals.empty() || any_zero) {
    std::vector<Vec3> area = area_weighted_normals(m.positions, m.triangles);
    if (m.normals.empty()) {
      m.normals = std::move(area);
    } else {
      for (size_t i = 0; i < m.normals.size(); ++i)
        if (m.normals[i] == Vec3{}) m.normals[i] = area[i];
    }
  }
}

}  // namespace detail

SmoothResult smooth_mesh(const TriMesh& mesh, const SmoothOptions& options) {
  detail::check_smooth_options(options, mesh.triangles.size());

  detail::ProgressTracker tracker(options.progress);
  SmoothResult result;
  SmoothStats& st = result.stats;
  detail::with_threads(options.threads, [&] {
    auto t0 = Clock::now();
    tracker.stage("checking the mesh", 0.0, 0.05);
    detail::check_corner_attributes(mesh);
    detail::ControlMesh cm = detail::prepare_control_mesh(mesh, options.scheme == SmoothScheme::Loop);
    st.input_vertices = mesh.positions.size();
    st.dropped_vertices = cm.dropped_vertices;
    st.control_vertices = cm.positions.size();
    st.control_triangles = cm.triangles.size();
    st.control_edges = cm.edges.size();
    st.boundary_edges = cm.boundary_edges;
    st.nonmanifold_edges = cm.nonmanifold_edges;
    st.nonmanifold_vertices = cm.nonmanifold_vertices;
    st.reoriented_triangles = cm.reoriented_triangles;
    st.levels = options.levels;

    std::vector<std::pair<uint32_t, uint32_t>> crease_pairs;
    std::vector<float> crease_sharpness;
    detail::resolve_creases(cm, options, &crease_pairs, &crease_sharpness);
    st.creases = crease_pairs.size();
    st.seconds_prepare = seconds_since(t0);
    tracker.check();

    if (options.scheme == SmoothScheme::Loop)
      detail::loop_subdivide(cm, options, crease_pairs, crease_sharpness, tracker, result);
    else
      detail::butterfly_subdivide(cm, options, tracker, result);
    result.mesh.corner_attributes = detail::subdivide_corner_attributes(mesh, cm, options.levels);

    // Normals: Loop's limit normals where they exist, area-weighted ones elsewhere.
    auto t1 = Clock::now();
    tracker.stage("normals", 0.95, 1.0);
    detail::finish_smooth_normals(result.mesh);
    st.seconds_output += seconds_since(t1);
    result.original_vertex = std::move(cm.original_vertex);
    st.vertices = result.mesh.positions.size();
    st.triangles = result.mesh.triangles.size();
    tracker.finish();
  });
  return result;
}

}  // namespace particlemesh
