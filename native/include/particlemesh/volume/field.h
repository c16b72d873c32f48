// The implicit surface of volume particles (thesis chapter 5, section 5.1.1, equation 5.1):
//
//     F(x) = sum_i  w_i * g(|x - p_i|^2 / R_i^2),      surface:  F(x) = T,  inside: F(x) >= T
//
// with particle centres p_i, per-particle radius R_i (the support: particle i contributes
// nothing at distance >= R_i), strength w_i (default 1) and a kernel g (kernel.h). The
// threshold T must be positive, so the surface lies inside the union of the supports of the
// positive-strength particles and is closed.
//
// ParticleField holds the particles with every parameter resolved (defaults filled in) and a
// uniform grid of cell max_i R_i over them, so that one evaluation of F or its gradient
// touches only the particles in the few cells around x (about 30 particles at the default
// radius on evenly spaced input), independent of N. Radii that differ by a large factor make
// the cells, and so every evaluation, correspondingly larger.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "particlemesh/core/export.h"
#include "particlemesh/core/progress.h"
#include "particlemesh/core/vec3.h"
#include "particlemesh/mesh/point_cloud.h"
#include "particlemesh/spatial/neighbor_grid.h"
#include "particlemesh/volume/kernel.h"

namespace particlemesh {

namespace detail {
struct FieldBuilder;
}

/// Default radius: R = kDefaultRadiusFactor x the median particle spacing (the median
/// nearest-neighbour distance, estimate_spacing): every point of an evenly packed volume
/// then lies in the support of about 30 particles, so the summed field is smooth.
inline constexpr double kDefaultRadiusFactor = 2.0;

/// Default threshold: T = kDefaultThresholdFraction x the field deep inside an evenly packed
/// volume at the default radius, lattice_field(kernel, kDefaultRadiusFactor, 1), x the median
/// strength: a constant per kernel (3.33 Wyvill, 3.94 Poly4, 2.58 Poly6, 1.23 Blinn), so it
/// needs no spacing estimate. With the default radius, the surface of a packed block then lies
/// about half a spacing outside its outermost particles: the boundary of the volume the
/// particles stand for (for a flat face of a continuum, exactly there); a larger radius
/// fattens the surface. Isolated particles (F = 1 at their centre) fall below T and vanish,
/// like splashes in SPH surface reconstruction; give a threshold below 1 to keep every
/// particle as a blob.
inline constexpr double kDefaultThresholdFraction = 0.5;
/// The largest strength magnitude accepted: sums and gradients of the field stay finite.
inline constexpr double kMaxStrength = 1e100;

/// The field at a particle of an infinite simple cubic lattice of unit-strength particles
/// with the given spacing and radius: the sum of g(|q|^2 / R^2) over the lattice points q
/// (the particle itself included) with |q| < R. It is the level of F deep inside an evenly
/// packed volume, and the unit in which the default threshold is measured (SPH iso levels
/// given as a fraction of the rest density map to  T = fraction x lattice_field).
/// @throws Error(InvalidArgument) unless radius and spacing are positive and finite and
///         radius / spacing <= 1000.
PM_EXPORT double lattice_field(Kernel kernel, double radius, double spacing);

/// The field's parameters. Zero radius / threshold ask for the defaults above; the default
/// radius needs the particle spacing and therefore at least two distinct particles.
struct FieldParams {
  Kernel kernel = Kernel::Wyvill;
  /// R for every particle, world units (not relative). 0 = kDefaultRadiusFactor x the median
  /// spacing. Ignored when `radii` is given.
  double radius = 0;
  /// T > 0, in the units of F (sums of kernel values times strengths). 0 = the default
  /// (kDefaultThresholdFraction x median strength x lattice_field(kernel, 2, 1)).
  double threshold = 0;
  /// Empty, or one radius R_i > 0 per particle (world units).
  std::vector<double> radii;
  /// Empty (every strength 1), or one finite strength w_i per particle, |w_i| <= kMaxStrength
  /// (1e100). Negative strengths subtract; particles of zero strength contribute nothing.
  std::vector<double> strengths;
};

/// The summed field of a set of particles, with its threshold, ready to evaluate.
/// Evaluations are const and safe to run from many threads at once.
class PM_EXPORT ParticleField {
 public:
  ParticleField() = default;

