#include "particlemesh/surface/normals.h"

#include <gtest/gtest.h>

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
