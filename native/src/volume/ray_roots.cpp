#include "volume/ray_roots.h"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace PM_NAMESPACE::detail {

namespace {

// Newton's method for the polynomial, two steps, from x (polishes closed-form roots, whose
// rounding grows with the coefficients' spread).
double newton2(const double* c, int n, double x) {
  for (int it = 0; it < 2; ++it) {
    double p = c[n], dp = 0;
    for (int j = n - 1; j >= 0; --j) {
      dp = dp * x + p;
      p = p * x + c[j];
    }
    if (dp == 0 || !std::isfinite(p / dp)) break;
    x -= p / dp;
  }
  return x;
}

// The degree once negligible leading coefficients are dropped.
int effective_degree(const double* c, int n) {
  double big = 0;
  for (int j = 0; j <= n; ++j) big = std::max(big, std::abs(c[j]));
  while (n > 0 && std::abs(c[n]) <= 1e-14 * big) --n;
  return n;
}

// Solve a monic or general quadratic a x^2 + b x + c without cancellation.
int quadratic_roots(double a, double b, double c, double* r) {
  if (a == 0) {
    if (b == 0) return 0;
    r[0] = -c / b;
    return 1;
  }
  const double disc = b * b - 4 * a * c;
  if (disc < 0) return 0;
  if (disc == 0) {
    r[0] = -b / (2 * a);
    return 1;
  }
  const double q = -0.5 * (b + std::copysign(std::sqrt(disc), b));
  r[0] = q / a;
  r[1] = q != 0 ? c / q : -r[0];
  return 2;
}

// Polish the crossing inside [lo, hi], where the state (p >= 0) at lo is lo_inside and at hi
// is not: safeguarded Newton (Newton when it stays inside the bracket and shrinks it fast
// enough, bisection otherwise; "rtsafe"), to the last bits of u.
double polish(const double* c, int n, double lo, double hi, bool lo_inside) {
  double x = 0.5 * (lo + hi);
  double dx_old = hi - lo, dx = dx_old;
  for (int it = 0; it < 200; ++it) {
    double p = c[n], dp = 0;
    for (int j = n - 1; j >= 0; --j) {
      dp = dp * x + p;
      p = p * x + c[j];
    }
    if ((p >= 0) == lo_inside) lo = x;
    else hi = x;
    if (hi - lo <= 4e-16 * std::max(1.0, std::abs(x))) break;
    const double newton = dp != 0 ? x - p / dp : lo - 1.0;
    if (!(newton > lo && newton < hi) || std::abs(2.0 * p) > std::abs(dx_old * dp)) {
      dx_old = dx;
      dx = 0.5 * (hi - lo);
      x = lo + dx;
    } else {
      dx_old = dx;
      dx = newton - x;
      x = newton;
      if (std::abs(dx) <= 1e-17 * std::max(1.0, std::abs(x))) break;
    }
  }
  return x;
}

constexpr double kBinomial[kMaxPolyDegree + 1][kMaxPolyDegree + 1] = {
    {1, 0, 0, 0, 0, 0, 0},  {1, 1, 0, 0, 0, 0, 0},   {1, 2, 1, 0, 0, 0, 0},    {1, 3, 3, 1, 0, 0, 0},
    {1, 4, 6, 4, 1, 0, 0},  {1, 5, 10, 10, 5, 1, 0}, {1, 6, 15, 20, 15, 6, 1},
};

// Sign changes of the state (b >= 0) along the coefficients.
int variations(const double* b, int n) {
  int v = 0;
  bool s = b[0] >= 0;
  for (int k = 1; k <= n; ++k) {
    const bool t = b[k] >= 0;
    v += t != s;
    s = t;
  }
  return v;
}

struct Bracket {
  double lo, hi;
  bool lo_inside;
};

void isolate(const double* b, int n, double u0, double u1, int depth, Bracket* out, int* count) {
  if (*count >= kMaxCrossings) return;
  const int v = variations(b, n);
  if (v == 0) return;
  const bool s0 = b[0] >= 0, s1 = b[n] >= 0;
  if (v == 1 || u1 - u0 < kMinWidth || depth > 60) {
    // V = 1: exactly one root inside. A piece below the resolution: its end states decide
    // (an even number of crossings that close together is a touch: none).
    if (s0 != s1) out[(*count)++] = {u0, u1, s0};
    return;
  }
  double left[kMaxPolyDegree + 1], right[kMaxPolyDegree + 1], tmp[kMaxPolyDegree + 1];
  std::copy(b, b + n + 1, tmp);
  left[0] = b[0];
  right[n] = b[n];
  for (int r = 1; r <= n; ++r) {
    for (int k = 0; k <= n - r; ++k) tmp[k] = 0.5 * (tmp[k] + tmp[k + 1]);
    left[r] = tmp[0];
    right[n - r] = tmp[n - r];
  }
  const double um = 0.5 * (u0 + u1);
  isolate(left, n, u0, um, depth + 1, out, count);
  isolate(right, n, um, u1, depth + 1, out, count);
}

// Fill `out` from polished crossing positions (sorted), with the sampled magnitudes.
void finish(const double* c, int n, const double* u, int m, IntervalCrossings* out) {
  const double p0 = c[0], p1 = poly_eval(c, n, 1.0);
  out->start_inside = p0 >= 0;
  out->end_inside = p1 >= 0;
  out->count = m;
  double prev = 0, height = std::abs(p0);
  for (int k = 0; k < m; ++k) {
    out->c[k].u = u[k];
    out->c[k].gap = std::max(height, std::abs(poly_eval(c, n, 0.5 * (prev + u[k]))));
    prev = u[k];
    height = 0;
  }
  out->tail = m == 0 ? std::max(std::abs(p0), std::abs(p1))
                     : std::max(std::abs(p1), std::abs(poly_eval(c, n, 0.5 * (prev + 1.0))));
}

}  // namespace

