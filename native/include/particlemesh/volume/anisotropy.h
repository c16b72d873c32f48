// Anisotropic kernels for volume particles (Yu and Turk, "Reconstructing surfaces of
// particle-based fluids using anisotropic kernels", ACM Transactions on Graphics 32(1), 2013).
//
// With spherical kernels every particle near the surface is a bump, a sheet one particle thick
// falls apart into droplets, and flat faces come out dimpled. Yu and Turk give each particle
// an ellipsoid that follows where its neighbours are: stretched along a sheet or a flat face,
// squeezed across it, spherical inside the bulk and where neighbours are few. Per particle i:
//
// 1. Weighted PCA of its neighbours j within r_i = neighbor_radius x R_i (R_i: the particle's
//    radius), weights w_ij = 1 - (|p_j - p_i| / r_i)^3 (the particle itself included):
//    the weighted mean m_i = sum w_ij p_j / sum w_ij and covariance
//    C_i = sum w_ij (p_j - m_i)(p_j - m_i)^T / sum w_ij, with eigenvalues s1 >= s2 >= s3
//    and eigenvectors q1, q2, q3.
// 2. Clamping: s2, s3 are raised to at least s1 / k_r (k_r = max_stretch), so no kernel is
//    more than k_r times longer than it is thick. With fewer than N_eps = min_neighbors
//    neighbours the kernel stays the sphere of radius R_i (Yu and Turk's k_n I).
// 3. Volume kept: the ellipsoid's semi-axes are a_k = R_i s_k / cbrt(s1 s2 s3), so a1 a2 a3 =
//    R_i^3: every kernel has the volume, and the integral, of the sphere it replaces (where
//    Yu and Turk scale by k_s det(G), whose value depends on the simulation's units). The
//    field deep inside packed particles, and so the meaning of the threshold, is unchanged.
// 4. Smoothing of the kernel centres (one step of Laplacian smoothing, the diffusion step of
//    Yu and Turk): c_i = (1 - lambda) p_i + lambda m_i (lambda = smoothing). Off by default:
//    on volume particles it pulls a face's outer layer inward (m_i of a particle on a face
//    lies about a third of r_i inside), by about a spacing at Yu and Turk's lambda = 0.9, and
//    the surface then loses volume that no threshold gives back (a jittered block: 14 %),
//    while the stretched kernels already average the jitter of a flat face out.
//
// The kernel of particle i is then g(s) with s = (x - c_i)^T M_i (x - c_i), where
// M_i = sum_k q_k q_k^T / a_k^2 (a sphere: M_i = I / R_i^2); along a ray, s is still a
// quadratic in t, so the ray caster's per-interval polynomials keep their degree, and the
// support is the ellipsoid s < 1.
//
// Cost: one fixed-radius neighbour query per particle (about 270 neighbours inside packed
// particles at the defaults) and a 3 x 3 symmetric eigendecomposition (Eigen's closed form).
// Every sum runs over the neighbours in a fixed order, so the kernels do not depend on the
// thread count.
#pragma once

#include "particlemesh/core/config.h"

#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "particlemesh/core/export.h"
#include "particlemesh/core/progress.h"
#include "particlemesh/core/vec3.h"

namespace PM_NAMESPACE {

/// Yu and Turk's parameters (their values are the defaults, but for `smoothing`). Off unless
/// `enabled`. With them, FieldParams' default threshold is calibrated on the particles
/// (field.h).
struct AnisotropyOptions {
  bool enabled = false;
  /// PCA neighbourhood radius r_i as a multiple of the particle's radius R_i (Yu and Turk:
  /// twice the kernel's support). In (0, 10].
  double neighbor_radius = 2.0;
  /// k_r: the largest ratio of an ellipsoid's longest to shortest axis. In [1, 100]; 1 makes
  /// every kernel a sphere again (only the centres are smoothed).
  double max_stretch = 4.0;
  /// N_eps: particles with fewer neighbours than this within r_i keep a spherical kernel.
  /// In [0, 100000].
  int32_t min_neighbors = 25;
  /// lambda: how far each kernel centre moves toward its neighbours' weighted mean. In [0, 1];
  /// 0 (off) by default, where Yu and Turk use 0.9 (see 4. above).
  double smoothing = 0.0;
};

/// One particle's kernel: its centre and the symmetric matrix M of s = (x - c)^T M (x - c),
/// stored as {M_xx, M_yy, M_zz, M_xy, M_xz, M_yz}.
struct KernelEllipsoid {
  Vec3 centre;
  std::array<double, 6> metric{};
  bool anisotropic = false;  ///< false: the sphere of the particle's radius (too few neighbours)
  uint32_t neighbors = 0;    ///< other particles within r_i
  /// |m_i - p_i| / r_i: about 0 inside the bulk, 9/28 (0.32) on a flat face of a continuum.
  double mean_offset = 0;
};

/// @throws Error(InvalidArgument) naming the first option out of its range.
PM_EXPORT void validate_anisotropy(const AnisotropyOptions& options);

/// The anisotropic kernels of n particles with one radius (`radii` empty) or one radius per
/// particle, in input order (see the top of this file). threads: 0 = all cores; the result
/// does not depend on it.
/// @throws Error(InvalidInput) non-finite coordinates; Error(InvalidArgument) bad options,
///         radii or a radii array of the wrong size; Error(Cancelled) from the callback.
PM_EXPORT std::vector<KernelEllipsoid> anisotropic_kernels(const std::vector<Vec3>& positions, double radius,
                                                           const std::vector<double>& radii,
                                                           const AnisotropyOptions& options, int threads = 0,
                                                           const ProgressCallback& progress = {});

/// Half the extent of the ellipsoid s < 1 along each axis: sqrt of the diagonal of M^-1.
PM_EXPORT Vec3 ellipsoid_half_extent(const std::array<double, 6>& metric);

}  // namespace particlemesh
