#include "particlemesh/spatial/neighbor_grid.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <random>

#include "particlemesh/core/error.h"
#include "particlemesh/sample/shapes.h"
#include "support/test_support.h"

using namespace particlemesh;

TEST(NeighborGrid, RadiusQueriesMatchBruteForce) {
  const PointCloud c = test::random_cloud(2000, 7, 10.0);
  for (double cell : {0.3, 1.0, 2.5}) {
    NeighborGrid grid(c.positions.data(), c.size(), cell);
    EXPECT_EQ(grid.point_count(), c.size());
    for (size_t q = 0; q < 50; ++q) {
      const Vec3 p = c.positions[q * 37];
      const double r = 0.9;
      std::vector<uint32_t> got;
      grid.for_each_within(p, r, [&](uint32_t s, double d2) {
        EXPECT_LE(d2, r * r);
        got.push_back(grid.original_index(s));
      });
      std::vector<uint32_t> want;
      for (uint32_t i = 0; i < c.size(); ++i)
        if (squared_distance(c.positions[i], p) <= r * r) want.push_back(i);
      std::sort(got.begin(), got.end());
      EXPECT_EQ(got, want) << "cell " << cell << " query " << q;
    }
  }
}

TEST(NeighborGrid, CellQueriesMatchALookUpPerCell) {
  // neighbor_cells and for_each_cell_in walk runs of cells along z; both must give exactly
  // the occupied cells a look-up per coordinate finds, in that order. The sphere's cell sizes
  // include one where a lowest point's cell rounds to coordinate 0 along z.
  const PointCloud c = fibonacci_sphere(100000);
  for (double h : {0.0246, 0.1}) {
    const NeighborGrid grid(c.positions.data(), c.size(), h);
    size_t differ = 0;
    for (uint32_t cell = 0; cell < grid.cell_count(); ++cell) {
      const auto cc = grid.cell_coord(cell);
      for (int32_t ring : {1, 2}) {
        std::vector<uint32_t> want, got;
        for (int32_t dx = -ring; dx <= ring; ++dx)
          for (int32_t dy = -ring; dy <= ring; ++dy)
            for (int32_t dz = -ring; dz <= ring; ++dz) {
              const uint32_t b = grid.find_cell({cc[0] + dx, cc[1] + dy, cc[2] + dz});
              if (b != NeighborGrid::kNoCell) want.push_back(b);
            }
        if (ring == 1) {
          uint32_t around[27];
          got.assign(around, around + grid.neighbor_cells(cell, around));
        } else {
          grid.for_each_cell_in({cc[0] - 2, cc[1] - 2, cc[2] - 2}, {cc[0] + 2, cc[1] + 2, cc[2] + 2},
                                [&](uint32_t b) { got.push_back(b); });
        }
        differ += got != want;
      }
    }
    EXPECT_EQ(differ, 0u) << "cell size " << h;
  }
}

TEST(NeighborGrid, BoxesOfEveryShapeMatchALookUpPerCell) {
  // for_each_cell_in walks a tall box's columns through the sorted keys and a short one by
  // look-ups: boxes of every extent from 1 to 9 cells per axis, partly outside the grid, on a
  // surface (most cells empty) and in a volume (columns full), against a look-up per
  // coordinate, cells and order.
  const PointCloud shell = fibonacci_sphere(20000);
  const PointCloud solid = test::random_cloud(20000, 3, 1.0);
  std::mt19937 rng(11);
  for (const PointCloud* c : {&shell, &solid}) {
    const NeighborGrid grid(c->positions.data(), c->size(), 0.05);
    size_t differ = 0, cells = 0;
    for (int q = 0; q < 3000; ++q) {
      const auto cc = grid.cell_coord(uint32_t(rng() % grid.cell_count()));
      NeighborGrid::CellCoord lo, hi;
      for (int a = 0; a < 3; ++a) {
        lo[a] = cc[a] - int32_t(rng() % 6);
        hi[a] = lo[a] + int32_t(rng() % 9);
      }
      std::vector<uint32_t> want, got;
      for (int32_t x = lo[0]; x <= hi[0]; ++x)
        for (int32_t y = lo[1]; y <= hi[1]; ++y)
          for (int32_t z = lo[2]; z <= hi[2]; ++z) {
            const uint32_t b = grid.find_cell({x, y, z});
            if (b != NeighborGrid::kNoCell) want.push_back(b);
          }
      grid.for_each_cell_in(lo, hi, [&](uint32_t b) { got.push_back(b); });
      differ += got != want;
      cells += want.size();
    }
    EXPECT_EQ(differ, 0u);
    EXPECT_GT(cells, 3000u);  // the boxes do hold cells
  }
}

