// The implicit surface of volume particles (thesis chapter 5, section 5.1.1, equation 5.1):
//
//     F(x) = sum_i  w_i * g(|x - p_i|^2 / R_i^2),      surface:  F(x) = T,  inside: F(x) >= T
//
// with particle centres p_i, per-particle radius R_i (the support: particle i contributes
// nothing at distance >= R_i), strength w_i (default 1) and a kernel g (kernel.h). The
// threshold T must be positive, so the surface lies inside the union of the supports of the
// positive-strength particles and is closed.
//
// With anisotropic kernels (FieldParams::anisotropy, anisotropy.h) the sphere becomes an
// ellipsoid of the same volume around a smoothed centre c_i:
//
//     F(x) = sum_i  w_i * g((x - c_i)^T M_i (x - c_i))
//
// ParticleField holds the particles with every parameter resolved (defaults filled in) and a
// uniform grid over the kernel centres of cell the largest reach of a kernel (max_i R_i, or
// the longest semi-axis of any ellipsoid), so that one evaluation of F or its gradient
// touches only the particles in the few cells around x (about 30 particles at the default
// radius on evenly spaced input), independent of N. Where a few per-particle radii are far
// larger than the rest (particle_grid_radius), the cells are sized by the rest and those few
// are kept apart, visited by every evaluation; radii spread more evenly make the cells, and
// so every evaluation, larger.
#pragma once

#include "particlemesh/core/config.h"

#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <type_traits>
#include <vector>

#include "particlemesh/core/export.h"
#include "particlemesh/core/progress.h"
#include "particlemesh/core/vec3.h"
#include "particlemesh/mesh/point_cloud.h"
#include "particlemesh/spatial/neighbor_grid.h"
#include "particlemesh/volume/anisotropy.h"
#include "particlemesh/volume/kernel.h"

