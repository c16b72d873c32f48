// Internal: Tonnesen's smallest-enclosing-sphere predicate with its symbolic tie-break.
// Shared by the fast triangulation and by the brute-force reference in the tests, so the
// two can only differ in which points they look at, never in how one point is judged.
#pragma once

#include "particlemesh/core/config.h"

#include <algorithm>
#include <array>
#include <cmath>

#include "particlemesh/core/vec3.h"

namespace PM_NAMESPACE::detail {

/// Lexicographic order of coordinates: the rank of the symbolic perturbation.
inline bool lex_less(const Vec3& p, const Vec3& q) {
  if (p.x != q.x) return p.x < q.x;
  if (p.y != q.y) return p.y < q.y;
  return p.z < q.z;
}

/// Relative width of the tie zone: |q - c|^2 - rho^2 within kTieTolerance * rho^2 is a tie.
constexpr double kTieTolerance = 1e-9;
/// A corner whose sine is below this makes the triplet degenerate (collinear).
constexpr double kDegenerateSine = 1e-10;
/// cos of a corner below -kRightAngleTolerance makes the triangle obtuse.
constexpr double kRightAngleTolerance = 1e-9;

struct SmallestSphere {
  bool degenerate = false;
  bool obtuse = false;
  Vec3 a, b, c;       ///< the corners (absolute coordinates)
  Vec3 center_rel;    ///< sphere centre minus a
  double r2 = 0;      ///< squared radius
  Vec3 normal;        ///< (b - a) x (c - a)
  double inv_normal2 = 0;
  int e0 = 0, e1 = 0; ///< obtuse: corners (0 = a, 1 = b, 2 = c) at the ends of the diameter

  const Vec3& corner(int i) const { return i == 0 ? a : (i == 1 ? b : c); }
};

/// The corners are put in rank order first, so the result (and its rounding) depends only on
/// the three points, never on the order in which a caller lists them. The result is written
/// once, as a whole (the triangle test calls this for every candidate triplet, and a
/// default-built result zeroed every field before setting it: a fifth of the function's time).
inline SmallestSphere smallest_sphere(Vec3 a, Vec3 b, Vec3 c) {
  if (lex_less(b, a)) std::swap(a, b);
  if (lex_less(c, b)) std::swap(b, c);
  if (lex_less(b, a)) std::swap(a, b);
  const Vec3 u = b - a, v = c - a, w = c - b;
  const double luu = squared_norm(u), lvv = squared_norm(v), lww = squared_norm(w);
  const Vec3 n = cross(u, v);
  const double n2 = squared_norm(n);
  // |n| = product of two edges times the sine between them; the largest product bounds
  // every corner's sine from below.
  const double lmax = std::max({luu, lvv, lww});
  const double lmid = luu + lvv + lww - lmax - std::min({luu, lvv, lww});
  if (!(luu > 0 && lvv > 0 && lww > 0) ||
      n2 <= kDegenerateSine * kDegenerateSine * lmax * lmid) {
    SmallestSphere s;
    s.a = a;
    s.b = b;
    s.c = c;
    s.degenerate = true;
    return s;
  }
  // Obtuse corner: the dot product of its two edges is clearly negative. (Only a negative one
  // can be: the square root, the bound's only cost, is taken for those alone.)
  const double da = dot(u, v);             // at a
  const double db = dot(a - b, c - b);     // at b
  const double dc = dot(a - c, b - c);     // at c
  bool obtuse = false;
  int e0 = 0, e1 = 0;
  if (da < 0 && da < -kRightAngleTolerance * std::sqrt(luu * lvv)) {
    obtuse = true; e0 = 1; e1 = 2;
  } else if (db < 0 && db < -kRightAngleTolerance * std::sqrt(luu * lww)) {
    obtuse = true; e0 = 0; e1 = 2;
  } else if (dc < 0 && dc < -kRightAngleTolerance * std::sqrt(lvv * lww)) {
    obtuse = true; e0 = 0; e1 = 1;
  }
  Vec3 center_rel;
  double r2;
  if (obtuse) {
    const Vec3 p0 = e0 == 0 ? a : b, p1 = e1 == 1 ? b : c;  // e0 < e1
    center_rel = (p0 - a) * 0.5 + (p1 - a) * 0.5;
    r2 = squared_distance(p0, p1) * 0.25;
  } else {
    // Circumcentre in the plane of the triangle.
    center_rel = (cross(n, u) * lvv + cross(v, n) * luu) * (0.5 / n2);
    r2 = squared_norm(center_rel);
  }
  return SmallestSphere{false, obtuse, a, b, c, center_rel, r2, n, 1.0 / n2, e0, e1};
}

/// Where q lies against the sphere: its squared distance from the centre less r^2 (negative
/// inside), as every test of the sphere takes it.
inline double sphere_gap(const SmallestSphere& s, const Vec3& q) { return squared_norm((q - s.a) - s.center_rel) - s.r2; }

/// Does q count as strictly inside the sphere? `tie` is set when the symbolic tie-break
/// decided. q must not be one of the corners.
inline bool sphere_contains(const SmallestSphere& s, const Vec3& q, bool* tie = nullptr) {
  const double d = sphere_gap(s, q);
  const double tol = kTieTolerance * s.r2;
  if (d < -tol) return true;
  if (d > tol) return false;
  if (tie) *tie = true;
  // Coefficients of the perturbed power  sum_v lambda_v(q) w_v - w_q.
  struct Term {
    const Vec3* p;
    double coef;
  };
  std::array<Term, 4> terms;
  int count = 0;
  terms[count++] = {&q, -1.0};
  if (s.obtuse) {
    const Vec3& p0 = s.corner(s.e0);
    const Vec3& p1 = s.corner(s.e1);
    const Vec3 dir = p1 - p0;
    const double mu1 = dot(q - p0, dir) / squared_norm(dir);
    terms[count++] = {&p0, 1.0 - mu1};
    terms[count++] = {&p1, mu1};
  } else {
    const double la = dot(cross(s.c - s.b, q - s.b), s.normal) * s.inv_normal2;
    const double lb = dot(cross(s.a - s.c, q - s.c), s.normal) * s.inv_normal2;
    terms[count++] = {&s.a, la};
    terms[count++] = {&s.b, lb};
    terms[count++] = {&s.c, 1.0 - la - lb};
  }
  for (int t = 1; t < count; ++t)  // insertion sort of at most four terms by rank
    for (int u = t; u > 0 && lex_less(*terms[u].p, *terms[u - 1].p); --u) std::swap(terms[u], terms[u - 1]);
  for (int t = 0; t < count; ++t) {
    if (std::abs(terms[t].coef) > 1e-12) return terms[t].coef < 0;
  }
  return false;  // unreachable: q's own coefficient is -1
}

}  // namespace particlemesh::detail
