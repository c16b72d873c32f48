// The local spacing's k nearest neighbours (src/spatial/nearest_neighbors.h), against a plain
// reference: every point of the rings of cells gathered cell by cell, all of those within
// reach collected and sorted - what the search did before it went by column and kept only
// the running k nearest. Both must agree entry for entry: ties (lattices), duplicates, far
// points that reach the last ring, clouds of a few points.
#include "spatial/nearest_neighbors.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>

#include "particlemesh/sample/shapes.h"

using namespace particlemesh;

namespace test_knn {

std::vector<uint32_t> reference(const NeighborGrid& grid, int k) {
  const size_t n = grid.point_count(), K = size_t(k);
  const double h = grid.cell_size();
  std::vector<uint32_t> out(n * K, detail::kNoNeighbor);
  for (uint32_t s = 0; s < n; ++s) {
    const auto cc = grid.coord_of(grid.sorted_point(s));
    for (int32_t ring = 2;; ++ring) {
      std::vector<std::pair<double, uint32_t>> found;
      grid.for_each_cell_in({cc[0] - ring, cc[1] - ring, cc[2] - ring}, {cc[0] + ring, cc[1] + ring, cc[2] + ring},
                            [&](uint32_t b) {
                              for (uint32_t t = grid.cell_begin(b); t < grid.cell_end(b); ++t) {
                                const double e2 = squared_distance(grid.sorted_point(t), grid.sorted_point(s));
                                if (e2 > 0 && (e2 <= double(ring) * h * double(ring) * h || ring == detail::kMaxNeighborRing))
                                  found.push_back({e2, t});
                              }
                            });
      if (found.size() >= K || ring == detail::kMaxNeighborRing) {
        std::sort(found.begin(), found.end());
        for (size_t i = 0; i < std::min(K, found.size()); ++i) out[s * K + i] = found[i].second;
        break;
      }
    }
  }
  return out;
}

void expect_reference(const std::vector<Vec3>& points, double cell, int k) {
  const NeighborGrid grid(points.data(), points.size(), cell);
  const ProgressCallback none;
  detail::ProgressTracker tracker(none);
  const std::vector<uint32_t> got = detail::nearest_neighbors(grid, k, tracker);
  const std::vector<uint32_t> want = reference(grid, k);
  ASSERT_EQ(got.size(), want.size());
  size_t differ = 0;
  for (size_t i = 0; i < got.size(); ++i) differ += got[i] != want[i];
  EXPECT_EQ(differ, 0u) << "of " << got.size() << " entries (" << points.size() << " points, k = " << k << ")";
}

}  // namespace test_knn

using namespace test_knn;

TEST(NearestNeighbors, MatchTheReferenceOnASphere) {
  const PointCloud c = fibonacci_sphere(3000);
  const double r0 = std::sqrt(4 * M_PI / 3000.0);
  expect_reference(c.positions, 2 * r0, 16);
  expect_reference(c.positions, 0.7 * r0, 16);  // small cells: the search goes past ring 2
  expect_reference(c.positions, 2 * r0, 1);
}

TEST(NearestNeighbors, BreakTiesByIndexOnALattice) {
  // A square lattice: every point has 4 neighbours at exactly one distance, 4 at another...
  std::vector<Vec3> points = square_lattice(30, 30, 1.0).positions;
  expect_reference(points, 2.0, 16);
  // ... and a cubic one, whose cells' faces pass through points.
  std::vector<Vec3> cube;
  for (int x = 0; x < 8; ++x)
    for (int y = 0; y < 8; ++y)
      for (int z = 0; z < 8; ++z) cube.push_back({double(x), double(y), double(z)});
  expect_reference(cube, 1.0, 16);
  expect_reference(cube, 2.0, 20);
}

TEST(NearestNeighbors, SkipDuplicatesAndKeepWhatFarPointsReach) {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::vector<Vec3> points;
  for (int i = 0; i < 400; ++i) points.push_back({u(rng), u(rng), 0.05 * u(rng)});
  for (int i = 0; i < 50; ++i) points.push_back(points[size_t(i) * 3]);  // duplicates
  for (int i = 0; i < 5; ++i) points.push_back({3.0 + 0.01 * i, 0.5, 0.0});  // a small cluster far off
  points.push_back({-4.0, -4.0, 2.0});                                      // a lone point
  expect_reference(points, 0.1, 16);   // the cluster and the lone point reach the last ring
  expect_reference(points, 0.02, 16);
  // Fewer points than k: every point gets all the others, the rest kNoNeighbor.
  expect_reference({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {0, 0, 1}}, 0.5, 16);
}

