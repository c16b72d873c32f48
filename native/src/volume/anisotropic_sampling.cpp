#include "volume/anisotropic_sampling.h"

#include <algorithm>
#include <cmath>
#include <cstring>

#include "volume/field_impl.h"
#include "volume/sampling_rows.h"

namespace PM_NAMESPACE::detail {

namespace {

constexpr int kB = kSampleBlock;

// row[x] += w g(s) with s = a2[x] + b dx[x] + c along a row of 8 nodes: the ellipsoid's
// quadratic form restricted to the row (a2 = M_xx dx^2, b and c from the row's y and z).
// Branch-free and 4-wide as the spherical sampler's rows (sampling_rows.h).
template <Kernel K>
inline void add_row(float* row, const float* a2, const float* dx, float b, float c, float wa, float wb) {
  for (int half = 0; half < 2; ++half) {
    const Float4 q = load4(a2 + 4 * half), d = load4(dx + 4 * half);
    store4(row + 4 * half, add_kernel<K>(load4(row + 4 * half), q + b * d + c, wa, wb));
  }
}

template <Kernel K>
void sample(const ParticleField& field, const Vec3& o, double h, float* out) {
  const NeighborGrid& grid = field.grid();
  const auto& P = grid.sorted_points();
  const auto& ws = field.sorted_strengths();
  const auto& M = field.sorted_metrics();
  const auto& E = field.sorted_half_extents();
  const double reach = field.cell_reach();
  const double inv_h = 1.0 / h, h2 = h * h;
  const double span = double(kB - 1) * h;
  std::fill(out, out + kB * kB * kB, 0.0f);
  const NeighborGrid::CellCoord clo = grid.coord_of(o - Vec3{reach, reach, reach});
  const NeighborGrid::CellCoord chi = grid.coord_of(o + Vec3{span + reach, span + reach, span + reach});
  alignas(16) float a2[kB], dxs[kB];
  const auto& B = field.cell_support_boxes();
  auto add = [&](uint32_t s) {
      const float w = ws.empty() ? 1.0f : float(ws[s]);
      if (w == 0.0f) return;
      float wa, wb;
      row_weights<K>(w, &wa, &wb);
      // Centre and half extents in node units, relative to the block's first node.
      const double ux = (P[s].x - o.x) * inv_h, uy = (P[s].y - o.y) * inv_h, uz = (P[s].z - o.z) * inv_h;
      const double ex = double(E[3 * size_t(s)]) * inv_h, ey = double(E[3 * size_t(s) + 1]) * inv_h,
                   ez = double(E[3 * size_t(s) + 2]) * inv_h;
      if (ux + ex < 0 || ux - ex > kB - 1 || uy + ey < 0 || uy - ey > kB - 1 || uz + ez < 0 || uz - ez > kB - 1)
        return;
      const int y0 = std::max(iceil(uy - ey), 0), y1 = std::min(ifloor(uy + ey), kB - 1);
      const int z0 = std::max(iceil(uz - ez), 0), z1 = std::min(ifloor(uz + ez), kB - 1);
      if (y0 > y1 || z0 > z1) return;
      // The quadratic form in node units, and its Schur complements: minimised over x, s is
      // Syy dy^2 + 2 Syz dy dz + Szz dz^2; minimised over y as well, Q dz^2. So the slice z
      // meets the support for Q dz^2 < 1, and its rows y for dy around -Syz dz / Syy.
      const double* m = &M[6 * size_t(s)];
      const double Axx = m[0] * h2, Ayy = m[1] * h2, Azz = m[2] * h2;
      const double Axy = m[3] * h2, Axz = m[4] * h2, Ayz = m[5] * h2;
      const double Syy = Ayy - Axy * Axy / Axx, Syz = Ayz - Axy * Axz / Axx, Szz = Azz - Axz * Axz / Axx;
      const double Q = Szz - Syz * Syz / Syy;
      for (int x = 0; x < kB; ++x) {
        const double d = double(x) - ux;
        a2[x] = float(Axx * d * d);
        dxs[x] = float(d);
      }
      for (int z = z0; z <= z1; ++z) {
        const double dz = double(z) - uz;
        const double rem = 1.0 - Q * dz * dz;
        if (!(rem > 0)) continue;
        const double yc = uy - Syz * dz / Syy;
        const double half = std::sqrt(rem / Syy);
        const int ya = std::max(y0, iceil(yc - half)), yb = std::min(y1, ifloor(yc + half));
        for (int y = ya; y <= yb; ++y) {
          const double dy = double(y) - uy;
          const float b = float(2.0 * (Axy * dy + Axz * dz));
          const float cc = float(Ayy * dy * dy + 2.0 * Ayz * dy * dz + Azz * dz * dz);
          float* row = out + kB * (y + kB * z);
          if constexpr (K == Kernel::Blinn) {
            for (int x = 0; x < kB; ++x) {
              const float q = a2[x] + b * dxs[x] + cc;
              row[x] += w * float(kernel_value(Kernel::Blinn, double(q)));
            }
          } else {
            add_row<K>(row, a2, dxs, b, cc, wa, wb);
          }
        }
      }
  };
  field.for_each_cell_in(clo, chi, [&](uint32_t c) {
    // The cell's kernels' boxes against the block's nodes: most cells in range miss them.
    const float* b = &B[6 * size_t(c)];
    if (double(b[3]) < o.x || double(b[4]) < o.y || double(b[5]) < o.z || double(b[0]) > o.x + span ||
        double(b[1]) > o.y + span || double(b[2]) > o.z + span)
      return;
    for (uint32_t s = grid.cell_begin(c); s < grid.cell_end(c); ++s) add(s);
  });
  for (uint32_t s = grid.apart_begin(); s < grid.point_count(); ++s) add(s);  // kept apart: last
}

}  // namespace

void sample_block_anisotropic(const ParticleField& field, const Vec3& first_node, double h, float* out) {
  dispatch_kernel(field.kernel(), [&]<Kernel K>() { sample<K>(field, first_node, h, out); });
}

bool anisotropic_support_meets_box(const ParticleField& field, const Vec3& lo, const Vec3& hi) {
  const NeighborGrid& grid = field.grid();
  const auto& P = grid.sorted_points();
  const auto& E = field.sorted_half_extents();
  const double reach = field.cell_reach();
  const NeighborGrid::CellCoord clo = grid.coord_of(lo - Vec3{reach, reach, reach});
  const NeighborGrid::CellCoord chi = grid.coord_of(hi + Vec3{reach, reach, reach});
  const auto& B = field.cell_support_boxes();
  bool met = false;
  auto test = [&](uint32_t s) {
    bool in = true;
    for (int a = 0; a < 3 && in; ++a) {
      const double e = double(E[3 * size_t(s) + size_t(a)]);
      in = P[s][a] - e < hi[a] && P[s][a] + e > lo[a];
    }
    met = in;
  };
  field.for_each_cell_in(clo, chi, [&](uint32_t c) {
    const float* b = &B[6 * size_t(c)];
    if (met || double(b[3]) <= lo.x || double(b[4]) <= lo.y || double(b[5]) <= lo.z || double(b[0]) >= hi.x ||
        double(b[1]) >= hi.y || double(b[2]) >= hi.z)
      return;
    for (uint32_t s = grid.cell_begin(c); s < grid.cell_end(c) && !met; ++s) test(s);
  });
  for (uint32_t s = grid.apart_begin(); s < grid.point_count() && !met; ++s) test(s);
  return met;
}

}  // namespace particlemesh::detail
