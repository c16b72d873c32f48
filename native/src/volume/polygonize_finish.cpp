#include "volume/polygonize_finish.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "particlemesh/core/error.h"
#include "particlemesh/mesh/components.h"
#include "particlemesh/smooth/taubin.h"
#include "core/parallel.h"
#include "mesh/short_edges.h"
#include "spatial/spacing_impl.h"

namespace PM_NAMESPACE::detail {

namespace {

// collapse_edges at most half a cell: a longer edge is no sliver's, and a collapse would move
// a vertex by a visible share of the lattice's resolution.
constexpr double kMaxCollapseEdges = 0.5;
// No triangle next to a collapse turns by more than 60 degrees (cos 60 = 0.5).
constexpr double kCollapseMinCos = 0.5;

std::string num(double v) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.17g", v);
  return buf;
}

}  // namespace

void validate_finishing(const PolygonizeOptions& o) {
  if (!(o.min_component_volume >= 0) || !std::isfinite(o.min_component_volume))
    throw Error(Status::InvalidArgument, "min_component_volume is " + num(o.min_component_volume) +
                                             " (must be a finite volume >= 0; 0 keeps every piece)");
  if (!(o.min_component_particles >= 0) || !std::isfinite(o.min_component_particles))
    throw Error(Status::InvalidArgument, "min_component_particles is " + num(o.min_component_particles) +
                                             " (must be finite and >= 0; 0 keeps every piece)");
  if (!(o.collapse_edges >= 0 && o.collapse_edges <= kMaxCollapseEdges))
    throw Error(Status::InvalidArgument, "collapse_edges is " + num(o.collapse_edges) +
                                             " (must be in [0, 0.5] cells; 0 collapses nothing)");
  validate_taubin(o.surface_smoothing);
  // Dropping pieces, collapsing edges and smoothing need the whole surface; a tile holds only
  // part of it.
  if (o.cells && (o.min_component_volume > 0 || o.min_component_particles > 0 || o.collapse_edges > 0 ||
                  o.surface_smoothing.iterations > 0))
    throw Error(Status::InvalidArgument,
                "a cell range (one tile of a cloud) cannot drop small pieces, collapse edges or smooth the mesh: "
                "min_component_volume, min_component_particles, collapse_edges and taubin_iterations need the "
                "whole surface");
}

AttributeSums::AttributeSums(std::vector<VertexAttribute>& out, size_t vertices, const ParticleField& field,
                             const std::vector<VertexAttribute>& attributes)
    : out_(out), field_(field), attributes_(attributes), kernel_(field.kernel()) {
  out.clear();
  const size_t nv = vertices, np = field.size();
  for (const VertexAttribute& a : attributes) {
    if (a.components < 1 || a.values.size() != np * size_t(a.components))
      throw Error(Status::InvalidInput, "attribute '" + a.name + "' has " + std::to_string(a.values.size()) +
                                            " values for " + std::to_string(np) + " particles x " +
                                            std::to_string(a.components) + " components");
    channels_ += size_t(a.components);
  }
  if (channels_ == 0) return;
  for (const VertexAttribute& a : attributes) out.push_back({a.name, a.components, std::vector<float>(nv * size_t(a.components))});
  sum_.resize(channels_);
}