TEST(NearestNeighbors, MatchTheReferenceWhereTheDensityVariesByOrdersOfMagnitude) {
  // A spinning lidar's ground: rings of points dense along each ring, rings farther apart
  // the farther out, so that far points find their neighbours many cells away (the search
  // walks shells of cells out to the last ring); and a few posts standing on it (columns of
  // cells found first at one ring and reached along z at later ones).
  std::vector<Vec3> points;
  for (int ring = 0; ring < 14; ++ring) {
    const double radius = 1.0 + 0.08 * double(ring * ring);
    const int count = 160;
    for (int i = 0; i < count; ++i) {
      const double a = 2 * M_PI * double(i) / count + 0.01 * ring;
      points.push_back({radius * std::cos(a), radius * std::sin(a), 0.002 * double(i % 3)});
    }
  }
  for (int post = 0; post < 6; ++post)
    for (int i = 0; i < 25; ++i) points.push_back({-2.0 + 0.8 * post, 0.3 * post, 0.05 * i});
  expect_reference(points, 0.06, 16);
  expect_reference(points, 0.15, 8);
}

TEST(NearestNeighbors, RejectABadCount) {
  const std::vector<Vec3> points{{0, 0, 0}, {1, 0, 0}};
  const NeighborGrid grid(points.data(), points.size(), 1.0);
  const ProgressCallback none;
  detail::ProgressTracker tracker(none);
  EXPECT_ANY_THROW(detail::nearest_neighbors(grid, 0, tracker));
  EXPECT_ANY_THROW(detail::nearest_neighbors(grid, 65, tracker));
}

TEST(NearestNeighbors, MatchTheReferenceInCrowdedCells) {
  // Clusters far denser than the cells (a close-up scan merged into a wide one): a small
  // sphere of 3000 points and, inside it, a smaller one of 1500 within one cell of a sphere of
  // 3000 (searched on a finer grid, and a finer one within it), with exact copies among them,
  // a lattice's ties, and a cluster of copies of a few points (no finer grid holds them apart).
  std::vector<Vec3> points;
  for (const Vec3& p : fibonacci_sphere(3000).positions) points.push_back(p);
  const Vec3 at{0.31, -0.52, 0.74};
  for (const Vec3& p : fibonacci_sphere(3000, 0.01, at).positions) points.push_back(p);
  for (const Vec3& p : fibonacci_sphere(1500, 0.0004, at + Vec3{0.002, 0.001, 0}).positions) points.push_back(p);
  for (int i = 0; i < 200; ++i) points.push_back(points[size_t(3100 + 13 * i)]);
  for (int x = 0; x < 8; ++x)
    for (int y = 0; y < 8; ++y)
      for (int z = 0; z < 4; ++z) points.push_back(Vec3{-0.6, 0.2, 0.7} + Vec3{double(x), double(y), double(z)} * 1e-3);
  for (int i = 0; i < 300; ++i) points.push_back(Vec3{0.5, 0.5, -0.6} + Vec3{double(i % 3), 0, 0} * 1e-4);
  expect_reference(points, 0.1, 16);
  expect_reference(points, 0.07, 8);
}

TEST(NearestNeighbors, MatchTheReferenceOnARandomSamplingSearchedOnACoarserGrid) {
  // Points dropped at random on a sphere, gridded as the local spacing grids them (cells of
  // twice the median nearest distance): their 16th nearest lies about 2.4 cells away, so the
  // search goes on a coarser grid (nearest_neighbors_cell) and must still give this grid's
  // lists entry for entry: ties broken by this grid's indices (points on a small lattice, exact
  // copies), and points whose 16 nearest this grid's rings would not reach (strays 25 to 35
  // cells out, two of them together) searched on this grid, whatever its last ring holds.
  std::mt19937_64 rng(11);
  std::normal_distribution<double> g(0.0, 1.0);
  std::vector<Vec3> points;
  for (int i = 0; i < 6000; ++i) {
    const Vec3 v{g(rng), g(rng), g(rng)};
    points.push_back(v / norm(v));
  }
  for (int x = 0; x < 6; ++x)
    for (int y = 0; y < 6; ++y) points.push_back(Vec3{0.0, 0.0, 1.0} + Vec3{double(x), double(y), 0.0} * 0.02);
  for (int i = 0; i < 40; ++i) points.push_back(points[size_t(97 * i)]);
  const double cell = 0.043;  // twice the median nearest distance of 6000 random points on it
  for (int i = 0; i < 6; ++i) points.push_back(Vec3{1.0 + (25.0 + 2.0 * i) * cell, 0.1 * i, -0.2});
  points.push_back({-2.6, 0.0, 0.0});
  points.push_back({-2.6, 0.01, 0.0});
  const NeighborGrid grid(points.data(), points.size(), cell);
  ASSERT_GT(detail::nearest_neighbors_cell(grid, 16), cell);
  expect_reference(points, cell, 16);
  // An even sampling's grid serves as it is.
  const PointCloud even = fibonacci_sphere(6000);
  const NeighborGrid even_grid(even.positions.data(), even.size(), 2 * std::sqrt(4 * M_PI / 6000.0));
  EXPECT_EQ(detail::nearest_neighbors_cell(even_grid, 16), 0.0);
}
