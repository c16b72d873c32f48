#include "volume/sphere_sampling.h"

#include <algorithm>
#include <cmath>
#include <cstring>

#include "volume/anisotropic_sampling.h"
#include "volume/field_impl.h"
#include "volume/sampling_rows.h"

namespace PM_NAMESPACE::detail {

namespace {

constexpr int kB = kSampleBlock;
constexpr int kBN = kB * kB * kB;

// g(s) with s clamped to the support, in float: t = max(0, 1 - s), so s >= 1 gives exactly
// 0 with no branch (the polynomial kernels are written in t).
template <Kernel K>
inline float kernel_clamped(float s) {
  const float t = std::max(0.0f, 1.0f - s);
  if constexpr (K == Kernel::Wyvill) return t * t * (5.0f + 4.0f * t) * (1.0f / 9.0f);
  else if constexpr (K == Kernel::Poly4) return t * t;
  else if constexpr (K == Kernel::Poly6) return t * t * t;
  else return float(kernel_value(Kernel::Blinn, double(s)));
}

// row[x] += w g(dx2[x] + syz) for the 8 nodes of a row (sampling_rows.h).
template <Kernel K>
inline void add_row(float* row, const float* dx2, float syz, float a, float b) {
  for (int half = 0; half < 2; ++half)
    store4(row + 4 * half, add_kernel<K>(load4(row + 4 * half), load4(dx2 + 4 * half) + syz, a, b));
}

// Sum every particle's contribution into the samples of one block, in grid order (the cells
// around the block, then the particles kept apart from the cells).
// The samples are float (as stored), and each row of 8 nodes is summed whole, branch-free
// (nodes outside the support get exactly 0): fixed-length float loops that the compiler
// vectorises with baseline SSE2, several times faster than finding each row's exact ends.
// The order of the sums is fixed (particles in grid order), so the samples do not depend on
// the thread count.
template <Kernel K>
void sample_block(const ParticleField& field, const Vec3& first, double h, float* out) {
  const double inv_h = 1.0 / h;
  const NeighborGrid& grid = field.grid();
  const auto& P = grid.sorted_points();
  const auto& inv_r2s = field.sorted_inverse_squared_radii();
  const auto& ws = field.sorted_strengths();
  const bool uniform = field.uniform_radius();
  const double inv_r2_common = 1.0 / (field.params().radius * field.params().radius);
  const double rmax = field.cell_reach();
  const double ox = first.x, oy = first.y, oz = first.z;
  const Vec3 lo{ox - rmax, oy - rmax, oz - rmax};
  const Vec3 hi{ox + double(kB - 1) * h + rmax, oy + double(kB - 1) * h + rmax, oz + double(kB - 1) * h + rmax};
  std::fill(out, out + kBN, 0.0f);
  const NeighborGrid::CellCoord clo = grid.coord_of(lo), chi = grid.coord_of(hi);
  // Uniform radius: the support in node units is the same for every particle.
  double c2 = h * h * inv_r2_common;  // (node units)^2 -> s
  double rn = std::sqrt(1.0 / c2);    // radius in node units
  alignas(32) float dx2[kB];
  auto add = [&](uint32_t s) {
      const float w = ws.empty() ? 1.0f : float(ws[s]);
      if (w == 0.0f) return;
      float wa, wb;
      row_weights<K>(w, &wa, &wb);
      if (!uniform) {
        c2 = h * h * inv_r2s[s];
        rn = std::sqrt(1.0 / c2);
      }
      // Particle position in node units, relative to the block's first node. (The cells
      // scanned are within a few radii of the block, so these are small numbers.)
      const double ux = (P[s].x - ox) * inv_h, uy = (P[s].y - oy) * inv_h, uz = (P[s].z - oz) * inv_h;
      if (ux + rn < 0 || ux - rn > kB - 1 || uy + rn < 0 || uy - rn > kB - 1 || uz + rn < 0 ||
          uz - rn > kB - 1)
        return;  // the support misses the block's nodes (most scanned particles)
      const int x0 = std::max(iceil(ux - rn), 0), x1 = std::min(ifloor(ux + rn), kB - 1);
      const int y0 = std::max(iceil(uy - rn), 0), y1 = std::min(ifloor(uy + rn), kB - 1);
      const int z0 = std::max(iceil(uz - rn), 0), z1 = std::min(ifloor(uz + rn), kB - 1);
      if (x0 > x1 || y0 > y1 || z0 > z1) return;
      for (int x = 0; x < kB; ++x) {
        const double d = double(x) - ux;
        dx2[x] = float(d * d * c2);
      }
      for (int z = z0; z <= z1; ++z) {
        const double dz = double(z) - uz;
        const double sz = dz * dz * c2;
        if (!(sz < 1.0)) continue;
        // The rows of this slice that meet the support (one square root per slice instead
        // of a hard-to-predict test per row; a row grazing the edge just adds zeros).
        const double half = std::sqrt((1.0 - sz) / c2);
        const int ya = std::max(y0, iceil(uy - half)), yb = std::min(y1, ifloor(uy + half));
        for (int y = ya; y <= yb; ++y) {
          const double dy = double(y) - uy;
          const float syz = float(sz + dy * dy * c2);
          float* row = out + kB * (y + kB * z);
          if constexpr (K == Kernel::Blinn) {
            for (int x = 0; x < kB; ++x) row[x] += w * kernel_clamped<K>(dx2[x] + syz);
          } else {
            add_row<K>(row, dx2, syz, wa, wb);
          }
        }
      }
  };
  field.for_each_cell_in(clo, chi, [&](uint32_t c) {
    for (uint32_t s = grid.cell_begin(c); s < grid.cell_end(c); ++s) add(s);
  });
  for (uint32_t s = grid.apart_begin(); s < grid.point_count(); ++s) add(s);
}

}  // namespace

void sample_block_spherical(const ParticleField& field, const Vec3& first_node, double h, float* out) {
  dispatch_kernel(field.kernel(), [&]<Kernel K>() { sample_block<K>(field, first_node, h, out); });
}

}  // namespace particlemesh::detail