int solve_quadratic(const double* c, double* roots) {
  const int n = effective_degree(c, 2);
  if (n == 0) return 0;
  return quadratic_roots(n == 2 ? c[2] : 0.0, c[1], c[0], roots);
}

int solve_cubic(const double* c, double* roots) {
  const int n = effective_degree(c, 3);
  if (n < 3) return solve_quadratic(c, roots);
  // x = y - B/3 turns x^3 + B x^2 + C x + D into y^3 + p y + q.
  const double B = c[2] / c[3], C = c[1] / c[3], D = c[0] / c[3];
  const double shift = B / 3.0;
  const double p = C - B * B / 3.0;
  const double q = 2.0 * B * B * B / 27.0 - B * C / 3.0 + D;
  const double half_q = 0.5 * q, third_p = p / 3.0;
  const double disc = half_q * half_q + third_p * third_p * third_p;
  int m = 0;
  if (disc > 0) {
    // One real root (Cardano), written without cancellation.
    const double a = -std::cbrt(half_q + std::copysign(std::sqrt(disc), half_q));
    const double y = a != 0 ? a - third_p / a : 0.0;
    roots[m++] = y - shift;
  } else {
    // Three real roots (trigonometric form).
    const double r = std::sqrt(std::max(0.0, -third_p));
    if (r == 0) {
      roots[m++] = -shift;
    } else {
      const double cosv = std::clamp(-half_q / (r * r * r), -1.0, 1.0);
      const double phi = std::acos(cosv) / 3.0;
      for (int k = 0; k < 3; ++k) roots[m++] = 2.0 * r * std::cos(phi - 2.0 * std::numbers::pi * k / 3.0) - shift;
    }
  }
  for (int k = 0; k < m; ++k) roots[k] = newton2(c, 3, roots[k]);
  return m;
}

