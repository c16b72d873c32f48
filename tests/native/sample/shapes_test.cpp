#include "particlemesh/sample/shapes.h"

#include <gtest/gtest.h>

#include <cmath>

#include "particlemesh/core/error.h"

#include "particlemesh/mesh/topology_report.h"
#include "particlemesh/spatial/spacing.h"
#include "support/test_support.h"

using namespace particlemesh;

TEST(Shapes, MeshesAreClosedOutwardWithTheRightGenus) {
  const TopologyReport torus = topology_report(torus_mesh(1, 0.4, 30, 12));
  EXPECT_TRUE(torus.closed && torus.outward);
  EXPECT_EQ(torus.per_component[0].genus, 1);
  const TopologyReport knot = topology_report(trefoil_tube_mesh(1, 0.35, 200, 16));
  EXPECT_TRUE(knot.closed && knot.outward && knot.consistently_oriented);
  EXPECT_EQ(knot.per_component[0].genus, 1);
  const TopologyReport ico = topology_report(icosphere_mesh(2));
  EXPECT_TRUE(ico.closed && ico.outward);
  EXPECT_EQ(ico.euler_characteristic, 2);
}

TEST(Shapes, SharpShapesAreClosedOutwardWithTheirVolume) {
  struct Shape {
    const char* name;
    TriMesh mesh;
    double volume;
  };
  const double pi = 3.14159265358979323846;
  const Shape shapes[] = {
      {"box", box_mesh({1, 2, 3}), 6.0},
      {"cone", cone_mesh(0.5, 1.0, 4096), pi * 0.25 / 3},
      {"prism", prism_mesh(60, 2.0), 0.5 * std::sin(pi / 3) * 2.0},
  };
  for (const Shape& s : shapes) {
    const TopologyReport t = topology_report(s.mesh);
    EXPECT_TRUE(t.closed && t.outward && t.consistently_oriented) << s.name;
    EXPECT_EQ(t.euler_characteristic, 2) << s.name;
    EXPECT_NEAR(t.per_component[0].signed_volume, s.volume, 1e-6 * s.volume + 1e-9) << s.name;
  }
  EXPECT_THROW(box_mesh({1, 0, 1}), Error);
  EXPECT_THROW(cone_mesh(1, 1, 2), Error);
  EXPECT_THROW(prism_mesh(180), Error);
}

TEST(Shapes, PoissonDiskSampleIsEvenAndOnTheSurface) {
  const PointCloud c = poisson_disk_sample(icosphere_mesh(5), 0.05, 7);
  ASSERT_GT(c.size(), 3000u);  // 4 pi / r0^2 / ~1.6 for a maximal Poisson disk sample
  for (const Vec3& p : c.positions) EXPECT_NEAR(norm(p), 1.0, 0.002);
  const SpacingEstimate e = estimate_spacing(c.positions.data(), c.size());
  EXPECT_GE(e.spacing, 0.05);
  // Same seed, same points; another seed, other points.
  EXPECT_EQ(poisson_disk_sample(icosphere_mesh(5), 0.05, 7).positions, c.positions);
  EXPECT_NE(poisson_disk_sample(icosphere_mesh(5), 0.05, 8).positions, c.positions);
}

TEST(Shapes, FibonacciSphereHasUnitNormalsOutward) {
  const PointCloud c = fibonacci_sphere(1000, 2.0, {1, 1, 1});
  for (size_t i = 0; i < c.size(); ++i) {
    EXPECT_NEAR(distance(c.positions[i], {1, 1, 1}), 2.0, 1e-12);
    EXPECT_NEAR(dot(c.normals[i], normalized(c.positions[i] - Vec3{1, 1, 1})), 1.0, 1e-12);
  }
}

// No two kept points closer than r0, checked pair by pair: the sampler's grid skips the
// neighbouring cells no point of which can come within r0 of a dart, and must skip no other,
// also far from the origin (the cells' coordinates then large, their rounding coarser).
TEST(Shapes, PoissonDiskSampleKeepsNoTwoPointsWithinR0) {
  for (const Vec3 shift : {Vec3{0, 0, 0}, Vec3{1e4, -3e3, 7e2}}) {
    TriMesh m = icosphere_mesh(4);
    for (Vec3& p : m.positions) p += shift;
    const double r0 = 0.07;
    const PointCloud c = poisson_disk_sample(m, r0, 3);
    ASSERT_GT(c.size(), 1000u);
    size_t close = 0;
    for (size_t i = 0; i < c.size(); ++i)
      for (size_t j = i + 1; j < c.size(); ++j) close += squared_distance(c.positions[i], c.positions[j]) < r0 * r0;
    EXPECT_EQ(close, 0u) << "shift " << shift.x;
    // And it is a maximal sample: no point of the sphere is farther than about 2 r0 from one.
    for (const Vec3& v : m.positions) {
      double nearest = 1e300;
      for (const Vec3& p : c.positions) nearest = std::min(nearest, squared_distance(v, p));
      ASSERT_LT(std::sqrt(nearest), 2 * r0);
    }
  }
}
