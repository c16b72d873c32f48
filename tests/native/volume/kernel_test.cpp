// The kernels: the formulas the header states, their support, monotonicity, derivatives,
// continuity at R, the polynomial coefficients in s (for ray casting) and the inverse.
#include "particlemesh/volume/kernel.h"

#include <gtest/gtest.h>

#include <cmath>

#include "particlemesh/core/error.h"

using namespace particlemesh;

namespace {
const Kernel kAll[] = {Kernel::Wyvill, Kernel::Poly4, Kernel::Poly6, Kernel::Blinn};
}

TEST(Kernel, StatedFormulas) {
  for (double s : {0.0, 0.1, 0.25, 0.5, 0.77, 0.99}) {
    EXPECT_NEAR(kernel_value(Kernel::Wyvill, s), 1 - 22.0 / 9 * s + 17.0 / 9 * s * s - 4.0 / 9 * s * s * s, 1e-15);
    EXPECT_NEAR(kernel_value(Kernel::Poly4, s), (1 - s) * (1 - s), 1e-15);
    EXPECT_NEAR(kernel_value(Kernel::Poly6, s), (1 - s) * (1 - s) * (1 - s), 1e-15);
    const double eps = kBlinnTolerance;
    EXPECT_NEAR(kernel_value(Kernel::Blinn, s), (std::exp(-std::log(1 / eps) * s) - eps) / (1 - eps), 1e-15);
  }
  EXPECT_NEAR(kBlinnExponent, std::log(1.0 / kBlinnTolerance), 1e-15);
}

TEST(Kernel, OneAtCentreZeroFromTheRadiusOn) {
  for (Kernel k : kAll) {
    SCOPED_TRACE(kernel_name(k));
    EXPECT_DOUBLE_EQ(kernel_value(k, 0.0), 1.0);
    EXPECT_EQ(kernel_value(k, 1.0), 0.0);  // exactly
    EXPECT_EQ(kernel_value(k, 1.5), 0.0);
    EXPECT_EQ(kernel_value(k, 1e300), 0.0);
    EXPECT_EQ(kernel_derivative(k, 1.0), 0.0);
    EXPECT_EQ(kernel_derivative(k, 2.0), 0.0);
    EXPECT_GE(kernel_value(k, 1.0 - 1e-12), 0.0);
  }
}

TEST(Kernel, StrictlyDecreasingInsideTheSupport) {
  for (Kernel k : kAll) {
    double prev = kernel_value(k, 0.0);
    for (int i = 1; i < 1000; ++i) {
      const double v = kernel_value(k, i / 1000.0);
      ASSERT_LT(v, prev) << kernel_name(k) << " at s = " << i / 1000.0;
      ASSERT_LT(kernel_derivative(k, i / 1000.0), 0.0) << kernel_name(k);
      prev = v;
    }
  }
}

TEST(Kernel, DerivativeMatchesFiniteDifferences) {
  for (Kernel k : kAll)
    for (double s : {0.01, 0.2, 0.5, 0.8, 0.97}) {
      const double d = 1e-6;
      const double fd = (kernel_value(k, s + d) - kernel_value(k, s - d)) / (2 * d);
      EXPECT_NEAR(kernel_derivative(k, s), fd, 1e-7 * std::max(1.0, std::abs(fd))) << kernel_name(k) << " s=" << s;
    }
}

