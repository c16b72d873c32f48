#include "particlemesh/volume/anisotropy.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>

#include <Eigen/Eigenvalues>

#include "core/parallel.h"
#include "core/progress_tracker.h"
#include "particlemesh/core/error.h"
#include "particlemesh/spatial/neighbor_grid.h"
#include "volume/anisotropy_impl.h"

namespace particlemesh {

namespace {

std::string num(double v) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.17g", v);
  return buf;
}

std::array<double, 6> sphere_metric(double r) {
  const double k = 1.0 / (r * r);
  return {k, k, k, 0.0, 0.0, 0.0};
}

}  // namespace

namespace detail {

KernelEllipsoid kernel_from_sums(const Vec3& p, double R, double r, double W, const Vec3& S,
                                 const std::array<double, 6>& Q, uint32_t count, const AnisotropyOptions& o) {
  KernelEllipsoid k;
  // W >= 1: the particle itself is among its neighbours, at distance 0.
  const Vec3 m = S / W;
  k.centre = p + m * o.smoothing;
  k.metric = sphere_metric(R);
  k.neighbors = count - 1;
  k.mean_offset = norm(m) / r;
  if (count < uint32_t(o.min_neighbors) + 1) return k;
  Eigen::Matrix3d C;
  C(0, 0) = Q[0] / W - m.x * m.x;
  C(1, 1) = Q[1] / W - m.y * m.y;
  C(2, 2) = Q[2] / W - m.z * m.z;
  C(0, 1) = C(1, 0) = Q[3] / W - m.x * m.y;
  C(0, 2) = C(2, 0) = Q[4] / W - m.x * m.z;
  C(1, 2) = C(2, 1) = Q[5] / W - m.y * m.z;
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig;
  eig.computeDirect(C);  // closed form (trigonometric): fast and deterministic
  const Eigen::Vector3d lam = eig.eigenvalues();  // increasing
  const double s1 = lam(2);
  // All neighbours on one spot (duplicates), or a spread below rounding: keep the sphere.
  if (!(s1 > 1e-12 * r * r) || !std::isfinite(s1)) return k;
  double sig[3];
  for (int a = 0; a < 3; ++a) sig[a] = std::max(lam(a), s1 / o.max_stretch);
  const double scale = R / std::cbrt(sig[0] * sig[1] * sig[2]);
  std::array<double, 6> mm{};
  const Eigen::Matrix3d V = eig.eigenvectors();
  for (int a = 0; a < 3; ++a) {
    const double ax = sig[a] * scale;  // semi-axis along eigenvector a
    const double inv2 = 1.0 / (ax * ax);
    const double vx = V(0, a), vy = V(1, a), vz = V(2, a);
    mm[0] += inv2 * vx * vx;
    mm[1] += inv2 * vy * vy;
    mm[2] += inv2 * vz * vz;
    mm[3] += inv2 * vx * vy;
    mm[4] += inv2 * vx * vz;
    mm[5] += inv2 * vy * vz;
  }
  k.metric = mm;
  k.anisotropic = true;
  return k;
}

}  // namespace detail

void validate_anisotropy(const AnisotropyOptions& o) {
  if (!(o.neighbor_radius > 0 && o.neighbor_radius <= 10))
    throw Error(Status::InvalidArgument, "anisotropy neighbor_radius is " + num(o.neighbor_radius) +
                                             " (must be in (0, 10], a multiple of the particle radius)");
  if (!(o.max_stretch >= 1 && o.max_stretch <= 100))
    throw Error(Status::InvalidArgument,
                "anisotropy max_stretch is " + num(o.max_stretch) + " (must be in [1, 100])");
  if (o.min_neighbors < 0 || o.min_neighbors > 100000)
    throw Error(Status::InvalidArgument, "anisotropy min_neighbors is " + std::to_string(o.min_neighbors) +
                                             " (must be in [0, 100000])");
  if (!(o.smoothing >= 0 && o.smoothing <= 1))
    throw Error(Status::InvalidArgument, "anisotropy smoothing is " + num(o.smoothing) + " (must be in [0, 1])");
}

Vec3 ellipsoid_half_extent(const std::array<double, 6>& m) {
  // Diagonal of M^-1 from the cofactors: (M^-1)_aa = cofactor_aa / det M.
  const double xx = m[0], yy = m[1], zz = m[2], xy = m[3], xz = m[4], yz = m[5];
  const double c0 = yy * zz - yz * yz, c1 = xx * zz - xz * xz, c2 = xx * yy - xy * xy;
  const double det = xx * c0 - xy * (xy * zz - yz * xz) + xz * (xy * yz - yy * xz);
  return {std::sqrt(c0 / det), std::sqrt(c1 / det), std::sqrt(c2 / det)};
}

