#include "particlemesh/volume/anisotropy.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <string>

#include <Eigen/Eigenvalues>

#include "core/format_number.h"
#include "core/parallel.h"
#include "core/progress_tracker.h"
#include "particlemesh/core/error.h"
#include "particlemesh/spatial/neighbor_grid.h"
#include "particlemesh/volume/field.h"
#include "volume/anisotropy_impl.h"

namespace PM_NAMESPACE {

namespace {

std::string num(double v) { return detail::format_number(v, 17); }

typedef float Float4 __attribute__((vector_size(4 * sizeof(float))));
typedef int32_t Int4 __attribute__((vector_size(4 * sizeof(int32_t))));

inline Float4 sqrt4(Float4 v) {
#if defined(__SSE__)
  return __builtin_ia32_sqrtps(v);
#else
  for (int k = 0; k < 4; ++k) v[k] = std::sqrt(v[k]);  // correctly rounded either way
  return v;
#endif
}

// The PCA's weighted sums over a particle's neighbours, 4 points at a time: W = sum w,
// S = sum w d, Q = sum w d d^T with d = q - p and Yu and Turk's w = 1 - (|d| / r)^3 within r
// (0 beyond), and the count within r.
class WeightedSums {
 public:
  explicit WeightedSums(double r) : r2_(float(r * r)), inv_r_(float(1.0 / r)) {}

  /// The particle's position in the frame of the points added next.
  void at(const Vec3& p) {
    px_ = float(p.x);
    py_ = float(p.y);
    pz_ = float(p.z);
  }

  void add(const float* x, const float* y, const float* z) {
    Float4 dx, dy, dz;
    std::memcpy(&dx, x, sizeof dx);
    std::memcpy(&dy, y, sizeof dy);
    std::memcpy(&dz, z, sizeof dz);
    dx -= px_;
    dy -= py_;
    dz -= pz_;
    const Float4 d2 = dx * dx + dy * dy + dz * dz;
    const Int4 in = d2 <= r2_;
    const Float4 t = sqrt4(d2) * inv_r_;
    Float4 w = 1.0f - t * t * t;
    w = (Float4)((Int4)w & in & (w > 0.0f));
    count_ -= in;  // true is -1
    w_ += w;
    const Float4 wx = w * dx, wy = w * dy, wz = w * dz;
    sx_ += wx;
    sy_ += wy;
    sz_ += wz;
    xx_ += wx * dx;
    yy_ += wy * dy;
    zz_ += wz * dz;
    xy_ += wx * dy;
    xz_ += wx * dz;
    yz_ += wy * dz;
  }

  /// The sums (lanes added in order, in double) and the count.
  uint32_t total(double* W, double* S, double* Q) const {
    auto sum = [](const Float4& v) { return double(v[0]) + double(v[1]) + double(v[2]) + double(v[3]); };
    *W = sum(w_);
    S[0] = sum(sx_);
    S[1] = sum(sy_);
    S[2] = sum(sz_);
    const Float4* q[6] = {&xx_, &yy_, &zz_, &xy_, &xz_, &yz_};
    for (int k = 0; k < 6; ++k) Q[k] = sum(*q[k]);
    return uint32_t(count_[0] + count_[1] + count_[2] + count_[3]);
  }