// Continuity across r = R of g as a function of r (s = r^2): C1 needs dg/dr -> 0, i.e.
// g'(s) -> 0; C2 also needs d2g/dr2 = 2 g'(s) + 4 s g''(s) -> 0, i.e. g''(s) -> 0.
TEST(Kernel, ContinuityAtTheRadiusIsAsStated) {
  auto g2 = [](Kernel k, double s) {
    const double d = 1e-5;
    return (kernel_derivative(k, s + d) - kernel_derivative(k, s - d)) / (2 * d);
  };
  const double just_inside = 1.0 - 1e-9;
  for (Kernel k : kAll) {
    SCOPED_TRACE(kernel_name(k));
    const int c = kernel_continuity(k);
    EXPECT_NEAR(kernel_value(k, just_inside), 0.0, 1e-8);  // C0 for all
    if (c >= 1) {
      EXPECT_NEAR(kernel_derivative(k, just_inside), 0.0, 1e-7);
    } else {
      EXPECT_GT(std::abs(kernel_derivative(k, just_inside)), 1e-3);  // a kink, as documented
    }
    if (c >= 2) {
      EXPECT_NEAR(g2(k, 1.0 - 1e-4), 0.0, 1e-3);
    } else if (c == 1) {
      EXPECT_GT(std::abs(g2(k, 1.0 - 1e-4)), 0.1);  // not C2
    }
  }
  EXPECT_EQ(kernel_continuity(Kernel::Wyvill), 1);
  EXPECT_EQ(kernel_continuity(Kernel::Poly4), 1);
  EXPECT_EQ(kernel_continuity(Kernel::Poly6), 2);
  EXPECT_EQ(kernel_continuity(Kernel::Blinn), 0);
  // Blinn's slope jump at R is k eps / (1 - eps), as the header says.
  EXPECT_NEAR(-kernel_derivative(Kernel::Blinn, just_inside),
              kBlinnExponent * kBlinnTolerance / (1 - kBlinnTolerance), 1e-9);
}

TEST(Kernel, PolynomialCoefficientsReproduceTheKernel) {
  for (Kernel k : {Kernel::Wyvill, Kernel::Poly4, Kernel::Poly6}) {
    ASSERT_TRUE(kernel_is_polynomial(k));
    const KernelPolynomial p = kernel_polynomial(k);
    EXPECT_EQ(p.degree, k == Kernel::Poly4 ? 2 : 3);
    for (int d = p.degree + 1; d <= kKernelMaxDegree; ++d) EXPECT_EQ(p.c[size_t(d)], 0.0);
    for (double s = 0; s < 1; s += 0.03125) {
      double v = 0;
      for (int d = p.degree; d >= 0; --d) v = v * s + p.c[size_t(d)];
      EXPECT_NEAR(v, kernel_value(k, s), 1e-14) << kernel_name(k) << " s=" << s;
    }
  }
  EXPECT_FALSE(kernel_is_polynomial(Kernel::Blinn));
  EXPECT_THROW(kernel_polynomial(Kernel::Blinn), Error);
}

TEST(Kernel, InverseRoundTrips) {
  for (Kernel k : kAll)
    for (double v : {1e-6, 0.01, 0.3, 0.5, 0.75, 0.999999}) {
      const double s = kernel_inverse(k, v);
      ASSERT_GE(s, 0.0);
      ASSERT_LE(s, 1.0);
      EXPECT_NEAR(kernel_value(k, s), v, 1e-12) << kernel_name(k) << " v=" << v;
    }
  for (Kernel k : kAll) {
    EXPECT_EQ(kernel_inverse(k, 1.0), 0.0);
    EXPECT_EQ(kernel_inverse(k, 0.0), 1.0);
    EXPECT_THROW(kernel_inverse(k, 1.5), Error);
    EXPECT_THROW(kernel_inverse(k, -0.1), Error);
    EXPECT_THROW(kernel_inverse(k, std::nan("")), Error);
  }
  // Wyvill's classic value: g(1/2) at r = R/2 ... and its inverse.
  EXPECT_NEAR(kernel_inverse(Kernel::Wyvill, kernel_value(Kernel::Wyvill, 0.25)), 0.25, 1e-14);
}

TEST(Kernel, NamesParseAndBadValuesAreRejected) {
  for (Kernel k : kAll) EXPECT_EQ(kernel_from_name(kernel_name(k)), k);
  EXPECT_EQ(kernel_from_name("POLY6"), Kernel::Poly6);
  try {
    kernel_from_name("gauss");
    FAIL();
  } catch (const Error& e) {
    EXPECT_EQ(e.status(), Status::InvalidArgument);
    EXPECT_NE(std::string(e.what()).find("wyvill"), std::string::npos);
  }
  EXPECT_NO_THROW(validate_kernel(Kernel::Blinn));
  EXPECT_THROW(validate_kernel(static_cast<Kernel>(4)), Error);
  EXPECT_THROW(validate_kernel(static_cast<Kernel>(-1)), Error);
  EXPECT_EQ(int(Kernel::Wyvill), 0);
  EXPECT_EQ(int(Kernel::Poly4), 1);
  EXPECT_EQ(int(Kernel::Poly6), 2);
  EXPECT_EQ(int(Kernel::Blinn), 3);
}
