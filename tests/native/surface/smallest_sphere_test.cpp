// The smallest enclosing sphere of three points (Tonnesen's test): its centre, radius and
// kind (circumsphere of an acute triangle, the longest edge's diametral sphere of an obtuse
// one, or degenerate), independent of the order the corners are given in.
#include "surface/smallest_sphere.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <bit>
#include <cstdint>
#include <random>
#include <vector>

using namespace particlemesh;
using detail::smallest_sphere;
using detail::SmallestSphere;

namespace {

void expect_vec_eq(const Vec3& a, const Vec3& b) {
  EXPECT_EQ(a.x, b.x);
  EXPECT_EQ(a.y, b.y);
  EXPECT_EQ(a.z, b.z);
}

// The same result, field for field and bit for bit, for all six orders of the corners.
SmallestSphere same_in_every_order(const Vec3& p, const Vec3& q, const Vec3& r) {
  std::array<int, 3> order{0, 1, 2};
  const Vec3 in[3] = {p, q, r};
  const SmallestSphere first = smallest_sphere(p, q, r);
  do {
    const SmallestSphere s = smallest_sphere(in[order[0]], in[order[1]], in[order[2]]);
    EXPECT_EQ(s.degenerate, first.degenerate);
    EXPECT_EQ(s.obtuse, first.obtuse);
    expect_vec_eq(s.a, first.a);
    expect_vec_eq(s.b, first.b);
    expect_vec_eq(s.c, first.c);
    if (first.degenerate) continue;
    expect_vec_eq(s.center_rel, first.center_rel);
    EXPECT_EQ(s.r2, first.r2);
    expect_vec_eq(s.normal, first.normal);
    EXPECT_EQ(s.inv_normal2, first.inv_normal2);
    EXPECT_EQ(s.e0, first.e0);
    EXPECT_EQ(s.e1, first.e1);
  } while (std::next_permutation(order.begin(), order.end()));
  return first;
}

void expect_center(const SmallestSphere& s, const Vec3& center, double r2) {
  const Vec3 c = s.a + s.center_rel;
  EXPECT_NEAR(c.x, center.x, 1e-12);
  EXPECT_NEAR(c.y, center.y, 1e-12);
  EXPECT_NEAR(c.z, center.z, 1e-12);
  EXPECT_NEAR(s.r2, r2, 1e-12);
}

}  // namespace

TEST(SmallestSphere, AcuteTriangleTakesItsCircumsphere) {
  // (0,0), (2,0), (1,2): the circumcentre (1, 3/4), radius^2 1 + 9/16.
  const SmallestSphere s = same_in_every_order({0, 0, 0}, {2, 0, 0}, {1, 2, 0});
  ASSERT_FALSE(s.degenerate);
  EXPECT_FALSE(s.obtuse);
  expect_center(s, {1, 0.75, 0}, 25.0 / 16.0);
  // The corners in rank (lexicographic) order, the normal (b - a) x (c - a) of that order.
  expect_vec_eq(s.a, {0, 0, 0});
  expect_vec_eq(s.b, {1, 2, 0});
  expect_vec_eq(s.c, {2, 0, 0});
  expect_vec_eq(s.normal, {0, 0, -4});
  EXPECT_EQ(s.inv_normal2, 1.0 / 16.0);
  EXPECT_TRUE(detail::sphere_contains(s, {1, 0.75, 0.5}));
  EXPECT_FALSE(detail::sphere_contains(s, {1, 0.75, 1.5}));
}

TEST(SmallestSphere, ObtuseTriangleTakesItsLongestEdgesDiametralSphere) {
  // The obtuse corner first in rank order: the diameter joins the other two (corners 1, 2).
  SmallestSphere s = same_in_every_order({0, 0, 0}, {1, 3, 0}, {1, -3, 0});
  ASSERT_TRUE(s.obtuse);
  EXPECT_EQ(s.e0, 1);
  EXPECT_EQ(s.e1, 2);
  expect_center(s, {1, 0, 0}, 9);
  // ... second: corners 0 and 2.
  s = same_in_every_order({0, 0, 0}, {1, 1, 0}, {4, 0, 0});
  ASSERT_TRUE(s.obtuse);
  EXPECT_EQ(s.e0, 0);
  EXPECT_EQ(s.e1, 2);
  expect_center(s, {2, 0, 0}, 4);
  // ... last: corners 0 and 1.
  s = same_in_every_order({5, 0, 0}, {4, 3, 0}, {4, -3, 0});
  ASSERT_TRUE(s.obtuse);
  EXPECT_EQ(s.e0, 0);
  EXPECT_EQ(s.e1, 1);
  expect_center(s, {4, 0, 0}, 9);
  // The diametral sphere holds the obtuse corner, and a point just beyond the diameter's end
  // is outside.
  EXPECT_TRUE(detail::sphere_contains(s, {4.5, 0, 0}));
  EXPECT_FALSE(detail::sphere_contains(s, {4, 3.01, 0}));
}