namespace PM_NAMESPACE {

namespace detail {
struct FieldBuilder;
}

/// Default radius: R = kDefaultRadiusFactor spacings of a simple cubic lattice as densely
/// packed as the particles: every point of an evenly packed volume then lies in the support of
/// about 30 particles, so the summed field is smooth. The spacing is the median
/// nearest-neighbour distance (estimate_spacing) for a lattice; particles in motion (an SPH
/// frame) sit closer to their nearest neighbour than their packing says (a median of 0.036
/// against a rest spacing of 0.05), and R = 2 x that leaves most of them outside the surface:
/// R is then taken larger, from the field at the particles (FieldParams::radius).
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
/// The largest strength magnitude accepted. The polygonizer samples the field in single
/// precision (FLT_MAX ~3.4e38): a strength beyond it became an infinite sample and NaN
/// vertices (found by fuzzing), so the limit leaves room for the sums of many particles.
inline constexpr double kMaxStrength = 1e30;

/// The field at a particle of an infinite simple cubic lattice of unit-strength particles
/// with the given spacing and radius: the sum of g(|q|^2 / R^2) over the lattice points q
/// (the particle itself included) with |q| < R. It is the level of F deep inside an evenly
/// packed volume, and the unit in which the default threshold is measured (SPH iso levels
/// given as a fraction of the rest density map to  T = fraction x lattice_field).
/// @throws Error(InvalidArgument) unless radius and spacing are positive and finite and
///         radius / spacing <= 1000.
PM_EXPORT double lattice_field(Kernel kernel, double radius, double spacing);

/// The largest radius / spacing ratio the anisotropic threshold calibration assumes.
inline constexpr double kMaxCalibrationRatio = 8.0;

/// The field on the face of a half-infinite simple cubic lattice of unit-strength particles
/// (spacing 1, the particles at integer points with z <= 0), on the plane z = 1/2 half a
/// spacing outside its outer layer, averaged over that plane; kernels of the given radius (in
/// spacings), made anisotropic as `anisotropy` says when it is enabled (each layer's kernels
/// from the same neighbour PCA as anisotropic_kernels, on the lattice itself). A threshold of
/// this value puts a flat face of such packed particles where the volume they stand for ends.
/// Spherical kernels: about half of lattice_field (0.486 of it for Wyvill at radius 2).
/// Cost: O(layers x (neighbor_radius x radius)^3), microseconds at the defaults.
/// @throws Error(InvalidArgument) a radius outside (0, kMaxCalibrationRatio], bad anisotropy
///         options or kernel.
PM_EXPORT double lattice_face_field(Kernel kernel, double radius, const AnisotropyOptions& anisotropy = {});

class ParticleField;

/// The radius the particle grid's cells are sized by, for per-particle radii (n values > 0;
/// spheres or ellipsoids): the particles with a larger radius are kept apart from the cells,
/// in a list every evaluation visits whole. Cells as wide as the largest radius hold, where
/// one particle is 20 times the rest, 8000 times the particles an evaluation needs
/// (polygonize 100 times slower); the list costs each evaluation a test per particle in it.
/// Chosen to minimise the particles one evaluation looks at: those apart, plus about
/// 216 (R_cell / R_median)^3 from the cells (27 cells of R_cell, the median radius taken as
/// two spacings); at most 4096 apart, and only where that costs at most a quarter of what
/// cells of the largest radius do. Otherwise the largest radius (none apart). Depends on the
/// set of radii only (not their order).
PM_EXPORT double particle_grid_radius(const double* radii, size_t n);

/// How the particles sit in their own field, from F at (up to 4096 of) their centres.
struct FieldAtParticles {
  /// The share of the particles at which F >= T: inside the surface. Deep inside packed
  /// particles F is about twice the default T; a low share means most particles end up
  /// outside the surface (a radius too small for how sparsely they are packed, or a
  /// threshold too high), and the surface shows only the densest of them.
  double enclosed_fraction = 0;
  /// Spherical kernels of one radius: the radius that is kDefaultRadiusFactor spacings of a
  /// simple cubic lattice as densely packed as these particles. The packing is read from the
  /// field at the centres of the bulk particles (those whose neighbours' kernel-weighted mean
  /// lies within 0.1 R of them), or from the upper quartile of all when fewer than 8 of the
  /// sampled particles are in the bulk: that level is lattice_field of a ratio x = R /
  /// spacing, and the result is R x 2 / x. Equal to R for a lattice at 2 spacings; larger for
  /// irregular particles (an SPH frame's median nearest-neighbour distance is well below its
  /// rest spacing). 0 otherwise.
  double density_radius = 0;
};
PM_EXPORT FieldAtParticles field_at_particles(const ParticleField& field);

/// The field's parameters. Zero radius / threshold ask for the defaults above; the default
/// radius needs the particle spacing and therefore at least two distinct particles.
struct FieldParams {
  Kernel kernel = Kernel::Wyvill;
  /// R for every particle, world units (not relative). 0 = the default: kDefaultRadiusFactor
  /// x the median spacing; with spherical kernels, when that leaves more than a tenth of the
  /// particles outside the surface of the default threshold (field_at_particles; whatever
  /// threshold is given, so that the radius does not depend on it),
  /// FieldAtParticles::density_radius of that field instead, if larger by over 2 % (the field
  /// is then built again at it): up to 2x larger for irregularly packed particles (SPH frames
  /// in motion), unchanged for packed ones. Ignored when `radii` is given.
  double radius = 0;
  /// T > 0, in the units of F (sums of kernel values times strengths). 0 = the default:
  /// spherical kernels: kDefaultThresholdFraction x median strength x lattice_field(kernel,
  /// 2, 1). Anisotropic kernels: calibrated on the particles themselves so that a flat face of
  /// packed particles lies half a spacing outside its outermost ones, keeping the volume they
  /// stand for: the median of F at the bulk particles (those with neighbours all around) is
  /// taken as lattice_field(kernel, x, 1) of an effective radius / spacing ratio x, and T =
  /// median strength x lattice_face_field(kernel, x, anisotropy) (x = 2 when fewer than 32
  /// particles are in the bulk: a sheet, a stream, a spray).
  double threshold = 0;
  /// Empty, or one radius R_i > 0 per particle (world units).
  std::vector<double> radii;
  /// Empty (every strength 1), or one finite strength w_i per particle, |w_i| <= kMaxStrength
  /// (1e30). Negative strengths subtract; particles of zero strength contribute nothing.
  std::vector<double> strengths;
  /// Anisotropic kernels (anisotropy.h; off by default): each particle's kernel becomes an
  /// ellipsoid of the volume of its sphere, centred on its smoothed centre, and F sums
  /// w_i g((x - c_i)^T M_i (x - c_i)).
  AnisotropyOptions anisotropy;
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
  /// With anisotropic kernels and the default threshold: the radius / spacing ratio the
  /// threshold was calibrated for (see FieldParams::threshold). 0 otherwise.
  double calibration_ratio() const { return calibration_ratio_; }
  bool threshold_defaulted() const { return threshold_defaulted_; }

