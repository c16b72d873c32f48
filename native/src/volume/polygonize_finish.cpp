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
#include "spatial/spacing_impl.h"

namespace PM_NAMESPACE::detail {

namespace {

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
  validate_taubin(o.surface_smoothing);
  // Dropping pieces and smoothing need the whole surface; a tile holds only part of it.
  if (o.cells && (o.min_component_volume > 0 || o.min_component_particles > 0 || o.surface_smoothing.iterations > 0))
    throw Error(Status::InvalidArgument,
                "a cell range (one tile of a cloud) cannot drop small pieces or smooth the mesh: "
                "min_component_volume, min_component_particles and taubin_iterations need the whole surface");
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
                        const Vec3* positions, size_t n, ProgressTracker& tracker) {
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