namespace detail {

std::vector<KernelEllipsoid> anisotropic_kernels_impl(const Vec3* positions, size_t n, double radius,
                                                      const double* radii, const AnisotropyOptions& o,
                                                      ProgressTracker& tracker, double begin, double end) {
  validate_anisotropy(o);
  std::vector<KernelEllipsoid> out(n);
  if (n == 0) return out;
  double rmax = radius;
  if (radii) rmax = *std::max_element(radii, radii + n);
  const double reach = o.neighbor_radius * rmax;
  // Cells of half the query radius: a query scans 5^3 cells, about a quarter of whose volume
  // is inside the ball (cells of the full radius scan 27 cells, a seventh inside).
  const NeighborGrid grid(positions, n, 0.5 * reach);
  const auto& P = grid.sorted_points();
  const size_t ncells = grid.cell_count();
  const int32_t K = int32_t(std::ceil(reach / grid.cell_size()));
  tracker.stage("anisotropic kernels", begin, end, ncells);
  // Cell by cell: the points of the (2K + 1)^3 cells around a cell are gathered once into a
  // contiguous buffer for all of its particles (no hash lookups per particle). The buffer
  // holds them in increasing sorted index, so each particle's sums run over its neighbours in
  // the order a per-particle query (for_each_within) would give: fixed, whatever the threads.
  detail::parallel_blocks(ncells, 16, [&](size_t cb, size_t ce) {
    if (tracker.cancelled()) return;
    struct NearCell {
      uint32_t begin, end;  // range in `near`
      Vec3 lo, hi;          // the box of the cell's points
    };
    std::vector<Vec3> near;
    std::vector<NearCell> cells;
    std::vector<Vec3> within;  // one particle's neighbours (offsets), in order
    for (size_t c = cb; c < ce; ++c) {
      const NeighborGrid::CellCoord cc = grid.cell_coord(uint32_t(c));
      near.clear();
      cells.clear();
      grid.for_each_cell_in({cc[0] - K, cc[1] - K, cc[2] - K}, {cc[0] + K, cc[1] + K, cc[2] + K}, [&](uint32_t d) {
        NearCell nc{uint32_t(near.size()), uint32_t(near.size() + grid.cell_end(d) - grid.cell_begin(d)),
                    P[grid.cell_begin(d)], P[grid.cell_begin(d)]};
        for (uint32_t k = grid.cell_begin(d); k < grid.cell_end(d); ++k) {
          nc.lo = {std::min(nc.lo.x, P[k].x), std::min(nc.lo.y, P[k].y), std::min(nc.lo.z, P[k].z)};
          nc.hi = {std::max(nc.hi.x, P[k].x), std::max(nc.hi.y, P[k].y), std::max(nc.hi.z, P[k].z)};
        }
        cells.push_back(nc);
        near.insert(near.end(), P.begin() + grid.cell_begin(d), P.begin() + grid.cell_end(d));
      });
      for (uint32_t s = grid.cell_begin(uint32_t(c)); s < grid.cell_end(uint32_t(c)); ++s) {
        const uint32_t i = grid.original_index(s);
        const Vec3 p = P[s];
        const double R = radii ? radii[i] : radius;
        const double r = o.neighbor_radius * R, r2 = r * r;
        // Pass 1: the neighbours within r, skipping the cells the ball misses.
        within.clear();
        for (const NearCell& nc : cells) {
          double gap2 = 0;
          for (int a = 0; a < 3; ++a) {
            const double g = std::max({nc.lo[a] - p[a], p[a] - nc.hi[a], 0.0});
            gap2 += g * g;
          }
          if (gap2 > r2) continue;
          for (uint32_t k = nc.begin; k < nc.end; ++k) {
            const Vec3 d = near[k] - p;  // offsets from p: no cancellation far from the origin
            if (squared_norm(d) <= r2) within.push_back(d);
          }
        }
        // Pass 2: the weighted sums (a branch-free loop over the neighbours).
        const double inv_r = 1.0 / r;
        double W = 0, sx = 0, sy = 0, sz = 0, cxx = 0, cyy = 0, czz = 0, cxy = 0, cxz = 0, cyz = 0;
        for (const Vec3& d : within) {
          const double t = std::sqrt(squared_norm(d)) * inv_r;
          const double w = std::max(1.0 - t * t * t, 0.0);
          W += w;
          sx += w * d.x;
          sy += w * d.y;
          sz += w * d.z;
          cxx += w * d.x * d.x;
          cyy += w * d.y * d.y;
          czz += w * d.z * d.z;
          cxy += w * d.x * d.y;
          cxz += w * d.x * d.z;
          cyz += w * d.y * d.z;
        }
        out[i] = kernel_from_sums(p, R, r, W, {sx, sy, sz}, {cxx, cyy, czz, cxy, cxz, cyz}, uint32_t(within.size()), o);
      }
    }
    tracker.tick(ce - cb);
  });
  tracker.check();
  return out;
}

}  // namespace detail

std::vector<KernelEllipsoid> anisotropic_kernels(const std::vector<Vec3>& positions, double radius,
                                                 const std::vector<double>& radii, const AnisotropyOptions& options,
                                                 int threads, const ProgressCallback& progress) {
  validate_anisotropy(options);
  const size_t n = positions.size();
  for (size_t i = 0; i < n; ++i)
    if (!is_finite(positions[i]))
      throw Error(Status::InvalidInput, "positions[" + std::to_string(i) + "] is not finite");
  if (!radii.empty()) {
    if (radii.size() != n)
      throw Error(Status::InvalidArgument,
                  "radii has " + std::to_string(radii.size()) + " values for " + std::to_string(n) + " particles");
    for (size_t i = 0; i < n; ++i)
      if (!(radii[i] > 0) || !std::isfinite(radii[i]))
        throw Error(Status::InvalidArgument, "radii[" + std::to_string(i) + "] is " + num(radii[i]) +
                                                 " (must be a finite length > 0)");
  } else if (!(radius > 0) || !std::isfinite(radius)) {
    throw Error(Status::InvalidArgument, "radius is " + num(radius) + " (must be a finite length > 0)");
  }
  detail::ProgressTracker tracker(progress);
  auto r = detail::with_threads(threads, [&] {
    return detail::anisotropic_kernels_impl(positions.data(), n, radius, radii.empty() ? nullptr : radii.data(),
                                            options, tracker, 0.0, 1.0);
  });
  tracker.finish();
  return r;
}

}  // namespace particlemesh