TEST(SmallestSphere, CollinearOrCoincidentCornersAreDegenerate) {
  EXPECT_TRUE(same_in_every_order({0, 0, 0}, {1, 1, 1}, {2, 2, 2}).degenerate);
  EXPECT_TRUE(same_in_every_order({0, 0, 0}, {0, 0, 0}, {1, 0, 0}).degenerate);
  const SmallestSphere s = same_in_every_order({3, 0, 0}, {1, 0, 0}, {2, 0, 0});
  ASSERT_TRUE(s.degenerate);
  expect_vec_eq(s.a, {1, 0, 0});  // the corners still in rank order
  expect_vec_eq(s.c, {3, 0, 0});
}

namespace {

bool same_bits(double x, double y) { return std::bit_cast<uint64_t>(x) == std::bit_cast<uint64_t>(y); }
bool same_bits(const Vec3& p, const Vec3& q) { return same_bits(p.x, q.x) && same_bits(p.y, q.y) && same_bits(p.z, q.z); }

}  // namespace

// The triangle test computes its triplets' spheres eight at a time (AVX-512, where the
// processor has it): every field, bit for bit, as one at a time, for every count of 1 to 8 and
// every kind of triplet: acute, obtuse at each rank, right-angled within the tolerance and
// just beyond it, collinear, coincident corners, corners that tie in x or in x and y (the rank
// order's later tests), -0 against +0, and lengths whose squares overflow.
TEST(SmallestSphere, EightAtATimeGiveTheBitsOfOneAtATime) {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::vector<Vec3> points;
  const auto add = [&](const Vec3& p) { points.push_back(p); };
  const Vec3 a{0.25, -0.5, 0.125};
  // Random triangles around a, at three scales.
  for (int i = 0; i < 300; ++i) {
    const double s = i % 3 == 0 ? 1e-6 : i % 3 == 1 ? 1.0 : 1e6;
    add(a + Vec3{u(rng), u(rng), u(rng)} * s);
  }
  // Right angles at a within and beyond the tolerance, obtuse and acute near 90 degrees.
  for (const double e : {0.0, 1e-12, -1e-12, 1e-9, -1e-9, 1e-8, -1e-8, 0.1, -0.1}) {
    add(a + Vec3{1, 0, 0});
    add(a + Vec3{e, 1, 0});
  }
  // Collinear and coincident corners; ties in x, in x and y; signed zeros.
  add(a), add(a), add(a + Vec3{1, 1, 1}), add(a + Vec3{2, 2, 2}), add(a + Vec3{-3, -3, -3});
  add({a.x, a.y + 1, a.z}), add({a.x, a.y - 1, a.z + 1}), add({a.x, a.y, a.z + 2}), add({a.x, a.y, a.z - 2});
  add({0.0, 0.0, 0.0}), add({-0.0, 1.0, 0.0}), add({0.0, -0.0, 1.0}), add({-0.0, -0.0, -0.0});
  // Squares that overflow to infinity.
  add({1e200, 0, 0}), add({0, 1e200, 0}), add({-1e200, 1e200, 1e200});
  const size_t m = points.size();
  std::vector<uint32_t> js, ks;
  for (uint32_t j = 0; j < m; ++j)
    for (uint32_t k = j + 1; k < m; k += 1 + uint32_t(rng() % 7)) js.push_back(j), ks.push_back(k);
  for (const Vec3& corner : {a, Vec3{-0.0, 0.0, 0.0}, Vec3{1e200, 1e200, 0}}) {
    size_t checked = 0;
    for (size_t first = 0; first < js.size();) {
      const int count = 1 + int(rng() % 8);
      uint32_t j[8] = {}, k[8] = {};
      for (int l = 0; l < count; ++l) j[l] = js[(first + l) % js.size()], k[l] = ks[(first + l) % js.size()];
      // Lanes past count: any index, even one past the points (never read).
      for (int l = count; l < 8; ++l) j[l] = k[l] = uint32_t(1u << 31);
      SmallestSphere batch[8];
      detail::smallest_spheres(corner, points.data(), j, k, count, batch);
      for (int l = 0; l < count; ++l) {
        const SmallestSphere one = smallest_sphere(corner, points[j[l]], points[k[l]]);
        const SmallestSphere& s = batch[l];
        ASSERT_EQ(s.degenerate, one.degenerate) << j[l] << " " << k[l];
        ASSERT_EQ(s.obtuse, one.obtuse) << j[l] << " " << k[l];
        EXPECT_TRUE(same_bits(s.a, one.a) && same_bits(s.b, one.b) && same_bits(s.c, one.c)) << j[l] << " " << k[l];
        EXPECT_TRUE(same_bits(s.center_rel, one.center_rel)) << j[l] << " " << k[l];
        EXPECT_TRUE(same_bits(s.r2, one.r2)) << j[l] << " " << k[l];
        EXPECT_TRUE(same_bits(s.normal, one.normal)) << j[l] << " " << k[l];
        EXPECT_TRUE(same_bits(s.inv_normal2, one.inv_normal2)) << j[l] << " " << k[l];
        EXPECT_EQ(s.e0, one.e0);
        EXPECT_EQ(s.e1, one.e1);
        ++checked;
      }
      first += size_t(count);
    }
    EXPECT_GE(checked, js.size());
  }
}
