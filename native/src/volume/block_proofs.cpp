#include "volume/block_proofs.h"

#include <algorithm>
#include <cmath>
#include <cstring>

#include "volume/anisotropic_sampling.h"
#include "volume/field_impl.h"

namespace PM_NAMESPACE::detail {

namespace {

constexpr int kB = kSampleBlock;
constexpr int kG = kB / 2;  // group centres per block edge (groups of 2 x 2 x 2 nodes)

typedef float Float4 __attribute__((vector_size(4 * sizeof(float))));
typedef int32_t Int4 __attribute__((vector_size(4 * sizeof(int32_t))));

// The particles whose support can reach the block's nodes, in grid order (those kept apart
// from the cells last): f(sorted index, position in node units relative to the block's first
// node, radius in node units, s per squared node unit, strength) returns whether to go on.
template <class F>
void for_each_particle_near(const ParticleField& field, const Vec3& o, double h, F&& f) {
  const NeighborGrid& grid = field.grid();
  const auto& P = grid.sorted_points();
  const auto& inv_r2s = field.sorted_inverse_squared_radii();
  const auto& ws = field.sorted_strengths();
  const bool uniform = field.uniform_radius();
  const double inv_h = 1.0 / h;
  const double rmax = field.cell_reach(), span = double(kB - 1) * h;
  const double c2_common = h * h / (field.params().radius * field.params().radius);
  const double rn_common = std::sqrt(1.0 / c2_common);
  const NeighborGrid::CellCoord clo = grid.coord_of(o - Vec3{rmax, rmax, rmax});
  const NeighborGrid::CellCoord chi = grid.coord_of(o + Vec3{span + rmax, span + rmax, span + rmax});
  bool go_on = true;
  auto visit = [&](uint32_t s) {
    const double w = ws.empty() ? 1.0 : ws[s];
    if (w == 0) return;
    const double c2 = uniform ? c2_common : h * h * inv_r2s[s];
    const double rn = uniform ? rn_common : std::sqrt(1.0 / c2);
    const double ux = (P[s].x - o.x) * inv_h, uy = (P[s].y - o.y) * inv_h, uz = (P[s].z - o.z) * inv_h;
    if (ux + rn < 0 || ux - rn > kB - 1 || uy + rn < 0 || uy - rn > kB - 1 || uz + rn < 0 || uz - rn > kB - 1)
      return;
    go_on = f(s, ux, uy, uz, rn, c2, w);
  };
  field.for_each_cell_in(clo, chi, [&](uint32_t c) {
    for (uint32_t s = grid.cell_begin(c); s < grid.cell_end(c) && go_on; ++s) visit(s);
  });
  for (uint32_t s = grid.apart_begin(); s < grid.point_count() && go_on; ++s) visit(s);
}

// Upper bound of F over the block's nodes: each particle at its nearest point of the nodes'
// box. Stops (returns false) as soon as the sum reaches T.
bool outside(const ParticleField& field, const Vec3& o, double h) {
  const Kernel kernel = field.kernel();
  const double T = field.threshold();
  double ub = 0, wmax = 0;
  size_t n = 0;
  bool reached = false;
  for_each_particle_near(field, o, h, [&](uint32_t, double ux, double uy, double uz, double, double c2, double w) {
    auto gap = [](double u) { return u < 0 ? -u : (u > kB - 1 ? u - (kB - 1) : 0.0); };
    const double dx = gap(ux), dy = gap(uy), dz = gap(uz);
    const double s = (dx * dx + dy * dy + dz * dz) * c2;
    if (!(s < 1.0)) return true;
    ub += w * kernel_value(kernel, s);
    wmax = std::max(wmax, w);
    ++n;
    reached = ub >= T;
    return !reached;
  });
  // Far above the rounding of a float sample of n terms (about n 2^-22 of the sum).
  const double margin = double(n + 16) * 0x1p-20 * (ub + double(n + 16) * wmax);
  return !reached && ub + margin < T;
}

// The tangent bound at the 4 x 4 x 4 group centres (see block_proofs.h). Returns true when
// every group's bound stays at or above T.
template <Kernel K>
bool inside(const ParticleField& field, const Vec3& o, double h) {
  const double T = field.threshold();
  // Accumulators per row of 4 centres (y, z): F, dF/dx, dF/dy, dF/dz, K, contributors.
  Float4 acc_f[kG * kG] = {}, acc_gx[kG * kG] = {}, acc_gy[kG * kG] = {}, acc_gz[kG * kG] = {},
         acc_k[kG * kG] = {}, acc_n[kG * kG] = {};
  double wmax = 0;
  const Float4 cx = {0.5f, 2.5f, 4.5f, 6.5f};
  for_each_particle_near(field, o, h, [&](uint32_t, double ux, double uy, double uz, double rn, double c2, double w) {
    // The centres span [0.5, 6.5] on each axis.
    if (ux + rn < 0.5 || ux - rn > 6.5 || uy + rn < 0.5 || uy - rn > 6.5 || uz + rn < 0.5 || uz - rn > 6.5) return true;
    wmax = std::max(wmax, w);
    // w g = t^2 (wa + wb t), w dg/ds = -t (2 wa + 3 wb t), t = 1 - s.
    const float wa = K == Kernel::Wyvill ? float(w * 5.0 / 9.0) : (K == Kernel::Poly4 ? float(w) : 0.0f);
    const float wb = K == Kernel::Wyvill ? float(w * 4.0 / 9.0) : (K == Kernel::Poly6 ? float(w) : 0.0f);
    // In float throughout: the bound's margin covers its rounding.
    const float c2f = float(c2);
    const Float4 dx = cx - float(ux);
    const Float4 dx2 = dx * dx * c2f;
    float dy[kG], dy2[kG], dz[kG], dz2[kG];
    for (int i = 0; i < kG; ++i) {
      dy[i] = float(0.5 + 2 * i - uy);
      dz[i] = float(0.5 + 2 * i - uz);
      dy2[i] = dy[i] * dy[i] * c2f;
      dz2[i] = dz[i] * dz[i] * c2f;
    }
    const float two_wa = 2.0f * wa, three_wb = 3.0f * wb;
    for (int z = 0; z < kG; ++z) {
      if (!(dz2[z] < 1.0f)) continue;
      for (int y = 0; y < kG; ++y) {
        const float syz = dz2[z] + dy2[y];
        if (!(syz < 1.0f)) continue;
        const int r = y + kG * z;
        Float4 t = 1.0f - (dx2 + syz);
        const Int4 in = t > 0.0f;
        t = (Float4)((Int4)t & in);
        const Float4 a = -(t * (two_wa + three_wb * t)) * c2f;  // w dg/ds, per squared node
        const Float4 a2 = a + a;
        acc_f[r] += t * t * (wa + wb * t);
        acc_gx[r] += a2 * dx;
        acc_gy[r] += dy[y] * a2;
        acc_gz[r] += dz[z] * a2;
        acc_k[r] -= a;
        acc_n[r] += __builtin_convertvector(in & 1, Float4);
      }
    }
    return true;
  });
  for (int r = 0; r < kG * kG; ++r)
    for (int i = 0; i < 4; ++i) {
      const double f = acc_f[r][i], k = acc_k[r][i], n = acc_n[r][i];
      const double g1 = std::abs(double(acc_gx[r][i])) + std::abs(double(acc_gy[r][i])) + std::abs(double(acc_gz[r][i]));
      const double bound = f - 0.5 * g1 - 0.75 * k;
      // Far above the rounding of the float sums here and of the nodes' float samples (a node
      // may have a few more contributors than its group's centre: 2n + 32).
      const double m = 2 * n + 32;
      const double margin = m * 0x1p-20 * (f + g1 + k + m * wmax);
      if (!(bound >= T + margin)) return false;
    }
  return true;
}

}  // namespace

bool block_proofs_apply(const ParticleField& field) {
  if (field.anisotropic()) return false;
  for (const double w : field.sorted_strengths())
    if (w < 0) return false;
  return true;
}

BlockProof prove_block(const ParticleField& field, const Vec3& first_node, double h, bool try_inside) {
  if (outside(field, first_node, h)) return BlockProof::Outside;
  if (!try_inside) return BlockProof::None;
  bool in = false;
  switch (field.kernel()) {
    case Kernel::Wyvill: in = inside<Kernel::Wyvill>(field, first_node, h); break;
    case Kernel::Poly4: in = inside<Kernel::Poly4>(field, first_node, h); break;
    case Kernel::Poly6: in = inside<Kernel::Poly6>(field, first_node, h); break;
    case Kernel::Blinn: break;  // not a polynomial: no inside proof
  }
  return in ? BlockProof::Inside : BlockProof::None;
}

}  // namespace particlemesh::detail
