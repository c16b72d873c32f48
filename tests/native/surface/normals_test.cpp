#include "particlemesh/surface/normals.h"

#include <gtest/gtest.h>

#include <cmath>

#include "particlemesh/core/error.h"
#include "particlemesh/sample/shapes.h"
#include "support/test_support.h"

using namespace particlemesh;

TEST(EstimateNormals, SphereNormalsAreRadialAndOutward) {
  PointCloud c = fibonacci_sphere(20000, 2.0, {1, -2, 3});
  c.normals.clear();
  const std::vector<Vec3> n = estimate_normals(c);
  ASSERT_EQ(n.size(), c.size());
  for (size_t i = 0; i < c.size(); ++i) {
    const Vec3 radial = normalized(c.positions[i] - Vec3{1, -2, 3});
    ASSERT_GT(dot(n[i], radial), 0.995) << i;
  }
}

TEST(EstimateNormals, TorusAndDoubleTorusFaceOutwardEverywhere) {
  // Outward on a torus: away from the tube's centre circle.
  PointCloud t = poisson_disk_sample(torus_mesh(1.0, 0.3, 200, 60), 0.03, 2);
  const std::vector<Vec3> n = estimate_normals(t);
  for (size_t i = 0; i < t.size(); ++i) {
    const Vec3 p = t.positions[i];
    const Vec3 ring = normalized(Vec3{p.x, p.y, 0});
    EXPECT_GT(dot(n[i], normalized(p - ring)), 0.9) << i;
  }
  // The double torus's normals come from its gradient: every estimate faces the same way,
  // and all but a handful (where the surface turns within a spacing) within ~35 degrees.
  const PointCloud d = double_torus_sample(0.03, 3);
  const std::vector<Vec3> m = estimate_normals(d);
  size_t agree = 0;
  for (size_t i = 0; i < d.size(); ++i) {
    EXPECT_GT(dot(m[i], d.normals[i]), 0.0) << i;
    agree += dot(m[i], d.normals[i]) > 0.8;
  }
  EXPECT_GE(double(agree), 0.999 * double(d.size()));
}

TEST(EstimateNormals, CreasePointsFaceBothSides) {
  // A cone's 63-degree rim, jittered. Near the rim a plane fit is a coin toss between the two
  // faces, and a rim point with the other face's normal is 117 degrees off this face's
  // triangles; the spanning tree then carried the wrong sense onto the whole base. Where the
  // two planes cross at a point, it takes their bisector, within 90 degrees of both faces
  // (a fifth of the rim points or more here, none before; the rest keep one face).
  const double r0 = 0.02;
  for (uint64_t seed : {1, 2}) {
    PointCloud c = test::jittered(poisson_disk_sample(cone_mesh(0.5, 1.0, 256), r0, 3), 0.05 * r0, seed);
    c.normals.clear();
    const std::vector<Vec3> n = estimate_normals(c);
    size_t rim = 0, both = 0, faces = 0, own = 0;
    for (size_t i = 0; i < c.size(); ++i) {
      const Vec3 p = c.positions[i];
      const double rho = std::hypot(p.x, p.y);
      const Vec3 base{0, 0, -1}, side = normalized(Vec3{p.x / rho, p.y / rho, 0.5});
      const double to_rim = std::hypot(rho - 0.5, p.z);  // the rim: radius 0.5 at z = 0
      if (to_rim < 0.25 * r0) {
        ++rim;
        both += dot(n[i], base) > 0 && dot(n[i], side) > 0;
      } else if (to_rim > 2.5 * r0 && p.z < 0.9 && rho > 3 * r0) {  // clear of rim, apex and axis
        ++faces;
        own += dot(n[i], p.z < 0.25 * r0 ? base : side) > 0.95;
      }
    }
    ASSERT_GT(rim, 50u);
    EXPECT_EQ(own, faces) << "seed " << seed;  // every face point outward along its own face
    EXPECT_GE(5 * both, rim) << "seed " << seed << ": " << both << " of " << rim << " rim points face both sides";
  }
}

TEST(EstimateNormals, FacingSheetsGetOppositeNormals) {
  // Two parallel planes 1.2 spacings apart: the tree must not carry one's orientation to
  // the other as if it were the same sheet (across a gap, normals are opposite).
  PointCloud c;
  for (int i = 0; i < 40; ++i)
    for (int j = 0; j < 40; ++j) {
      c.positions.push_back({i * 0.1 + 0.03 * (j % 2), j * 0.1, 0});
      c.positions.push_back({i * 0.1 + 0.03 * (j % 2), j * 0.1, 0.12});
    }
  NormalOptions o;
  o.radius = 0.2;
  const std::vector<Vec3> n = estimate_normals(c, o);
  for (size_t i = 0; i < c.size(); i += 2) {
    const Vec3 p = c.positions[i];
    if (p.x < 0.3 || p.x > 3.6 || p.y < 0.3 || p.y > 3.6) continue;  // away from the sheets' rims
    ASSERT_LT(dot(n[i], n[i + 1]), -0.99) << i;
  }
}

TEST(EstimateNormals, RejectsBadInput) {
  PointCloud c = fibonacci_sphere(100);
  NormalOptions o;
  o.radius = -1;
  EXPECT_THROW(estimate_normals(c, o), Error);
  EXPECT_THROW(estimate_normals(PointCloud{}, {}), Error);
}