int solve_quartic(const double* c, double* roots) {
  const int n = effective_degree(c, 4);
  if (n < 4) return solve_cubic(c, roots);
  // Ferrari: x = y - B/4 gives y^4 + p y^2 + q y + r; with m > 0 a root of the resolvent
  // cubic m^3 + p m^2 + (p^2/4 - r) m - q^2/8, it factors into
  //   (y^2 - sqrt(2m) y + p/2 + m + q / (2 sqrt(2m))) (y^2 + sqrt(2m) y + p/2 + m - q / (2 sqrt(2m))).
  const double B = c[3] / c[4], C = c[2] / c[4], D = c[1] / c[4], E = c[0] / c[4];
  const double shift = B / 4.0, B2 = B * B;
  const double p = C - 3.0 * B2 / 8.0;
  const double q = D - B * C / 2.0 + B2 * B / 8.0;
  const double r = E - B * D / 4.0 + B2 * C / 16.0 - 3.0 * B2 * B2 / 256.0;
  int m = 0;
  const double scale = std::max({std::abs(p), std::sqrt(std::abs(r)), std::cbrt(std::abs(q)), 1e-300});
  if (std::abs(q) <= 1e-14 * scale * scale * scale) {
    // Biquadratic: y^2 = z with z^2 + p z + r = 0.
    double z[2];
    const int nz = quadratic_roots(1.0, p, r, z);
    for (int k = 0; k < nz; ++k) {
      if (z[k] < 0) continue;
      const double y = std::sqrt(z[k]);
      roots[m++] = y - shift;
      if (y > 0) roots[m++] = -y - shift;
    }
  } else {
    const double res[4] = {-q * q / 8.0, p * p / 4.0 - r, p, 1.0};
    double ms[3];
    const int nm = solve_cubic(res, ms);
    double mm = 0;
    for (int k = 0; k < nm; ++k) mm = std::max(mm, ms[k]);
    if (mm <= 0) return 0;  // only from rounding of a degenerate case
    const double s = std::sqrt(2.0 * mm);
    const double t = q / (2.0 * s);
    double y[2];
    int ny = quadratic_roots(1.0, -s, 0.5 * p + mm + t, y);
    for (int k = 0; k < ny; ++k) roots[m++] = y[k] - shift;
    ny = quadratic_roots(1.0, s, 0.5 * p + mm - t, y);
    for (int k = 0; k < ny; ++k) roots[m++] = y[k] - shift;
  }
  for (int k = 0; k < m; ++k) roots[k] = newton2(c, 4, roots[k]);
  return m;
}

void power_to_bernstein(const double* c, int n, double* b) {
  for (int k = 0; k <= n; ++k) {
    double v = 0;
    for (int j = 0; j <= k; ++j) v += kBinomial[k][j] / kBinomial[n][j] * c[j];
    b[k] = v;
  }
}

void crossings_closed_form(const double* c, int n, IntervalCrossings* out) {
  double cand[4] = {};
  int nc = 0;
  double pc[5] = {0, 0, 0, 0, 0};
  std::copy(c, c + n + 1, pc);
  if (n >= 1) nc = n <= 2 ? solve_quadratic(pc, cand) : (n == 3 ? solve_cubic(pc, cand) : solve_quartic(pc, cand));
  double inner[4];
  int ni = 0;
  for (int k = 0; k < nc; ++k)
    if (cand[k] > 0 && cand[k] < 1) inner[ni++] = cand[k];
  for (int k = 1; k < ni; ++k)  // (at most 4: insertion sort)
    for (int j = k; j > 0 && inner[j] < inner[j - 1]; --j) std::swap(inner[j], inner[j - 1]);
  // Samples: 0, the middle of every piece between candidates, 1. A crossing lies between
  // neighbouring samples of different states (and only there).
  double x[8];  // 0, up to 4 + 1 piece middles, 1
  int nx = 0;
  x[nx++] = 0.0;
  double prev = 0.0;
  for (int k = 0; k < ni; ++k) {
    if (inner[k] - prev > 0) x[nx++] = 0.5 * (prev + inner[k]);
    prev = inner[k];
  }
  if (1.0 - prev > 0 && ni > 0) x[nx++] = 0.5 * (prev + 1.0);
  x[nx++] = 1.0;
  double u[kMaxCrossings];
  int m = 0;
  bool s = c[0] >= 0;
  for (int k = 1; k < nx; ++k) {
    const bool t = poly_eval(c, n, x[k]) >= 0;
    if (t != s) u[m++] = polish(c, n, x[k - 1], x[k], s);
    s = t;
  }
  finish(c, n, u, m, out);
}

void crossings_bernstein(const double* c, int n, IntervalCrossings* out) {
  double b[kMaxPolyDegree + 1];
  power_to_bernstein(c, n, b);
  // Ends exactly as the sweep sees them (Horner), so the states chain from piece to piece.
  b[0] = c[0];
  b[n] = poly_eval(c, n, 1.0);
  Bracket br[kMaxCrossings];
  int nb = 0;
  isolate(b, n, 0.0, 1.0, 0, br, &nb);
  double u[kMaxCrossings];
  for (int k = 0; k < nb; ++k) u[k] = polish(c, n, br[k].lo, br[k].hi, br[k].lo_inside);
  finish(c, n, u, nb, out);
}

}  // namespace particlemesh::detail
