#include "core/select_within.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

namespace pm = particlemesh;

// The neighbour searches' filter: the vector path (AVX-512, where the processor has it) keeps
// the same positions or values, in the same order, as the scalar loop and as the plain test,
// for every length around the vectors' 8 and 16 (the tails' masks); with distances at and
// around the bounds, zero (the point itself), negative zero, NaN and infinite ones; with an
// infinite and a zero upper bound, a lower bound of 0 (the k nearest: not the point itself)
// and of -inf (the neighbour lists), and with values, one of which is excluded.
TEST(SelectWithin, KeepsWhatTheScalarLoopKeeps) {
  std::mt19937_64 rng(21);
  const double specials[] = {0.0, -0.0, 1.0, std::nextafter(1.0, 2.0), std::nextafter(1.0, 0.0), NAN, INFINITY, -1.0};
  for (size_t m = 0; m <= 70; ++m)
    for (int trial = 0; trial < 20; ++trial) {
      std::vector<double> d(m);
      std::vector<uint32_t> values(m);
      for (size_t i = 0; i < m; ++i) {
        d[i] = rng() % 3 == 0 ? specials[rng() % 8] : std::uniform_real_distribution<double>(0.0, 2.0)(rng);
        values[i] = uint32_t(rng() % 8);
      }
      for (const double low : {0.0, -double(INFINITY)})
        for (const double high : {1.0, double(INFINITY), 0.0})
          for (const bool with_values : {false, true}) {
            const uint32_t* v = with_values ? values.data() : nullptr;
            std::vector<uint32_t> a(m + 16, 99), b(m + 16, 99), expected;
            const size_t na = pm::detail::select_within(d.data(), m, low, high, v, 3, a.data());
            const size_t nb = pm::detail::select_within_scalar(d.data(), m, low, high, v, 3, b.data());
            for (size_t i = 0; i < m; ++i)
              if (d[i] > low && d[i] <= high && (!with_values || values[i] != 3))
                expected.push_back(with_values ? values[i] : uint32_t(i));
            ASSERT_EQ(na, expected.size()) << m << " " << low << " " << high << " " << with_values;
            ASSERT_EQ(nb, expected.size());
            for (size_t i = 0; i < na; ++i) {
              ASSERT_EQ(a[i], expected[i]) << m << " " << i;
              ASSERT_EQ(b[i], expected[i]) << m << " " << i;
            }
          }
    }
}
