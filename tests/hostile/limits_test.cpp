// Bounded resources: inputs that would blow up time or memory get a clear error
// before they do, and every limit is settable.
#include <gtest/gtest.h>

#include <cmath>

#include "hostile_support.h"
#include "particlemesh/sample/shapes.h"
#include "particlemesh/smooth/subdivide.h"
#include "particlemesh/spatial/neighbor_grid.h"
#include "particlemesh/surface/normals.h"
#include "particlemesh/surface/reconstruct.h"
#include "particlemesh/spatial/spacing.h"
#include "particlemesh/surface/triangulate.h"
#include "support/test_support.h"

using namespace particlemesh;
using namespace particlemesh::test;

// Points packed far denser than the given spacing: the neighbour cap stops the run and says
// which point and how to go on.
TEST(Limits, NeighbourCapIsReportedAndSettable) {
  const PointCloud c = fibonacci_sphere(20000);  // spacing about 0.024
  TriangulateOptions o;
  o.spacing = 0.2;  // the caller claims a spacing 8x the real one
  PM_EXPECT_ERROR(triangulate_raw(c, o), Status::LimitExceeded, "more than the limit of 256");
  std::string msg;
  status_of([&] { triangulate_raw(c, o); }, &msg);
  EXPECT_NE(msg.find("point "), std::string::npos) << msg;
  EXPECT_NE(msg.find("denser than the spacing"), std::string::npos) << msg;
  // The cap is an option, and the count seen is reported.
  o.spacing = 0;
  const TriangulateResult ok = triangulate_raw(c, o);
  EXPECT_GT(ok.stats.max_neighbors_seen, 5u);
  o.max_neighbors = ok.stats.max_neighbors_seen - 1;
  // The message names the limit that lets the call through: the most any point has.
  PM_EXPECT_ERROR(triangulate_raw(c, o), Status::LimitExceeded,
                  "more than the limit of " + std::to_string(o.max_neighbors) + ": ");
  PM_EXPECT_ERROR(triangulate_raw(c, o), Status::LimitExceeded,
                  "raise the neighbour limit to at least " + std::to_string(ok.stats.max_neighbors_seen) + ",");
  o.max_neighbors = ok.stats.max_neighbors_seen;
  EXPECT_EQ(triangulate_raw(c, o).mesh.triangles, ok.mesh.triangles);
}

// Clusters of coincident points: set aside as duplicates (counted), never a blow-up.
TEST(Limits, CoincidentClustersAreDuplicatesNotNeighbours) {
  PointCloud c = fibonacci_sphere(5000);
  const size_t n = c.size();
  for (size_t i = 0; i < 20000; ++i) c.positions.push_back(c.positions[i % 7]);  // 7 points x ~2900
  c.normals.clear();
  const TriangulateResult r = triangulate_raw(c);
  EXPECT_EQ(r.stats.duplicate_points, 20000u);
  EXPECT_LT(r.stats.max_neighbors_seen, 64u);
  EXPECT_EQ(r.mesh.positions.size(), n + 20000);
  PointCloud all_same;
  all_same.positions.assign(100000, Vec3{0.5, -2, 7});
  PM_EXPECT_ERROR(triangulate_raw(all_same), Status::InvalidInput, "coincide");
  PM_EXPECT_ERROR(estimate_spacing(all_same.positions.data(), all_same.size()), Status::InvalidInput, "coincide");
}

// A max edge so large that the triplet count explodes: refused before the test, with the
// count, the limit and the remedy; settable (0 = no limit); the count is reported.
TEST(Limits, TripletCapStopsAnExplodingMaxEdge) {
  const PointCloud c = fibonacci_sphere(4000);
  TriangulateOptions o;
  o.max_edge_factor = 12;    // L = 12 r0: about 25000 triplets per point
  o.max_neighbors = 100000;  // the neighbour cap raised out of the way
  const auto t0 = Clock::now();
  PM_EXPECT_ERROR(triangulate_raw(c, o), Status::LimitExceeded, "more than max_triplets_per_point = 4096");
  EXPECT_LT(seconds(Clock::now() - t0), 5.0) << "refused before the test, not after it";
  std::string msg;
  status_of([&] { triangulate_raw(c, o); }, &msg);
  EXPECT_NE(msg.find("far too large for the spacing"), std::string::npos) << msg;
  // The default edge factor needs a few dozen per point, and the count is reported.
  const TriangulateResult normal = triangulate_raw(c);
  EXPECT_GT(normal.stats.triplets, normal.stats.candidates);
  EXPECT_LT(normal.stats.triplets, 60u * c.size());
  // The limit is settable: just below the count per point fails, at it runs; 0 = no limit.
  TriangulateOptions p;
  p.max_triplets_per_point = normal.stats.triplets / c.size();
  PM_EXPECT_ERROR(triangulate_raw(c, p), Status::LimitExceeded,
                  "max_triplets_per_point = " + std::to_string(p.max_triplets_per_point));
  p.max_triplets_per_point += 1;
  EXPECT_EQ(triangulate_raw(c, p).mesh.triangles, normal.mesh.triangles);
  p.max_triplets_per_point = 0;
  EXPECT_EQ(triangulate_raw(c, p).mesh.triangles, normal.mesh.triangles);
}