TEST(NeighborGrid, BoxesWiderThanTheOccupiedCellsMatchAScanOfAllCells) {
  // Boxes with more cells than the grid has occupied (a ball as wide as a sparse cloud's
  // neighbourhoods) skip what lies outside them through the sorted keys: on a cloud of
  // clusters far apart (x ranges with no cell, rows and columns beyond the box) and one flat
  // as a scan of the ground, against every occupied cell filtered by its coordinates.
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::vector<Vec3> clusters, ground;
  for (int i = 0; i < 3000; ++i) {
    const double cx = double(i % 4) * 7.0, cy = double((i / 4) % 3) * 5.0;
    clusters.push_back({cx + u(rng), cy + u(rng), u(rng) * 3.0});
    ground.push_back({40 * u(rng), 40 * u(rng), 0.01 * u(rng)});
  }
  for (const auto* points : {&clusters, &ground}) {
    const NeighborGrid grid(points->data(), points->size(), 0.2);
    size_t differ = 0, cells = 0, wide = 0;
    for (int q = 0; q < 400; ++q) {
      const auto cc = grid.cell_coord(uint32_t(rng() % grid.cell_count()));
      NeighborGrid::CellCoord lo, hi;
      for (int a = 0; a < 3; ++a) {
        lo[a] = cc[a] - int32_t(rng() % 120);
        hi[a] = cc[a] + int32_t(rng() % 120);
      }
      const double box = double(hi[0] - lo[0] + 1) * double(hi[1] - lo[1] + 1) * double(hi[2] - lo[2] + 1);
      wide += box > double(grid.cell_count());
      std::vector<uint32_t> want, got;
      for (uint32_t c = 0; c < grid.cell_count(); ++c) {
        const auto k = grid.cell_coord(c);
        if (k[0] >= lo[0] && k[0] <= hi[0] && k[1] >= lo[1] && k[1] <= hi[1] && k[2] >= lo[2] && k[2] <= hi[2])
          want.push_back(c);
      }
      grid.for_each_cell_in(lo, hi, [&](uint32_t b) { got.push_back(b); });
      differ += got != want;
      cells += want.size();
    }
    EXPECT_EQ(differ, 0u);
    EXPECT_GT(wide, 300u);     // most boxes are wider than the occupied cells
    EXPECT_GT(cells, 20000u);  // and hold some
  }
}

TEST(NeighborGrid, SortedLayoutIsAPermutationGroupedByCell) {
  const PointCloud c = test::random_cloud(500, 3);
  NeighborGrid grid(c.positions.data(), c.size(), 0.1);
  std::vector<uint32_t> idx = grid.original_indices();
  std::sort(idx.begin(), idx.end());
  for (uint32_t i = 0; i < idx.size(); ++i) ASSERT_EQ(idx[i], i);
  for (uint32_t cell = 0; cell < grid.cell_count(); ++cell) {
    for (uint32_t s = grid.cell_begin(cell); s < grid.cell_end(cell); ++s)
      EXPECT_EQ(grid.coord_of(grid.sorted_point(s)), grid.cell_coord(cell));
    if (cell > 0) {
      EXPECT_LT(grid.cell_coord(cell - 1), grid.cell_coord(cell));
    }
    EXPECT_EQ(grid.find_cell(grid.cell_coord(cell)), cell);
  }
  EXPECT_EQ(grid.find_cell({-5, -5, -5}), NeighborGrid::kNoCell);
}

// The layout is the order of a sort by (cell, input index), whatever the extent: here 300
// cells spread over 10^6 cells along every axis (keys of ~60 bits, every bit deciding some
// order), 10 points near each, given in an order unrelated to their cells.
TEST(NeighborGrid, CellsInCoordinateOrderAndPointsInInputOrderOverAWideExtent) {
  const PointCloud centres = test::random_cloud(300, 11, 2.5e5);
  const PointCloud offsets = test::random_cloud(3000, 12, 0.2);
  std::vector<Vec3> points;
  for (size_t i = 0; i < 3000; ++i) points.push_back(centres.positions[(i * 7) % 300] + offsets.positions[i]);
  NeighborGrid grid(points.data(), points.size(), 0.25);
  ASSERT_LT(grid.cell_count(), 1500u);  // several points to a cell
  for (uint32_t cell = 0; cell < grid.cell_count(); ++cell) {
    if (cell > 0) {
      EXPECT_LT(grid.cell_coord(cell - 1), grid.cell_coord(cell));
    }
    for (uint32_t s = grid.cell_begin(cell); s < grid.cell_end(cell); ++s) {
      EXPECT_EQ(grid.coord_of(grid.sorted_point(s)), grid.cell_coord(cell));
      if (s > grid.cell_begin(cell)) {
        EXPECT_LT(grid.original_index(s - 1), grid.original_index(s));
      }
    }
  }
  EXPECT_GT(grid.cell_coord(uint32_t(grid.cell_count() - 1))[0], 900000);
}

