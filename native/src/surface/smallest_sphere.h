// Internal: Tonnesen's smallest-enclosing-sphere predicate with its symbolic tie-break.
// Shared by the fast triangulation and by the brute-force reference in the tests, so the
// two can only differ in which points they look at, never in how one point is judged.
#pragma once

#include "particlemesh/core/config.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>

#include "core/cpu_clones.h"
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

#ifdef PM_HAVE_AVX512
namespace sphere_lanes {  // smallest_spheres_avx512's steps (a lambda would not inherit its target)
PM_TARGET_AVX512 inline __m512d sub(__m512d p, __m512d q) { return _mm512_sub_pd(p, q); }
PM_TARGET_AVX512 inline __m512d mul(__m512d p, __m512d q) { return _mm512_mul_pd(p, q); }
PM_TARGET_AVX512 inline __m512d add(__m512d p, __m512d q) { return _mm512_add_pd(p, q); }
/// dot(): x, then y, then z.
PM_TARGET_AVX512 inline __m512d dot3(__m512d px, __m512d py, __m512d pz, __m512d qx, __m512d qy, __m512d qz) {
  return add(add(mul(px, qx), mul(py, qy)), mul(pz, qz));
}
/// lex_less(p, q), lane by lane.
PM_TARGET_AVX512 inline __mmask8 lex_less(__m512d px, __m512d py, __m512d pz, __m512d qx, __m512d qy, __m512d qz) {
  const __mmask8 z_less = _mm512_cmp_pd_mask(pz, qz, _CMP_LT_OQ);
  const __mmask8 y_less = _mm512_cmp_pd_mask(py, qy, _CMP_LT_OQ) | (_mm512_cmp_pd_mask(py, qy, _CMP_EQ_OQ) & z_less);
  return __mmask8(_mm512_cmp_pd_mask(px, qx, _CMP_LT_OQ) | (_mm512_cmp_pd_mask(px, qx, _CMP_EQ_OQ) & y_less));
}
/// std::swap(p, q) in the lanes of m.
PM_TARGET_AVX512 inline void swap_where(__mmask8 m, __m512d& p, __m512d& q) {
  const __m512d p2 = _mm512_mask_blend_pd(m, p, q);
  q = _mm512_mask_blend_pd(m, q, p);
  p = p2;
}
/// d < 0 && d < -kRightAngleTolerance * sqrt(l1 * l2): the corner is clearly obtuse.
PM_TARGET_AVX512 inline __mmask8 clearly_negative(__m512d d, __m512d l1, __m512d l2, __m512d minus_tol) {
  return __mmask8(_mm512_cmp_pd_mask(d, _mm512_setzero_pd(), _CMP_LT_OQ) &
                  _mm512_cmp_pd_mask(d, mul(minus_tol, _mm512_maskz_sqrt_pd(0xff, mul(l1, l2))), _CMP_LT_OQ));
}
/// 3 i for the indices i in the lanes, 0 in the others (i holds eight, the others any value).
/// (The maskz forms here and below, all lanes kept where a plain form exists: GCC 12 warns of
/// its own headers' plain forms.)
PM_TARGET_AVX512 inline __m512i coordinate_index(const uint32_t* i, __mmask8 lanes) {
  const __m512i v = _mm512_maskz_cvtepu32_epi64(lanes, _mm256_loadu_si256(reinterpret_cast<const __m256i*>(i)));
  return _mm512_add_epi64(v, _mm512_add_epi64(v, v));
}
/// The coordinate at base + 3 i (x, y or z of point i) in the lanes, 0 in the others.
PM_TARGET_AVX512 inline __m512d gather_coordinate(const double* base, __m512i index3, __mmask8 lanes) {
  return _mm512_mask_i64gather_pd(_mm512_setzero_pd(), lanes, index3, base, 8);
}
}  // namespace sphere_lanes