  /// Copy the particles and resolve the parameters: estimate the spacing when the default
  /// radius is asked for (threads: 0 = all cores; the result does not depend on it), check
  /// every value. Cost: O(N) expected (a sort of the particles into grid cells, and the
  /// spacing estimate when needed).
  /// @throws Error(InvalidInput) no particle, a non-finite coordinate, or the default radius
  ///         asked for with fewer than two distinct particles;
  ///         Error(InvalidArgument) a radius, strength or threshold out of range, naming the
  ///         index for per-particle values (e.g. "radii[12] is -1 (must be > 0)"), or a
  ///         radii/strengths array whose size is not the particle count;
  ///         Error(LimitExceeded) particles spread over more than ~2 million radii along an
  ///         axis; Error(Cancelled) from the progress callback.
  ParticleField(std::vector<Vec3> positions, const FieldParams& params, int threads = 0,
                const ProgressCallback& progress = {});
  /// The same from a point cloud (its normals and attributes are ignored).
  ParticleField(const PointCloud& cloud, const FieldParams& params, int threads = 0,
                const ProgressCallback& progress = {});

  /// The resolved parameters: radius and threshold are the values in use (never 0);
  /// `radius` is the common radius, or the median of `radii` when those are given.
  const FieldParams& params() const { return params_; }
  Kernel kernel() const { return params_.kernel; }
  double threshold() const { return params_.threshold; }
  /// The median particle spacing when the default radius needed it, else 0.
  double spacing() const { return spacing_; }
  bool radius_defaulted() const { return radius_defaulted_; }
  bool threshold_defaulted() const { return threshold_defaulted_; }

  size_t size() const { return grid_.point_count(); }
  /// Centre of particle i (input order). The particles are kept once, in grid order.
  const Vec3& position(size_t i) const { return grid_.sorted_point(sorted_index_[i]); }
  double radius(size_t i) const { return params_.radii.empty() ? params_.radius : params_.radii[i]; }
  double strength(size_t i) const { return params_.strengths.empty() ? 1.0 : params_.strengths[i]; }
  double max_radius() const { return max_radius_; }
  /// Smallest axis-aligned box holding every particle's support (centre +- R_i).
  Vec3 support_min() const { return support_lo_; }
  Vec3 support_max() const { return support_hi_; }
  /// The corner the particle grid (cells of max_radius(), from lower_corner() - max_radius())
  /// is anchored to: the particles' smallest coordinates, or the whole cloud's when these
  /// particles are a tile of it (PolygonizeOptions::domain_min).
  Vec3 lower_corner() const { return lower_; }

  /// F(x).
  double value(const Vec3& x) const;
  /// grad F(x) = sum_i w_i 2 g'(s_i) (x - p_i) / R_i^2.
  Vec3 gradient(const Vec3& x) const;
  /// F(x), and grad F(x) into *gradient, in one pass.
  double value_and_gradient(const Vec3& x, Vec3* gradient) const;
  /// value(x) >= threshold().
  bool inside(const Vec3& x) const { return value(x) >= params_.threshold; }

  /// Call f(i, s) for every particle i whose support contains x (s = |x - p_i|^2 / R_i^2 < 1),
  /// in a fixed order (by grid cell, then by index) that does not depend on threads.
  template <class F>
  void for_each_contributor(const Vec3& x, F&& f) const {
    if (size() == 0) return;
    grid_.for_each_within(x, max_radius_, [&](uint32_t sorted, double d2) {
      const double inv_r2 = uniform_ ? inv_r2_ : sorted_inv_r2_[sorted];
      const double s = d2 * inv_r2;
      if (s < 1.0) f(size_t(grid_.original_index(sorted)), s);
    });
  }

  /// The grid over the particles (cell = max_radius()), for callers with their own traversal.
  const NeighborGrid& grid() const { return grid_; }
  /// Per sorted grid index: 1 / R^2 and strength (empty when uniform / all 1).
  const std::vector<double>& sorted_inverse_squared_radii() const { return sorted_inv_r2_; }
  const std::vector<double>& sorted_strengths() const { return sorted_strength_; }
  bool uniform_radius() const { return uniform_; }

 private:
  friend struct detail::FieldBuilder;
  FieldParams params_;
  NeighborGrid grid_;
  std::vector<uint32_t> sorted_index_;  // input index -> grid (sorted) index
  std::vector<double> sorted_inv_r2_;
  std::vector<double> sorted_strength_;
  bool uniform_ = true;
  double inv_r2_ = 0;
  double max_radius_ = 0;
  double spacing_ = 0;
  bool radius_defaulted_ = false;
  bool threshold_defaulted_ = false;
  Vec3 support_lo_, support_hi_;
  Vec3 lower_;
};

}  // namespace particlemesh
