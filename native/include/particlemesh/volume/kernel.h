// Field kernels of volume particles (thesis chapter 5, section 5.1.1): the profile g that
// each particle's field follows as a function of distance, falling monotonically from 1 at the
// centre to 0 at the particle's radius R.
//
// Every kernel here is written as a function of the *squared* normalised distance
//
//     s = |x - p|^2 / R^2        (0 <= s; the support is s < 1, g = 0 for s >= 1)
//
// because that is what is cheap to compute (no square root), because a function of r^2 is
// smooth at the particle centre, and because along a ray x(t) = o + t d, s is a quadratic in
// t: a kernel that is a polynomial of degree k in s is a polynomial of degree 2k in t on every
// interval where a fixed set of particles contributes (the ray casting of section 5.1.3).
//
//   kernel  g(s) on 0 <= s < 1                          as a polynomial in s         at r = R
//   Wyvill  1 - 22/9 s + 17/9 s^2 - 4/9 s^3             degree 3 (degree 6 in r)     C1
//           (= (1-s)^2 (5 + 4(1-s)) / 9; Wyvill, McPheeters and Wyvill 1986, "soft objects")
//   Poly4   (1 - s)^2                                   degree 2 (degree 4 in r)     C1
//   Poly6   (1 - s)^3                                   degree 3 (degree 6 in r)     C2
//   Blinn   (exp(-k s) - eps) / (1 - eps),  eps = 1e-3, k = ln(1/eps)                C0
//           Blinn's (1982) exponential blob, truncated where it has fallen to eps = 1e-3
//           of its peak and shifted down by eps so that it still reaches 0 continuously
//           (its slope dg/ds jumps by k eps / (1 - eps) ~ 0.0069 at R, 1e-3 of its largest
//           value). Not a polynomial: ray casting needs an iterative solver for it.
//
// "Continuity at r = R" is that of the field as a function of position across the edge of
// the support; inside the support every kernel is C-infinity. All are 1 at s = 0, strictly
// decreasing on [0, 1) and exactly 0 for s >= 1.
#pragma once

#include "particlemesh/core/config.h"

#include <array>
#include <cmath>
#include <cstdint>
#include <string_view>

#include "particlemesh/core/error.h"
#include "particlemesh/core/export.h"

namespace PM_NAMESPACE {

/// The kernels. The numeric values are those of PM_KERNEL_* in the C ABI and never change.
enum class Kernel : int32_t {
  Wyvill = 0,  ///< 1 - 22/9 s + 17/9 s^2 - 4/9 s^3, C1 at R (the default)
  Poly4 = 1,   ///< (1 - s)^2, C1 at R
  Poly6 = 2,   ///< (1 - s)^3, C2 at R
  Blinn = 3,   ///< exponential truncated at kBlinnTolerance, C0 at R
};

/// Blinn's exponential is cut where exp(-k s) has fallen to this fraction of its peak.
inline constexpr double kBlinnTolerance = 1e-3;
/// k = ln(1 / kBlinnTolerance).
inline constexpr double kBlinnExponent = 6.907755278982137;

/// The largest degree in s of a polynomial kernel.
inline constexpr int kKernelMaxDegree = 3;

/// A polynomial kernel as g(s) = c[0] + c[1] s + c[2] s^2 + c[3] s^3 on 0 <= s < 1 (and 0 for
/// s >= 1). Coefficients above `degree` are zero.
struct KernelPolynomial {
  int degree = 0;
  std::array<double, kKernelMaxDegree + 1> c{};
};

/// True for the kernels that are polynomials in s (all but Blinn).
constexpr bool kernel_is_polynomial(Kernel kernel) { return kernel != Kernel::Blinn; }

/// Order of continuity of the field at the edge of the support (r = R): 1 means C1.
constexpr int kernel_continuity(Kernel kernel) {
  switch (kernel) {
    case Kernel::Wyvill: return 1;
    case Kernel::Poly4: return 1;
    case Kernel::Poly6: return 2;
    case Kernel::Blinn: return 0;
  }
  return 0;
}

/// The coefficients in s of a polynomial kernel.
/// @throws Error(InvalidArgument) for Blinn, which is not a polynomial.
inline KernelPolynomial kernel_polynomial(Kernel kernel) {
  switch (kernel) {
    case Kernel::Wyvill: return {3, {1.0, -22.0 / 9.0, 17.0 / 9.0, -4.0 / 9.0}};
    case Kernel::Poly4: return {2, {1.0, -2.0, 1.0, 0.0}};
    case Kernel::Poly6: return {3, {1.0, -3.0, 3.0, -1.0}};
    case Kernel::Blinn: break;
  }
  throw Error(Status::InvalidArgument, "the Blinn kernel is not a polynomial");
}

/// g(s) for s = |x - p|^2 / R^2: 1 at s = 0, strictly decreasing, exactly 0 for s >= 1.
/// (The polynomial kernels are evaluated in t = 1 - s, which makes g(1) exactly 0.)
inline double kernel_value(Kernel kernel, double s) {
  if (!(s < 1.0)) return 0.0;
  const double t = 1.0 - s;
  switch (kernel) {
    case Kernel::Wyvill: return t * t * (5.0 + 4.0 * t) * (1.0 / 9.0);
    case Kernel::Poly4: return t * t;
    case Kernel::Poly6: return t * t * t;
    case Kernel::Blinn: {
      const double v = (std::exp(-kBlinnExponent * s) - kBlinnTolerance) / (1.0 - kBlinnTolerance);
      return v > 0.0 ? v : 0.0;
    }
  }
  return 0.0;
}

/// dg/ds (<= 0). 0 for s >= 1; for Blinn, the one-sided derivative inside the support.
/// The gradient of a particle's field in space is  2 g'(s) (x - p) / R^2.
inline double kernel_derivative(Kernel kernel, double s) {
  if (!(s < 1.0)) return 0.0;
  const double t = 1.0 - s;
  switch (kernel) {
    case Kernel::Wyvill: return -t * (10.0 + 12.0 * t) * (1.0 / 9.0);
    case Kernel::Poly4: return -2.0 * t;
    case Kernel::Poly6: return -3.0 * t * t;
    case Kernel::Blinn:
      return -kBlinnExponent * std::exp(-kBlinnExponent * s) / (1.0 - kBlinnTolerance);
  }
  return 0.0;
}

/// The s in [0, 1] at which g(s) = value, for value in [0, 1] (g is strictly decreasing):
/// a single particle of strength w and radius R has its iso-surface at threshold T on the
/// sphere of radius R * sqrt(kernel_inverse(kernel, T / w)). Closed form for Poly4, Poly6 and
/// Blinn; Newton's method with a bisection safeguard (to 1e-15) for Wyvill.
/// @throws Error(InvalidArgument) if value is not in [0, 1].
PM_EXPORT double kernel_inverse(Kernel kernel, double value);

/// "wyvill", "poly4", "poly6", "blinn".
PM_EXPORT const char* kernel_name(Kernel kernel);

/// Parse a kernel name (as kernel_name writes it, case-insensitive).
/// @throws Error(InvalidArgument) naming the accepted names.
PM_EXPORT Kernel kernel_from_name(std::string_view name);

/// Check that `kernel` holds one of the four enumerators (values coming from C or files).
/// @throws Error(InvalidArgument) otherwise.
PM_EXPORT void validate_kernel(Kernel kernel);

}  // namespace particlemesh