TEST(NeighborGrid, RejectsBadCellSizeAndAbsurdExtent) {
  const PointCloud c = test::random_cloud(10, 1);
  EXPECT_THROW(NeighborGrid(c.positions.data(), c.size(), 0.0), Error);
  EXPECT_THROW(NeighborGrid(c.positions.data(), c.size(), -1.0), Error);
  // A subnormal cell size has no finite reciprocal: refused, not turned into NaN cell indices.
  EXPECT_THROW(NeighborGrid(c.positions.data(), c.size(), 1e-310), Error);
  std::vector<Vec3> far = {{0, 0, 0}, {1e12, 0, 0}};
  try {
    NeighborGrid g(far.data(), far.size(), 1e-3);
    FAIL() << "expected LimitExceeded";
  } catch (const Error& e) {
    EXPECT_EQ(e.status(), Status::LimitExceeded);
    EXPECT_NE(std::string(e.what()).find("outliers"), std::string::npos);
  }
  // One point far above a given lower corner: the span is the corner's, and the message (whose
  // search for the widest gap between points needs two) says so; found by fuzzing polygonize
  // with a domain_min, where it read past the one point.
  const Vec3 corner{-1e12, 0, 0};
  std::string msg;
  const auto grid_over = [&](const std::vector<Vec3>& p, const Vec3& lower) {
    return [&p, lower] { NeighborGrid g(p.data(), p.size(), 1e-3, lower); };
  };
  for (const std::vector<Vec3>& one : {std::vector<Vec3>{{0, 0, 0}}, std::vector<Vec3>{{5, 1, 2}}}) {
    EXPECT_EQ(test::status_of(grid_over(one, corner), &msg), Status::LimitExceeded);
    EXPECT_NE(msg.find("lower corner x = -1e+12"), std::string::npos) << msg;
  }
  // Points that would fit on their own: the corner is named too, not a gap between them.
  const std::vector<Vec3> two = {{0, 0, 0}, {1, 0, 0}};
  EXPECT_EQ(test::status_of(grid_over(two, corner), &msg), Status::LimitExceeded);
  EXPECT_NE(msg.find("lower corner x = -1e+12 to x = 1:"), std::string::npos) << msg;
  // Points too far apart on their own: the gap between them is named, whatever the corner.
  const std::vector<Vec3> apart = {{0, 0, 0}, {1, 0, 0}, {1e12, 0, 0}};
  EXPECT_EQ(test::status_of(grid_over(apart, Vec3{-1, 0, 0}), &msg), Status::LimitExceeded);
  EXPECT_NE(msg.find("none lies between x = 1 and 1e+12"), std::string::npos) << msg;
}

// Points kept apart follow every cell's points, in input order; no cell holds them, the cells
// hold the others as a grid of those alone would, and the bounds are every point's.
TEST(NeighborGrid, PointsKeptApartFollowTheCellsAndNoQueryFindsThem) {
  const PointCloud c = test::random_cloud(2000, 21);
  std::vector<uint8_t> apart(c.size(), 0);
  std::vector<Vec3> rest;
  std::vector<uint32_t> apart_ids;
  for (size_t i = 0; i < c.size(); ++i) {
    apart[i] = i % 97 == 3;
    if (apart[i]) apart_ids.push_back(uint32_t(i));
    else rest.push_back(c.positions[i]);
  }
  Vec3 lo = c.positions[0];
  for (const Vec3& p : c.positions) lo = {std::min(lo.x, p.x), std::min(lo.y, p.y), std::min(lo.z, p.z)};
  const NeighborGrid grid(c.positions.data(), c.size(), 0.1, &lo, apart.data());
  const NeighborGrid alone(rest.data(), rest.size(), 0.1, lo);
  ASSERT_EQ(grid.point_count(), c.size());
  ASSERT_EQ(grid.apart_begin(), rest.size());
  for (size_t k = 0; k < apart_ids.size(); ++k) {
    EXPECT_EQ(grid.original_index(uint32_t(rest.size() + k)), apart_ids[k]);
    EXPECT_TRUE(grid.sorted_point(uint32_t(rest.size() + k)) == c.positions[apart_ids[k]]);
  }
  // The same cells, holding the same points in the same order.
  ASSERT_EQ(grid.cell_count(), alone.cell_count());
  for (uint32_t cell = 0; cell < grid.cell_count(); ++cell) {
    ASSERT_EQ(grid.cell_coord(cell), alone.cell_coord(cell));
    ASSERT_EQ(grid.cell_begin(cell), alone.cell_begin(cell));
    ASSERT_EQ(grid.cell_end(cell), alone.cell_end(cell));
    for (uint32_t s = grid.cell_begin(cell); s < grid.cell_end(cell); ++s)
      ASSERT_TRUE(grid.sorted_point(s) == alone.sorted_point(s));
  }
  EXPECT_EQ(grid.cell_end(uint32_t(grid.cell_count() - 1)), grid.apart_begin());
  for (const uint32_t i : apart_ids)
    grid.for_each_within(c.positions[i], 0.3, [&](uint32_t s, double) { EXPECT_LT(s, grid.apart_begin()); });
  // Without flags: none apart; the same grid as the constructor without them.
  const NeighborGrid plain(c.positions.data(), c.size(), 0.1, nullptr, nullptr);
  EXPECT_EQ(plain.apart_begin(), c.size());
  EXPECT_TRUE(plain.original_indices() == NeighborGrid(c.positions.data(), c.size(), 0.1).original_indices());
}