// The triplet count is exact: pairs (j, k) of each point's neighbours within L that come
// after it in the neighbour grid's order (each triangle is generated from its first corner).
TEST(Limits, TripletCountEqualsBruteForce) {
  const PointCloud c = test::random_cloud(300, 5);
  TriangulateOptions o;
  o.spacing = 0.08;
  const TriangulateResult r = triangulate_raw(c, o);
  const double L = r.stats.max_edge;
  const NeighborGrid grid(c.positions.data(), c.size(), L * (2.0 / std::sqrt(3.0)) * (1.0 + 1e-6));
  size_t expected = 0;
  for (uint32_t s = 0; s < c.size(); ++s) {
    size_t higher = 0;
    for (uint32_t t = s + 1; t < c.size(); ++t) higher += distance(grid.sorted_point(s), grid.sorted_point(t)) <= L;
    expected += higher * (higher - (higher > 0)) / 2;
  }
  EXPECT_EQ(r.stats.triplets, expected);
  EXPECT_GE(r.stats.triplets, r.stats.candidates + r.stats.degenerate);
}

// Far outliers: the grid refuses to span more than 2^21 cells along an axis.
TEST(Limits, FarOutlierGivesAGridLimitNotAHugeAllocation) {
  PointCloud c = fibonacci_sphere(1000);
  c.normals.clear();
  c.positions.push_back({1e12, 0, 0});
  TriangulateOptions o;
  o.spacing = 0.1;
  PM_EXPECT_ERROR(triangulate_raw(c, o), Status::LimitExceeded, "far outliers");
  // The message names the stray point: the one farthest from the others' median.
  PM_EXPECT_ERROR(triangulate_raw(c, o), Status::LimitExceeded, "point 1000 (x = 1e+12) lies 1e+12 from");
  // And the widest empty stretch along the axis, with the points on each side: where to crop.
  PM_EXPECT_ERROR(triangulate_raw(c, o), Status::LimitExceeded, " and 1e+12 (1000 below, 1 above)");
  // Two groups alike: the median lies in one, the "farthest" point in the other; the stretch
  // between them says both.
  PointCloud two = fibonacci_sphere(500);
  for (const Vec3& p : fibonacci_sphere(500, 1.0, {0, 1e9, 0}).positions) two.positions.push_back(p);
  two.normals.clear();
  PM_EXPECT_ERROR(triangulate_raw(two, o), Status::LimitExceeded, "(500 below, 500 above)");
  c.positions.back() = {1e300, -1e300, 0};
  PM_EXPECT_ERROR(triangulate_raw(c, o), Status::LimitExceeded, "cells");
  PM_EXPECT_ERROR(NeighborGrid(c.positions.data(), c.size(), 1e-300), Status::LimitExceeded, "cells");
}

// Absurd subdivision levels: refused before any work (levels > 10, or a result beyond
// max_triangles, checked on F x 4^levels before allocating).
TEST(Limits, SmoothLevelsAndTriangleBudget) {
  const TriMesh m = icosphere_mesh(5);  // 20480 triangles
  SmoothOptions o;
  o.levels = 11;
  PM_EXPECT_ERROR(smooth_mesh(m, o), Status::InvalidArgument, "levels must be in [0, 10]");
  o.levels = 1000000;
  PM_EXPECT_ERROR(smooth_mesh(m, o), Status::InvalidArgument, "levels");
  o.levels = -1;
  PM_EXPECT_ERROR(smooth_mesh(m, o), Status::InvalidArgument, "levels");
  o.levels = 10;  // 2.1e10 triangles
  const auto t0 = Clock::now();
  PM_EXPECT_ERROR(smooth_mesh(m, o), Status::LimitExceeded, "more than max_triangles = 33554432");
  EXPECT_LT(seconds(Clock::now() - t0), 5.0);  // refused up front, not after trying
  o.levels = 2;
  o.max_triangles = 20480 * 16 - 1;
  PM_EXPECT_ERROR(smooth_mesh(m, o), Status::LimitExceeded, "max_triangles");
  o.max_triangles = 20480 * 16;
  EXPECT_EQ(smooth_mesh(m, o).mesh.triangles.size(), 20480u * 16);
  o.max_triangles = 0;
  PM_EXPECT_ERROR(smooth_mesh(m, o), Status::InvalidArgument, "max_triangles");
}

// Normal estimation with a radius far beyond the spacing is bounded by the triplet cap.
TEST(Limits, NormalRadiusFarBeyondTheSpacing) {
  const PointCloud c = fibonacci_sphere(3000);
  NormalOptions o;
  o.radius = 1.5;  // most of the sphere
  PM_EXPECT_ERROR(estimate_normals(c, o), Status::LimitExceeded, "max_triplets_per_point");
}