/// smallest_sphere(a, points[j[l]], points[k[l]]) for the lanes l < count (1 to 8), eight at a
/// time: the same operations in the same order as the scalar function, lane by lane (IEEE
/// arithmetic and square roots round the same in a vector, and the library is built without
/// fused multiply-adds), so the same bits. The triangle test computes a sphere for every candidate
/// triplet (on an irregular sampling ~70 a point, a fifth of a run), and one at a time the
/// function is a chain of dependent divisions and square roots with unpredictable branches.
PM_TARGET_AVX512 inline void smallest_spheres_avx512(const Vec3& a, const Vec3* points, const uint32_t* j,
                                                     const uint32_t* k, int count, SmallestSphere* out) {
  // The corners gathered from the points (Vec3 is three doubles: x of point i at 3 i).
  static_assert(sizeof(Vec3) == 3 * sizeof(double));
  using namespace sphere_lanes;
  const __mmask8 lanes = __mmask8((1u << count) - 1);
  const __m512i ij = coordinate_index(j, lanes), ik = coordinate_index(k, lanes);
  const double* base = &points[0].x;
  // Lanes past count hold zeros (degenerate, never written out).
  __m512d bx = gather_coordinate(base, ij, lanes), by = gather_coordinate(base + 1, ij, lanes),
          bz = gather_coordinate(base + 2, ij, lanes);
  __m512d cx = gather_coordinate(base, ik, lanes), cy = gather_coordinate(base + 1, ik, lanes),
          cz = gather_coordinate(base + 2, ik, lanes);
  __m512d ax = _mm512_set1_pd(a.x), ay = _mm512_set1_pd(a.y), az = _mm512_set1_pd(a.z);
  __mmask8 m = lex_less(bx, by, bz, ax, ay, az);
  swap_where(m, ax, bx), swap_where(m, ay, by), swap_where(m, az, bz);
  m = lex_less(cx, cy, cz, bx, by, bz);
  swap_where(m, bx, cx), swap_where(m, by, cy), swap_where(m, bz, cz);
  m = lex_less(bx, by, bz, ax, ay, az);
  swap_where(m, ax, bx), swap_where(m, ay, by), swap_where(m, az, bz);
  const __m512d ux = sub(bx, ax), uy = sub(by, ay), uz = sub(bz, az);
  const __m512d vx = sub(cx, ax), vy = sub(cy, ay), vz = sub(cz, az);
  const __m512d wx = sub(cx, bx), wy = sub(cy, by), wz = sub(cz, bz);
  const __m512d luu = dot3(ux, uy, uz, ux, uy, uz), lvv = dot3(vx, vy, vz, vx, vy, vz),
                lww = dot3(wx, wy, wz, wx, wy, wz);
  // n = cross(u, v)
  const __m512d nx = sub(mul(uy, vz), mul(uz, vy)), ny = sub(mul(uz, vx), mul(ux, vz)),
                nz = sub(mul(ux, vy), mul(uy, vx));
  const __m512d n2 = dot3(nx, ny, nz, nx, ny, nz);
  // The squared lengths are never NaN or -0 (sums of squares of finite differences), so
  // max and min give std::max's and std::min's values.
  const __m512d lmax = _mm512_maskz_max_pd(0xff, _mm512_maskz_max_pd(0xff, luu, lvv), lww);
  const __m512d lmin = _mm512_maskz_min_pd(0xff, _mm512_maskz_min_pd(0xff, luu, lvv), lww);
  const __m512d lmid = sub(sub(add(add(luu, lvv), lww), lmax), lmin);
  const __m512d zero = _mm512_setzero_pd();
  const __mmask8 positive = _mm512_cmp_pd_mask(luu, zero, _CMP_GT_OQ) & _mm512_cmp_pd_mask(lvv, zero, _CMP_GT_OQ) &
                            _mm512_cmp_pd_mask(lww, zero, _CMP_GT_OQ);
  const __m512d bound = mul(mul(_mm512_set1_pd(kDegenerateSine * kDegenerateSine), lmax), lmid);
  const __mmask8 degenerate = __mmask8(~positive | _mm512_cmp_pd_mask(n2, bound, _CMP_LE_OQ));
  // The obtuse corner, a's first, then b's, then c's.
  const __m512d da = dot3(ux, uy, uz, vx, vy, vz);
  const __m512d db = dot3(sub(ax, bx), sub(ay, by), sub(az, bz), wx, wy, wz);
  const __m512d dc = dot3(sub(ax, cx), sub(ay, cy), sub(az, cz), sub(bx, cx), sub(by, cy), sub(bz, cz));
  const __m512d minus_tol = _mm512_set1_pd(-kRightAngleTolerance);
  const __mmask8 at_a = clearly_negative(da, luu, lvv, minus_tol);
  const __mmask8 at_b = __mmask8(~at_a & clearly_negative(db, luu, lww, minus_tol));
  const __mmask8 at_c = __mmask8(~at_a & ~at_b & clearly_negative(dc, lvv, lww, minus_tol));
  const __mmask8 obtuse = __mmask8(at_a | at_b | at_c);
  // Obtuse: the diameter p0 p1 (b c at a, a c at b, a b at c).
  const __m512d p0x = _mm512_mask_blend_pd(at_a, ax, bx), p0y = _mm512_mask_blend_pd(at_a, ay, by),
                p0z = _mm512_mask_blend_pd(at_a, az, bz);
  const __m512d p1x = _mm512_mask_blend_pd(at_c, cx, bx), p1y = _mm512_mask_blend_pd(at_c, cy, by),
                p1z = _mm512_mask_blend_pd(at_c, cz, bz);
  const __m512d half = _mm512_set1_pd(0.5);
  const __m512d ox = add(mul(sub(p0x, ax), half), mul(sub(p1x, ax), half)),
                oy = add(mul(sub(p0y, ay), half), mul(sub(p1y, ay), half)),
                oz = add(mul(sub(p0z, az), half), mul(sub(p1z, az), half));
  const __m512d dx = sub(p0x, p1x), dy = sub(p0y, p1y), dz = sub(p0z, p1z);
  const __m512d or2 = mul(dot3(dx, dy, dz, dx, dy, dz), _mm512_set1_pd(0.25));
  // Acute: the circumcentre, (cross(n, u) lvv + cross(v, n) luu) (0.5 / n2).
  const __m512d h = _mm512_div_pd(half, n2);
  const __m512d qx = mul(add(mul(sub(mul(ny, uz), mul(nz, uy)), lvv), mul(sub(mul(vy, nz), mul(vz, ny)), luu)), h),
                qy = mul(add(mul(sub(mul(nz, ux), mul(nx, uz)), lvv), mul(sub(mul(vz, nx), mul(vx, nz)), luu)), h),
                qz = mul(add(mul(sub(mul(nx, uy), mul(ny, ux)), lvv), mul(sub(mul(vx, ny), mul(vy, nx)), luu)), h);
  const __m512d qr2 = dot3(qx, qy, qz, qx, qy, qz);
  alignas(64) double o[17][8];
  _mm512_store_pd(o[0], ax), _mm512_store_pd(o[1], ay), _mm512_store_pd(o[2], az);
  _mm512_store_pd(o[3], bx), _mm512_store_pd(o[4], by), _mm512_store_pd(o[5], bz);
  _mm512_store_pd(o[6], cx), _mm512_store_pd(o[7], cy), _mm512_store_pd(o[8], cz);
  _mm512_store_pd(o[9], _mm512_mask_blend_pd(obtuse, qx, ox));
  _mm512_store_pd(o[10], _mm512_mask_blend_pd(obtuse, qy, oy));
  _mm512_store_pd(o[11], _mm512_mask_blend_pd(obtuse, qz, oz));
  _mm512_store_pd(o[12], _mm512_mask_blend_pd(obtuse, qr2, or2));
  _mm512_store_pd(o[13], nx), _mm512_store_pd(o[14], ny), _mm512_store_pd(o[15], nz);
  _mm512_store_pd(o[16], _mm512_div_pd(_mm512_set1_pd(1.0), n2));
  for (int l = 0; l < count; ++l) {
    SmallestSphere& s = out[l];
    s.a = {o[0][l], o[1][l], o[2][l]};
    s.b = {o[3][l], o[4][l], o[5][l]};
    s.c = {o[6][l], o[7][l], o[8][l]};
    if ((degenerate >> l) & 1) {  // as the scalar function's: the corners, the rest default
      s.degenerate = true;
      s.obtuse = false;
      s.center_rel = Vec3{};
      s.r2 = 0;
      s.normal = Vec3{};
      s.inv_normal2 = 0;
      s.e0 = s.e1 = 0;
      continue;
    }
    s.degenerate = false;
    s.obtuse = (obtuse >> l) & 1;
    s.center_rel = {o[9][l], o[10][l], o[11][l]};
    s.r2 = o[12][l];
    s.normal = {o[13][l], o[14][l], o[15][l]};
    s.inv_normal2 = o[16][l];
    s.e0 = (at_a >> l) & 1;                        // 1 at a, else 0
    s.e1 = (obtuse >> l) & 1 ? ((at_c >> l) & 1 ? 1 : 2) : 0;  // 2 at a or b, 1 at c
  }
}
#endif