  size_t size() const { return grid_.point_count(); }
  /// Centre of particle i's kernel (input order): the particle's position, or its smoothed
  /// centre with anisotropic kernels. The centres are kept once, in grid order.
  const Vec3& position(size_t i) const { return grid_.sorted_point(sorted_index_[i]); }
  double radius(size_t i) const { return params_.radii.empty() ? params_.radius : params_.radii[i]; }
  double strength(size_t i) const { return params_.strengths.empty() ? 1.0 : params_.strengths[i]; }
  double max_radius() const { return max_radius_; }
  /// The farthest any kernel reaches from its centre: max_radius(), or with anisotropic
  /// kernels the longest semi-axis of any of them (at most max_stretch^(2/3) x max_radius()).
  double max_reach() const { return reach_; }
  /// The farthest the kernel of a particle in the grid's cells reaches: max_reach(), or with
  /// per-particle radii far apart less (the grid's cells are then as wide as their
  /// particle_grid_radius, and the particles of larger radius are kept apart: sorted indices
  /// from grid().apart_begin() on, visited by every evaluation). Spheres: the cells' size.
  double cell_reach() const { return cell_reach_; }

  /// Anisotropic kernels in use (params().anisotropy.enabled).
  bool anisotropic() const { return params_.anisotropy.enabled; }
  /// With anisotropic kernels: how many particles got an ellipsoid (the others, with fewer
  /// than min_neighbors neighbours, kept their sphere). 0 otherwise.
  size_t anisotropic_count() const { return anisotropic_count_; }
  /// The matrix M of particle i's kernel, {xx, yy, zz, xy, xz, yz}: I / R_i^2 for a sphere.
  std::array<double, 6> metric(size_t i) const;
  /// Smallest axis-aligned box holding every particle's support (centre +- R_i).
  Vec3 support_min() const { return support_lo_; }
  Vec3 support_max() const { return support_hi_; }
  /// The corner the particle grid (cells of grid().cell_size(), from lower_corner() minus one cell)
  /// is anchored to: the particles' smallest coordinates, or the whole cloud's when these
  /// particles are a tile of it (PolygonizeOptions::domain_min).
  Vec3 lower_corner() const { return lower_; }

  /// F(x).
  double value(const Vec3& x) const;
  /// grad F(x) = sum_i w_i 2 g'(s_i) M_i (x - c_i)  (M_i = I / R_i^2 for spheres).
  Vec3 gradient(const Vec3& x) const;
  /// F(x), and grad F(x) into *gradient, in one pass.
  double value_and_gradient(const Vec3& x, Vec3* gradient) const;
  /// value(x) >= threshold().
  bool inside(const Vec3& x) const { return value(x) >= params_.threshold; }

  /// Call f(i, s) for every particle i whose support contains x (s = |x - p_i|^2 / R_i^2 < 1,
  /// or (x - c_i)^T M_i (x - c_i) < 1 with anisotropic kernels), in a fixed order (by grid
  /// cell, then by index) that does not depend on threads.
  template <class F>
  void for_each_contributor(const Vec3& x, F&& f) const {
    if (size() == 0) return;
    if (!sorted_metric_.empty()) {
      for_each_ellipsoid_near(x, [&](uint32_t sorted, const Vec3& d) {
        const double* m = &sorted_metric_[6 * size_t(sorted)];
        const double s = m[0] * d.x * d.x + m[1] * d.y * d.y + m[2] * d.z * d.z +
                         2.0 * (m[3] * d.x * d.y + m[4] * d.x * d.z + m[5] * d.y * d.z);
        if (s < 1.0) f(size_t(grid_.original_index(sorted)), s);
      });
      return;
    }
    for_each_within(x, cell_reach_, [&](uint32_t sorted, double d2) {
      const double s = d2 * (uniform_ ? inv_r2_ : sorted_inv_r2_[sorted]);
      if (s < 1.0) f(size_t(grid_.original_index(sorted)), s);
    });
    for (uint32_t sorted = grid_.apart_begin(); sorted < grid_.point_count(); ++sorted) {
      const double s = squared_distance(grid_.sorted_point(sorted), x) * sorted_inv_r2_[sorted];
      if (s < 1.0) f(size_t(grid_.original_index(sorted)), s);
    }
  }

