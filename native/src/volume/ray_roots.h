// Internal: the crossings of a polynomial p(u) = c[0] + c[1] u + ... + c[n] u^n (n <= 6) on
// the unit interval 0 <= u <= 1, as the ray caster needs them (raycast.h): every place where
// the state "p >= 0" changes, in increasing u, each polished to full double precision, plus
// the magnitudes of p sampled between them (the caster's tangent rule uses those).
//
// Two solvers, the two that exact ray casting of implicit surfaces calls for (Tonnesen's
// thesis, section 5.1.3, cites ray casting of blobs):
//  - closed form (degree <= 4): Ferrari's quartic through the resolvent cubic (Cardano or
//    the trigonometric form), the candidates then used as sample points: between two
//    neighbouring samples whose states differ lies exactly one crossing of the candidates'
//    pieces, polished by safeguarded Newton in that bracket. A candidate whose two sides
//    have the same state (a double root) is no crossing.
//  - Bernstein / Descartes subdivision (any degree <= 6): p in the Bernstein basis on the
//    interval; the number V of sign changes of its coefficients bounds the number of roots
//    and has their parity (Descartes' rule of signs), V = 0 means no root and V = 1 exactly
//    one; otherwise the interval is halved (de Casteljau) until every piece has V <= 1 or is
//    narrower than kMinWidth (then the end states decide: one crossing or none). Certified:
//    no crossing wider apart than kMinWidth is missed, none is reported twice.
// Hand-written because no library of Debian's gives root isolation of small polynomials on
// an interval with this contract (GSL's gsl_poly_complex_solve finds complex roots of the
// whole line through a companion matrix, far slower and with no certification).
#pragma once

#include "particlemesh/core/config.h"

#include <cstddef>

namespace PM_NAMESPACE::detail {

inline constexpr int kMaxPolyDegree = 6;
inline constexpr int kMaxCrossings = 8;
/// Pieces narrower than this (in u) are not subdivided further by the Bernstein solver.
inline constexpr double kMinWidth = 1e-12;

struct PolyCrossing {
  double u = 0;    ///< where p changes state, 0 < u < 1 (or at an end, to rounding)
  double gap = 0;  ///< max |p| sampled between the previous crossing (or u = 0) and this one
};

struct IntervalCrossings {
  int count = 0;
  PolyCrossing c[kMaxCrossings];
  bool start_inside = false;  ///< p(0) >= 0
  bool end_inside = false;    ///< p(1) >= 0 (count is odd iff start_inside != end_inside)
  double tail = 0;            ///< max |p| sampled after the last crossing (p(1) included)
};

/// p(u) by Horner.
inline double poly_eval(const double* c, int n, double u) {
  double v = c[n];
  for (int j = n - 1; j >= 0; --j) v = v * u + c[j];
  return v;
}

/// Real roots of c0 + c1 x + c2 x^2 (+ c3 x^3 (+ c4 x^4)) on the whole line, unsorted, by
/// closed form (each polished by two Newton steps). Returns how many were written (<= n).
/// Leading coefficients that are zero (or negligible) lower the degree.
int solve_quadratic(const double* c, double* roots);
int solve_cubic(const double* c, double* roots);
int solve_quartic(const double* c, double* roots);

/// Crossings of p on [0, 1] through the closed-form roots (n <= 4).
void crossings_closed_form(const double* c, int n, IntervalCrossings* out);
/// Crossings of p on [0, 1] by Bernstein subdivision (n <= 6).
void crossings_bernstein(const double* c, int n, IntervalCrossings* out);

/// Power-basis coefficients on [0, 1] to Bernstein coefficients of degree n.
void power_to_bernstein(const double* c, int n, double* b);

}  // namespace particlemesh::detail