 private:
  float px_ = 0, py_ = 0, pz_ = 0, r2_, inv_r_;
  Float4 w_{}, sx_{}, sy_{}, sz_{}, xx_{}, yy_{}, zz_{}, xy_{}, xz_{}, yz_{};
  Int4 count_{};
};

std::array<double, 6> sphere_metric(double r) {
  const double k = 1.0 / (r * r);
  return {k, k, k, 0.0, 0.0, 0.0};
}

}  // namespace

namespace detail {

KernelEllipsoid kernel_from_sums(const Vec3& p, double R, double r, double W, const Vec3& S,
                                 const std::array<double, 6>& Q, uint32_t count, const AnisotropyOptions& o,
                                 double unit) {
  KernelEllipsoid k;
  // W >= 1: the particle itself is among its neighbours, at distance 0. m and C are in units
  // of `unit`; the semi-axes below depend only on the ratios of C's eigenvalues.
  const Vec3 m = S / W;
  k.centre = p + m * (unit * o.smoothing);
  k.metric = sphere_metric(R);
  k.neighbors = count - 1;
  k.mean_offset = norm(m) * (unit / r);
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
  if (!(s1 > 1e-12 * (r / unit) * (r / unit)) || !std::isfinite(s1)) return k;
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
                                                      const double* radii, double cell_radius,
                                                      const AnisotropyOptions& o, ProgressTracker& tracker,
                                                      double begin, double end) {
  validate_anisotropy(o);
  std::vector<KernelEllipsoid> out(n);
  if (n == 0) return out;
  double rmax = radius;
  if (radii) rmax = *std::max_element(radii, radii + n);
  const double reach = o.neighbor_radius * rmax;
  // Cells of half the query radius: a query scans 5^3 cells, about a quarter of whose volume
  // is inside the ball (cells of the full radius scan 27 cells, a seventh inside). The radius
  // is the field grid's (particle_grid_radius): a few particles far larger than the rest
  // search their larger neighbourhoods over more cells, rather than every cell being theirs.
  const double cell_reach = o.neighbor_radius * cell_radius;
  NeighborGrid grid;
  try {
    grid = NeighborGrid(positions, n, 0.5 * cell_reach);
  } catch (const Error& e) {
    if (e.status() != Status::LimitExceeded) throw;
    throw Error(Status::LimitExceeded, "the anisotropic kernels' neighbourhood (neighbor_radius x R = " + num(reach) +
                                           ") is too small for the particles' extent: " + e.what());
  }
  const auto& P = grid.sorted_points();
  const size_t ncells = grid.cell_count();
  const int32_t K = int32_t(std::ceil(cell_reach / grid.cell_size()));
  tracker.stage("anisotropic kernels", begin, end, ncells);
  // The points as float arrays, cell by cell, each cell's relative to its first point, in units
  // of the largest neighbourhood radius (so that float holds any radius the field accepts),
  // padded to a multiple of 4 with points far away (offsets of a few radii lose nothing that
  // matters to a covariance in float), with the box of the cell's points (same units).
  const double unit = reach, inv_unit = 1.0 / reach;
  std::vector<uint32_t> start(ncells + 1, 0);
  for (size_t c = 0; c < ncells; ++c) start[c + 1] = start[c] + ((grid.cell_end(uint32_t(c)) - grid.cell_begin(uint32_t(c)) + 3) & ~3u);
  std::vector<float> X(start[ncells]), Y(start[ncells]), Z(start[ncells]);
  std::vector<Vec3> box_lo(ncells), box_hi(ncells);
  detail::parallel_blocks(ncells, 256, [&](size_t cb, size_t ce) {
    for (size_t c = cb; c < ce; ++c) {
      const uint32_t b = grid.cell_begin(uint32_t(c)), e = grid.cell_end(uint32_t(c));
      const Vec3 ref = P[b];
      Vec3 lo{}, hi{};
      for (uint32_t k = b; k < e; ++k) {
        const Vec3 q = (P[k] - ref) * inv_unit;
        lo = {std::min(lo.x, q.x), std::min(lo.y, q.y), std::min(lo.z, q.z)};
        hi = {std::max(hi.x, q.x), std::max(hi.y, q.y), std::max(hi.z, q.z)};
        X[start[c] + k - b] = float(q.x);
        Y[start[c] + k - b] = float(q.y);
        Z[start[c] + k - b] = float(q.z);
      }
      for (uint32_t k = start[c] + (e - b); k < start[c + 1]; ++k) X[k] = Y[k] = Z[k] = 1e15f;
      box_lo[c] = lo;
      box_hi[c] = hi;
    }
  });
  tracker.check();
  // Each particle sums its weights over the cells within reach, 4 points at a time (SSE / NEON
  // through the compiler's vector types), skipping the cells its ball misses. Cells come in
  // increasing order and the lanes are added in a fixed order at the end, so the sums do not
  // depend on the thread count.
  detail::parallel_blocks(ncells, 16, [&](size_t cb, size_t ce) {
    if (tracker.cancelled()) return;
    std::vector<uint32_t> near, wide;
    for (size_t c = cb; c < ce; ++c) {
      const NeighborGrid::CellCoord cc = grid.cell_coord(uint32_t(c));
      near.clear();
      grid.for_each_cell_in({cc[0] - K, cc[1] - K, cc[2] - K}, {cc[0] + K, cc[1] + K, cc[2] + K},
                            [&](uint32_t d) { near.push_back(d); });
      for (uint32_t s = grid.cell_begin(uint32_t(c)); s < grid.cell_end(uint32_t(c)); ++s) {
        const uint32_t i = grid.original_index(s);
        const Vec3 p = P[s];
        const double R = radii ? radii[i] : radius;
        const double r = o.neighbor_radius * R, r2 = (r * inv_unit) * (r * inv_unit);
        // A particle reaching beyond the cells' radius: the cells of its own reach.
        const std::vector<uint32_t>* cells = &near;
        if (R > cell_radius) {
          // Clamped before the conversion (a radius of 1e14 cells overflowed int): a reach past
          // the grid's whole span takes every cell, as for_each_cell_in clamps the box anyway.
          const double reach_cells = std::ceil(r / grid.cell_size());
          constexpr int32_t kWhole = NeighborGrid::kMaxCellsPerAxis + 4;
          const int32_t Ki = reach_cells < double(kWhole) ? int32_t(reach_cells) : kWhole;
          wide.clear();
          grid.for_each_cell_in({cc[0] - Ki, cc[1] - Ki, cc[2] - Ki}, {cc[0] + Ki, cc[1] + Ki, cc[2] + Ki},
                                [&](uint32_t d) { wide.push_back(d); });
          cells = &wide;
        }
        WeightedSums acc(r * inv_unit);
        for (const uint32_t d : *cells) {
          const Vec3 pd = (p - P[grid.cell_begin(d)]) * inv_unit;  // the particle in the cell's frame
          double gap2 = 0;
          for (int a = 0; a < 3; ++a) {
            const double g = std::max({box_lo[d][a] - pd[a], pd[a] - box_hi[d][a], 0.0});
            gap2 += g * g;
          }
          if (gap2 > r2) continue;  // the ball misses the cell
          acc.at(pd);
          for (uint32_t k = start[d]; k < start[d + 1]; k += 4) acc.add(&X[k], &Y[k], &Z[k]);
        }
        double W, S[3], Q[6];
        const uint32_t count = acc.total(&W, S, Q);
        out[i] = kernel_from_sums(p, R, r, W, {S[0], S[1], S[2]}, {Q[0], Q[1], Q[2], Q[3], Q[4], Q[5]}, count, o,
                                  unit);
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
                                            radii.empty() ? radius : particle_grid_radius(radii.data(), n), options,
                                            tracker, 0.0, 1.0);
  });
  tracker.finish();
  return r;
}

}  // namespace particlemesh