  /// As NeighborGrid::for_each_within on grid() (f(sorted index, squared distance) for every
  /// centre in the grid's cells within `radius` of p, in increasing sorted index; none of
  /// those kept apart), its cells found through for_each_cell_in.
  template <class F>
  void for_each_within(const Vec3& p, double radius, F&& f) const {
    const double r2 = radius * radius;
    const Vec3 r{radius, radius, radius};
    for_each_cell_in(grid_.coord_of(p - r), grid_.coord_of(p + r), [&](uint32_t c) {
      for (uint32_t s = grid_.cell_begin(c); s < grid_.cell_end(c); ++s) {
        const double d2 = squared_distance(grid_.sorted_point(s), p);
        if (d2 <= r2) f(s, d2);
      }
    });
  }

  /// With anisotropic kernels: f(sorted index, x - c) for every particle whose ellipsoid's
  /// bounding box contains x, in grid order (those kept apart last). The grid's cells are as
  /// wide as the largest radius (of those in cells); the cells within the longest such
  /// kernel's reach of x are looked up in a dense table
  /// when the occupied cells' box is small enough (else through the grid's hash), and a cell
  /// whose kernels' boxes all miss x is skipped whole.
  template <class F>
  void for_each_ellipsoid_near(const Vec3& x, F&& f) const {
    const Vec3 r{cell_reach_, cell_reach_, cell_reach_};
    auto visit = [&](uint32_t c) {
      const float* b = &cell_support_[6 * size_t(c)];
      if (x.x < b[0] || x.y < b[1] || x.z < b[2] || x.x > b[3] || x.y > b[4] || x.z > b[5]) return;
      for (uint32_t s = grid_.cell_begin(c); s < grid_.cell_end(c); ++s) {
        const Vec3 d = x - grid_.sorted_point(s);
        const float* e = &sorted_extent_[3 * size_t(s)];
        if (std::abs(d.x) > e[0] || std::abs(d.y) > e[1] || std::abs(d.z) > e[2]) continue;
        f(s, d);
      }
    };
    for_each_cell_in(grid_.coord_of(x - r), grid_.coord_of(x + r), visit);
    for (uint32_t s = grid_.apart_begin(); s < grid_.point_count(); ++s) {  // kept apart: last
      const Vec3 d = x - grid_.sorted_point(s);
      const float* e = &sorted_extent_[3 * size_t(s)];
      if (std::abs(d.x) > e[0] || std::abs(d.y) > e[1] || std::abs(d.z) > e[2]) continue;
      f(s, d);
    }
  }

  /// f(c) for every occupied cell c of grid() whose coordinate lies in [lo, hi], in increasing
  /// cell order (as NeighborGrid::for_each_cell_in), looked up in a dense table of the
  /// occupied cells' box when that box is small enough (at most 8 times the occupied cells,
  /// plus a million), else through the grid's hash.
  template <class F>
  void for_each_cell_in(NeighborGrid::CellCoord lo, NeighborGrid::CellCoord hi, F&& f) const {
    if (dense_cells_.empty()) {
      grid_.for_each_cell_in(lo, hi, f);
      return;
    }
    for (int a = 0; a < 3; ++a) {
      lo[size_t(a)] = std::max(lo[size_t(a)], dense_lo_[size_t(a)]);
      hi[size_t(a)] = std::min(hi[size_t(a)], dense_lo_[size_t(a)] + dense_size_[size_t(a)] - 1);
    }
    for (int32_t cx = lo[0]; cx <= hi[0]; ++cx)
      for (int32_t cy = lo[1]; cy <= hi[1]; ++cy) {
        const uint32_t* row = &dense_cells_[(size_t(cx - dense_lo_[0]) * size_t(dense_size_[1]) +
                                             size_t(cy - dense_lo_[1])) * size_t(dense_size_[2])];
        for (int32_t cz = lo[2]; cz <= hi[2]; ++cz) {
          const uint32_t c = row[cz - dense_lo_[2]];
          if (c != NeighborGrid::kNoCell) f(c);
        }
      }
  }

