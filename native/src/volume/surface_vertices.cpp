#include "volume/surface_vertices.h"

#include <algorithm>
#include <cmath>

#include "volume/mc_table.h"

namespace PM_NAMESPACE::detail {

Crossing refine_crossing(const ParticleField& field, const Vec3& a, int axis, double h, double fa, double fb,
                         double T) {
  Crossing out;
  double lo = 0, hi = 1;
  const double phi_lo = fa - T;  // sign at t = 0
  double t = std::clamp((T - fa) / (fb - fa), kEdgeClamp, 1.0 - kEdgeClamp);
  Vec3 grad{};
  auto at = [&](double tt) {
    Vec3 x = a;
    (axis == 0 ? x.x : axis == 1 ? x.y : x.z) += tt * h;
    return x;
  };
  for (int it = 0; it < 8; ++it) {
    const double phi = field.value_and_gradient(at(t), &grad) - T;
    ++out.evaluations;
    if (phi == 0) break;
    if ((phi < 0) == (phi_lo < 0)) lo = t; else hi = t;
    const double dphi = grad[axis] * h;
    double next = dphi != 0 ? t - phi / dphi : 0.5 * (lo + hi);
    if (!(next > lo && next < hi)) next = 0.5 * (lo + hi);
    const double step = std::abs(next - t);
    t = next;
    // Newton converges quadratically (error ~ (g''/2g') step^2, with g''/g' of order h/R):
    // after a step below 1e-2 of the edge the root is within ~1e-5 h, so that last step is
    // taken without another evaluation (the normal comes from the gradient that close by).
    if (step < 1e-2) break;
  }
  t = std::clamp(t, kEdgeClamp, 1.0 - kEdgeClamp);
  out.position = at(t);
  const double gn = norm(grad);
  if (gn > 0 && std::isfinite(gn)) {
    out.normal = grad * (-1.0 / gn);
  } else {
    // No gradient (a flat spot): fall back to the edge direction, from inside to outside.
    Vec3 e{};
    (axis == 0 ? e.x : axis == 1 ? e.y : e.z) = fa >= T ? 1.0 : -1.0;
    out.normal = e;
  }
  return out;
}

Crossing center_vertex(const ParticleField& field, const Vec3& cell_lo, double h, const float cv[8],
                       const uint8_t* loop, int len, double T) {
  Crossing out;
  Vec3 x{};
  for (int k = 0; k < len; ++k) {
    const int e = loop[k];
    const int lc = mc_edge_lower_corner(e), axis = mc_edge_axis(e);
    const double f0 = cv[lc], f1 = cv[lc + (1 << axis)];
    const double t = std::clamp((T - f0) / (f1 - f0), 0.0, 1.0);
    Vec3 p{double(lc & 1), double((lc >> 1) & 1), double((lc >> 2) & 1)};
    (axis == 0 ? p.x : axis == 1 ? p.y : p.z) += t;
    x += p;
  }
  x = cell_lo + x * (h / len);
  Vec3 grad{};
  for (int it = 0; it < 6; ++it) {
    const double phi = field.value_and_gradient(x, &grad) - T;
    ++out.evaluations;
    const double g2 = squared_norm(grad);
    if (!(g2 > 0) || phi == 0) break;
    Vec3 next = x - grad * (phi / g2);
    next = {std::clamp(next.x, cell_lo.x, cell_lo.x + h), std::clamp(next.y, cell_lo.y, cell_lo.y + h),
            std::clamp(next.z, cell_lo.z, cell_lo.z + h)};
    const double step = distance(next, x);
    x = next;
    if (step < 1e-7 * h) break;
  }
  out.position = x;
  const double gn = norm(grad);
  out.normal = gn > 0 && std::isfinite(gn) ? grad * (-1.0 / gn) : Vec3{0, 0, 1};
  return out;
}

}  // namespace PM_NAMESPACE::detail
