// The smallest enclosing sphere of three points (Tonnesen's test): its centre, radius and
// kind (circumsphere of an acute triangle, the longest edge's diametral sphere of an obtuse
// one, or degenerate), independent of the order the corners are given in.
#include "surface/smallest_sphere.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>

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