  /// The same cells as for_each_cell_in(lo, hi, f), in the same order, as runs: f(c0, c1) for
  /// the occupied cells c0, c0 + 1, ..., c1 - 1 of one (x, y) column of the box (the cells of
  /// a column are consecutive in cell order, and so are their particles: the sorted indices
  /// [grid().cell_begin(c0), grid().cell_begin(c1))). A column with none is skipped; without
  /// the dense table each cell is a run of its own.
  template <class F>
  void for_each_column_in(NeighborGrid::CellCoord lo, NeighborGrid::CellCoord hi, F&& f) const {
    if (dense_cells_.empty()) {
      grid_.for_each_cell_in(lo, hi, [&](uint32_t c) { f(c, c + 1); });
      return;
    }
    for (int a = 0; a < 3; ++a) {
      lo[size_t(a)] = std::max(lo[size_t(a)], dense_lo_[size_t(a)]);
      hi[size_t(a)] = std::min(hi[size_t(a)], dense_lo_[size_t(a)] + dense_size_[size_t(a)] - 1);
      if (lo[size_t(a)] > hi[size_t(a)]) return;
    }
    const size_t sy = size_t(dense_size_[2]), sx = size_t(dense_size_[1]) * sy;
    const int32_t len = hi[2] - lo[2] + 1;
    const uint32_t* plane = &dense_cells_[size_t(lo[0] - dense_lo_[0]) * sx + size_t(lo[1] - dense_lo_[1]) * sy +
                                          size_t(lo[2] - dense_lo_[2])];
    // The rows' length as a compile-time constant for the usual boxes (a query's or an edge's
    // span 2 to 4 cells along z), so that the scan of a row is unrolled.
    auto rows = [&](auto row_len) {
      const uint32_t* p = plane;
      for (int32_t cx = lo[0]; cx <= hi[0]; ++cx, p += sx) {
        const uint32_t* row = p;
        for (int32_t cy = lo[1]; cy <= hi[1]; ++cy, row += sy) {
          // The occupied ones among the row's cells are consecutive: the first (kNoCell is
          // above every cell) and how many.
          uint32_t first = NeighborGrid::kNoCell, count = 0;
          for (int32_t k = 0; k < int32_t(row_len); ++k) {
            first = std::min(first, row[k]);
            count += row[k] != NeighborGrid::kNoCell;
          }
          if (count != 0) f(first, first + count);
        }
      }
    };
    switch (len) {
      case 2: rows(std::integral_constant<int32_t, 2>{}); break;
      case 3: rows(std::integral_constant<int32_t, 3>{}); break;
      case 4: rows(std::integral_constant<int32_t, 4>{}); break;
      default: rows(len);
    }
  }

  /// The grid over the kernel centres (cells of the largest radius of the particles in them:
  /// cell_reach() for spheres), for callers with their own traversal: they visit the particles
  /// of the cells within cell_reach() of where they look, then every particle from
  /// grid().apart_begin() on (none, unless radii are far apart).
  const NeighborGrid& grid() const { return grid_; }
  /// Per sorted grid index: 1 / R^2 and strength (empty when uniform / all 1).
  const std::vector<double>& sorted_inverse_squared_radii() const { return sorted_inv_r2_; }
  const std::vector<double>& sorted_strengths() const { return sorted_strength_; }
  bool uniform_radius() const { return uniform_; }
  /// With anisotropic kernels, per sorted grid index: the 6 entries of M (as metric()) and the
  /// half extents of the ellipsoid along x, y, z (rounded up to float). Empty otherwise.
  const std::vector<double>& sorted_metrics() const { return sorted_metric_; }
  const std::vector<float>& sorted_half_extents() const { return sorted_extent_; }
  /// With anisotropic kernels, per grid cell: the box holding its kernels' boxes, {lo x y z,
  /// hi x y z} (rounded outward to float). Empty otherwise.
  const std::vector<float>& cell_support_boxes() const { return cell_support_; }

 private:
  friend struct detail::FieldBuilder;
  FieldParams params_;
  NeighborGrid grid_;
  std::vector<uint32_t> sorted_index_;  // input index -> grid (sorted) index
  std::vector<double> sorted_inv_r2_;
  std::vector<double> sorted_strength_;
  std::vector<double> sorted_metric_;  // anisotropic: 6 per particle, grid order
  std::vector<float> sorted_extent_;   // anisotropic: 3 per particle, grid order
  std::vector<float> cell_support_;    // anisotropic: 6 per grid cell
  std::vector<uint32_t> dense_cells_;  // cell index per coordinate in the occupied cells' box (or empty)
  NeighborGrid::CellCoord dense_lo_{}, dense_size_{};
  size_t anisotropic_count_ = 0;
  bool uniform_ = true;
  double inv_r2_ = 0;
  double max_radius_ = 0;
  double reach_ = 0;
  double cell_reach_ = 0;
  double spacing_ = 0;
  double calibration_ratio_ = 0;
  bool radius_defaulted_ = false;
  bool threshold_defaulted_ = false;
  Vec3 support_lo_, support_hi_;
  Vec3 lower_;
};

}  // namespace particlemesh