/// smallest_sphere(a, points[j[l]], points[k[l]]) into out[l] for l < count (1 to 8; j and k
/// hold eight indices, those past count any value): eight side by side where the processor has
/// AVX-512 (checked once at run time), else one at a time.
inline void smallest_spheres(const Vec3& a, const Vec3* points, const uint32_t* j, const uint32_t* k, int count,
                             SmallestSphere* out) {
#ifdef PM_HAVE_AVX512
  if (cpu_has_avx512()) {
    if (count > 0) smallest_spheres_avx512(a, points, j, k, count, out);
    return;
  }
#endif
  for (int l = 0; l < count; ++l) out[l] = smallest_sphere(a, points[j[l]], points[k[l]]);
}

/// Where q lies against the sphere: its squared distance from the centre less r^2 (negative
/// inside), as every test of the sphere takes it.
inline double sphere_gap(const SmallestSphere& s, const Vec3& q) { return squared_norm((q - s.a) - s.center_rel) - s.r2; }

#ifdef PM_HAVE_AVX512
/// sphere_gap() of eight points at a time (the triangle test's searches for a blocker), the
/// same arithmetic: the sphere broadcast once.
struct SphereGaps8 {
  __m512d ax, ay, az, cx, cy, cz, r2;

  PM_TARGET_AVX512 explicit SphereGaps8(const SmallestSphere& s)
      : ax(_mm512_set1_pd(s.a.x)), ay(_mm512_set1_pd(s.a.y)), az(_mm512_set1_pd(s.a.z)),
        cx(_mm512_set1_pd(s.center_rel.x)), cy(_mm512_set1_pd(s.center_rel.y)), cz(_mm512_set1_pd(s.center_rel.z)),
        r2(_mm512_set1_pd(s.r2)) {}
  /// (q - a) - centre, as Vec3 subtractions; its squared norm as dot() sums; less r^2.
  PM_TARGET_AVX512 __m512d operator()(__m512d x, __m512d y, __m512d z) const {
    using namespace sphere_lanes;
    const __m512d ex = sub(sub(x, ax), cx), ey = sub(sub(y, ay), cy), ez = sub(sub(z, az), cz);
    return sub(dot3(ex, ey, ez, ex, ey, ez), r2);
  }
  /// The first lane of `near` (not 0), its gap in *gap.
  PM_TARGET_AVX512 static int first(__mmask8 near, __m512d g, double* gap) {
    const int lane = __builtin_ctz(unsigned(near));
    alignas(64) double gs[8];
    _mm512_store_pd(gs, g);
    *gap = gs[lane];
    return lane;
  }
};
#endif

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

/// sphere_contains(), with the clear cases (a point clearly inside or outside: nearly all)
/// decided inline and only the tie zone's symbolic tie-break called.
inline bool sphere_contains_inline(const SmallestSphere& s, const Vec3& q, bool* tie) {
  const double d = sphere_gap(s, q);
  const double tol = kTieTolerance * s.r2;
  if (d < -tol) return true;
  if (d > tol) return false;
  return sphere_contains(s, q, tie);
}

}  // namespace particlemesh::detail
