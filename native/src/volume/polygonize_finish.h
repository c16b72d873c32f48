// Internal: what polygonize does to its mesh after marching cubes, on request: drop the small
// pieces, then smooth (Taubin).
#pragma once

#include "particlemesh/core/config.h"

#include <algorithm>
#include <cmath>
#include <vector>

#include "core/progress_tracker.h"
#include "volume/field_impl.h"
#include "particlemesh/volume/polygonize.h"

namespace PM_NAMESPACE::detail {

/// Check min_component_volume, min_component_particles and surface_smoothing.
/// @throws Error(InvalidArgument) naming the option.
void validate_finishing(const PolygonizeOptions& options);

/// Apply the finishing options to r.mesh and fill their statistics. The particle spacing for
/// min_component_particles is the field's when it estimated one, else it is estimated from
/// `positions` (the input particles; the field's centres when null). The mesh's attributes,
/// interpolated while its vertices were placed (AttributeSums), go with their vertices:
/// dropped pieces take theirs with them; a vertex that collapsed edges merge gets them from
/// `attributes` (the particles', those the mesh's were interpolated from; may be null: then
/// the mean of the merged vertices' values) at its new place, as polygonize_attributes would.
void finish_polygonized(PolygonizeResult& r, const PolygonizeOptions& options, const ParticleField& field,
                        const Vec3* positions, size_t n, ProgressTracker& tracker,
                        const std::vector<VertexAttribute>* attributes = nullptr);

/// The particles' attributes interpolated at the vertices of `mesh`: each vertex x gets, for
/// each attribute, the particles' values weighted by their normalised kernel weights at x:
/// a(x) = sum_i w_i a_i / sum_i w_i with w_i = |strength_i| g(s_i(x)), s_i the particle's
/// scaled squared distance (its sphere's, or its ellipsoid's with anisotropic kernels): the
/// same weights that sum to F(x) = T there, so a particle counts in proportion to its share
/// of the surface at x (Shepard interpolation with the field's kernel). Summed in the field's
/// fixed particle order (for_each_contributor): the values do not depend on the thread
/// count, and the tiles of a cloud get the whole cloud's values bit for bit. A vertex no
/// kernel reaches (none on a polygonized surface) gets 0.
///
/// The constructor checks `attributes` against the field's particles and makes `out` (zeros,
/// one value per vertex and component: a mesh's attributes, or polygonize_attributes' values); each thread then works on
/// a copy of its own and calls interpolate() for each vertex it places.
class AttributeSums {
 public:
  /// @throws Error(InvalidInput) an attribute whose values do not match the particles.
  AttributeSums(std::vector<VertexAttribute>& out, size_t vertices, const ParticleField& field,
                const std::vector<VertexAttribute>& attributes);
  /// Whether there is any channel to interpolate.
  bool any() const { return channels_ > 0; }
  /// Vertex v at x: its values from the contributors at x that `from` gives, in the field's
  /// order (a ParticleField, or an EdgeNeighbours gathered for the vertex's edge: the same
  /// contributors).
  template <class Contributors>
  void interpolate(size_t v, const Contributors& from, const Vec3& x) {
    // One attribute of up to four components (a velocity, a colour): the same sums in
    // locals, with the kernel known at compile time (the bits are the general loop's).
    if (attributes_.size() == 1 && attributes_[0].components <= 4) {
      dispatch_kernel(kernel_, [&]<Kernel K>() {
        switch (attributes_[0].components) {
          case 1: interpolate_one<K, 1>(v, from, x); break;
          case 2: interpolate_one<K, 2>(v, from, x); break;
          case 3: interpolate_one<K, 3>(v, from, x); break;
          default: interpolate_one<K, 4>(v, from, x); break;
        }
      });
      return;
    }
    std::fill(sum_.begin(), sum_.end(), 0.0);
    total_ = 0;
    from.for_each_contributor(x, [&](size_t i, double s) { add(i, s); });
    store(v);
  }

 private:
  /// Particle i (input order) at scaled squared distance s (as for_each_contributor gives).
  void add(size_t i, double s) {
    const double w = std::abs(field_.strength(i)) * kernel_value(kernel_, s);
    if (!(w > 0)) return;
    total_ += w;
    size_t c = 0;
    for (const VertexAttribute& a : attributes_)
      for (int k = 0; k < a.components; ++k) sum_[c++] += w * double(a.values[i * size_t(a.components) + size_t(k)]);
  }
  template <Kernel K, int C, class Contributors>
  void interpolate_one(size_t v, const Contributors& from, const Vec3& x) {
    const float* values = attributes_[0].values.data();
    double total = 0, sum[C] = {};
    from.for_each_contributor(x, [&](size_t i, double s) {
      const double w = std::abs(field_.strength(i)) * kernel_value_t<K>(s);
      if (!(w > 0)) return;
      total += w;
      for (int k = 0; k < C; ++k) sum[k] += w * double(values[i * C + size_t(k)]);
    });
    float* out = out_[0].values.data() + v * C;
    for (int k = 0; k < C; ++k) out[k] = total > 0 ? float(sum[k] / total) : 0.0f;
  }
  /// Vertex v's values into out.
  void store(size_t v) const {
    size_t c = 0;
    for (VertexAttribute& a : out_)
      for (int k = 0; k < a.components; ++k, ++c)
        a.values[v * size_t(a.components) + size_t(k)] = total_ > 0 ? float(sum_[c] / total_) : 0.0f;
  }

  std::vector<VertexAttribute>& out_;
  const ParticleField& field_;
  const std::vector<VertexAttribute>& attributes_;
  Kernel kernel_;
  size_t channels_ = 0;
  std::vector<double> sum_;
  double total_ = 0;
};

/// The field polygonize(cloud, options) samples, with the options' kernel, radius, threshold,
/// per-particle radii and strengths, anisotropy and domain (polygonize_attributes builds the
/// very same one, so that its values are polygonize's own).
inline ParticleField polygonize_field_of(const PointCloud& cloud, const PolygonizeOptions& options,
                                         ProgressTracker& tracker, double begin, double end) {
  FieldParams params;
  params.kernel = options.kernel;
  params.radius = options.radius;
  params.threshold = options.threshold;
  params.radii = options.radii;
  params.strengths = options.strengths;
  params.anisotropy = options.anisotropy;
  tracker.stage("estimating spacing", begin, end);
  return FieldBuilder::build(cloud.positions.data(), cloud.positions.size(), params, tracker, begin, end,
                             {options.domain_min, options.domain_max_radius, options.domain_grid_radius});
}

}  // namespace particlemesh::detail