void finish_polygonized(PolygonizeResult& r, const PolygonizeOptions& o, const ParticleField& field,
                        const Vec3* positions, size_t n, ProgressTracker& tracker,
                        const std::vector<VertexAttribute>* attributes) {
  const auto t0 = std::chrono::steady_clock::now();
  double limit = o.min_component_volume;
  if (o.min_component_particles > 0) {
    double s = field.spacing();
    if (!(s > 0)) {
      std::vector<Vec3> centres;
      if (positions == nullptr) {
        centres.resize(field.size());
        for (size_t i = 0; i < field.size(); ++i) centres[i] = field.position(i);
        positions = centres.data();
        n = centres.size();
      }
      try {
        s = estimate_spacing_impl(positions, n, tracker, 1.0, 1.0).spacing;
      } catch (const Error& e) {
        if (e.status() == Status::Cancelled) throw;
        throw Error(e.status(), std::string("min_component_particles needs the particle spacing, which cannot be "
                                            "estimated: ") + e.what() + " (give min_component_volume instead)");
      }
    }
    limit = std::max(limit, o.min_component_particles * s * s * s);
  }
  r.stats.min_component_volume = limit;
  if (limit > 0) {
    tracker.stage("dropping small pieces", 1.0, 1.0);
    r.stats.components_removed = remove_small_components(r.mesh, limit);
  }
  tracker.check();
  if (o.collapse_edges > 0 && !r.mesh.triangles.empty()) {
    tracker.stage("collapsing short edges", 1.0, 1.0);
    const double max_length = o.collapse_edges * r.stats.cell_size;
    // The merged vertex: the midpoint pulled onto F = T by Newton steps along the gradient
    // (an edge this short lies within a hair of the surface, so two or three steps), as
    // every other vertex lies on the true field; the midpoint itself if a step goes astray.
    const double T = field.threshold();
    auto place = [&](const Vec3& a, const Vec3& b) {
      const Vec3 m = (a + b) * 0.5;
      Vec3 x = m;
      for (int it = 0; it < 4; ++it) {
        Vec3 g;
        const double f = field.value_and_gradient(x, &g) - T;
        const double g2 = squared_norm(g);
        if (!(g2 > 0) || !std::isfinite(f)) break;
        const Vec3 step = g * (f / g2);
        x = x - step;
        // Converged when the step is under a thousandth of the edge: what is left is of the order
        // of its square over the radius of curvature.
        if (squared_norm(step) <= 1e-6 * max_length * max_length) break;
      }
      return is_finite(x) && squared_norm(x - m) <= 0.25 * max_length * max_length ? x : m;
    };
    const ShortEdgeCollapse c =
        collapse_short_edges(r.mesh, max_length, kCollapseMinCos, place, [&] { tracker.check(); });
    if (r.mesh.normals.size() == r.mesh.positions.size())
      parallel_blocks(c.moved.size(), 1024, [&](size_t begin, size_t end) {
        for (size_t i = begin; i < end; ++i) {
          const uint32_t v = c.moved[i];
          const Vec3 g = field.gradient(r.mesh.positions[v]);
          const double gn = norm(g);
          if (gn > 0 && std::isfinite(gn)) r.mesh.normals[v] = g * (-1.0 / gn);
        }
      });
    // Their attributes: the particles' at the new place (the mean the collapse gave them is
    // replaced), as every other vertex's, so polygonize_attributes at the mesh's vertices
    // gives them bit for bit.
    if (attributes != nullptr && !r.mesh.attributes.empty() && !c.moved.empty()) {
      std::vector<VertexAttribute> values;
      AttributeSums sums(values, c.moved.size(), field, *attributes);
      const bool same = values.size() == r.mesh.attributes.size() &&
                        std::equal(values.begin(), values.end(), r.mesh.attributes.begin(),
                                   [](const VertexAttribute& x, const VertexAttribute& y) {
                                     return x.name == y.name && x.components == y.components;
                                   });
      if (sums.any() && same) {
        parallel_blocks(c.moved.size(), 1024, [&](size_t begin, size_t end) {
          AttributeSums local(sums);  // its own running sums
          for (size_t i = begin; i < end; ++i) local.interpolate(i, field, r.mesh.positions[c.moved[i]]);
        });
        for (size_t k = 0; k < values.size(); ++k) {
          const size_t m = size_t(values[k].components);
          for (size_t i = 0; i < c.moved.size(); ++i)
            std::copy_n(values[k].values.begin() + ptrdiff_t(i * m), m,
                        r.mesh.attributes[k].values.begin() + ptrdiff_t(size_t(c.moved[i]) * m));
        }
      }
    }
    r.stats.edges_collapsed = c.collapsed;
  }
  tracker.check();
  if (o.surface_smoothing.iterations > 0) {
    tracker.stage("smoothing the surface", 1.0, 1.0);
    TaubinOptions t = o.surface_smoothing;
    t.threads = o.threads;
    taubin_smooth(r.mesh, t);
    r.stats.smoothing_iterations = t.iterations;
  }
  r.stats.vertices = r.mesh.positions.size();
  r.stats.triangles = r.mesh.triangles.size();
  r.stats.seconds_finishing = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

}  // namespace particlemesh::detail
