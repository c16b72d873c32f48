// Internal: the anisotropic kernels computed inside a caller's progress tracker and arena.
#pragma once

#include "particlemesh/core/config.h"

#include <vector>

#include "core/progress_tracker.h"
#include "particlemesh/volume/anisotropy.h"

namespace PM_NAMESPACE::detail {

/// Kernels of particles with finite positions; radius(i) = radii ? radii[i] : radius, all > 0.
/// The neighbour search's cells follow `cell_radius` (the field grid's: the largest radius, or
/// particle_grid_radius); particles of a larger radius search over the cells of their reach.
/// Runs in the caller's TBB arena; reports progress in [begin, end).
std::vector<KernelEllipsoid> anisotropic_kernels_impl(const Vec3* positions, size_t n, double radius,
                                                      const double* radii, double cell_radius,
                                                      const AnisotropyOptions& options, ProgressTracker& tracker,
                                                      double begin, double end);

/// The kernel of a particle at p (radius R, neighbourhood radius r) from the weighted sums over
/// its `count` neighbours within r (itself included), d = p_j - p, w = 1 - (|d| / r)^3:
/// W = sum w, S = sum w d, Q = sum w d d^T as {xx, yy, zz, xy, xz, yz}, with d measured in
/// units of `unit` (world length units per unit).
KernelEllipsoid kernel_from_sums(const Vec3& p, double R, double r, double W, const Vec3& S,
                                 const std::array<double, 6>& Q, uint32_t count, const AnisotropyOptions& options,
                                 double unit = 1.0);

/// s = d^T M d for M stored as {xx, yy, zz, xy, xz, yz}.
inline double metric_norm2(const double* m, const Vec3& d) {
  return m[0] * d.x * d.x + m[1] * d.y * d.y + m[2] * d.z * d.z +
         2.0 * (m[3] * d.x * d.y + m[4] * d.x * d.z + m[5] * d.y * d.z);
}

/// M d.
inline Vec3 metric_apply(const double* m, const Vec3& d) {
  return {m[0] * d.x + m[3] * d.y + m[4] * d.z, m[3] * d.x + m[1] * d.y + m[5] * d.z,
          m[4] * d.x + m[5] * d.y + m[2] * d.z};
}

}  // namespace particlemesh::detail
