// The cells around each cell of a walk in increasing cell order (src/spatial/
// neighbor_cell_walk.h), against NeighborGrid::neighbor_cells (a hash look-up per run of
// cells): both must give the same cells in the same order, whether the walk takes every cell,
// skips some, starts part-way (a thread's run of cells) or steps back (a fresh start).
#include "spatial/neighbor_cell_walk.h"

#include <gtest/gtest.h>

#include <random>
#include <vector>

#include "particlemesh/sample/shapes.h"

using namespace particlemesh;

namespace test_walk {

/// Walks `order` (cells of `grid`) with one walk and counts the cells whose list differs.
size_t differences(const NeighborGrid& grid, const std::vector<uint32_t>& order) {
  detail::NeighborCellWalk walk(grid);
  size_t differ = 0;
  for (const uint32_t c : order) {
    uint32_t want[27], got[27];
    const int nw = grid.neighbor_cells(c, want);
    const int ng = walk.around(c, got);
    differ += std::vector<uint32_t>(want, want + nw) != std::vector<uint32_t>(got, got + ng);
  }
  return differ;
}

std::vector<uint32_t> every(const NeighborGrid& grid, uint32_t from, uint32_t step) {
  std::vector<uint32_t> order;
  for (uint32_t c = from; c < grid.cell_count(); c += step) order.push_back(c);
  return order;
}

}  // namespace test_walk

using namespace test_walk;

TEST(NeighborCellWalk, MatchesNeighborCellsOnASphere) {
  // Cells of about the neighbour lists' size and of the spacing estimate's, and coarse ones
  // whose lowest points round to coordinate 0 (no cell below them).
  const PointCloud c = fibonacci_sphere(20000);
  for (double h : {0.0246, 0.05, 0.1, 0.5}) {
    const NeighborGrid grid(c.positions.data(), c.size(), h);
    ASSERT_GT(grid.cell_count(), 8u);
    EXPECT_EQ(differences(grid, every(grid, 0, 1)), 0u) << "cell size " << h;
    EXPECT_EQ(differences(grid, every(grid, uint32_t(grid.cell_count() / 3), 1)), 0u) << "from a third, h " << h;
    EXPECT_EQ(differences(grid, every(grid, 1, 7)), 0u) << "every 7th cell, h " << h;
  }
}

TEST(NeighborCellWalk, MatchesNeighborCellsOnSparseAndSteppedWalks) {
  // A sparse random cloud (columns far apart: the cursors jump), a dense block (full
  // columns), and a walk that goes back to cells it passed.
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::vector<Vec3> points;
  for (int i = 0; i < 3000; ++i) points.push_back({u(rng), u(rng), u(rng)});
  for (int x = 0; x < 12; ++x)
    for (int y = 0; y < 12; ++y)
      for (int z = 0; z < 12; ++z) points.push_back({2.0 + 0.05 * x, 0.05 * y, 0.05 * z});
  for (double h : {0.02, 0.05, 0.3}) {
    const NeighborGrid grid(points.data(), points.size(), h);
    EXPECT_EQ(differences(grid, every(grid, 0, 1)), 0u) << "cell size " << h;
    std::vector<uint32_t> order;
    for (int i = 0; i < 400; ++i) order.push_back(uint32_t(rng() % grid.cell_count()));
    EXPECT_EQ(differences(grid, order), 0u) << "random order, h " << h;
  }
  // One point, and a line along z (one column).
  const std::vector<Vec3> one{{1, 2, 3}};
  EXPECT_EQ(differences(NeighborGrid(one.data(), 1, 1.0), {0}), 0u);
  std::vector<Vec3> line;
  for (int z = 0; z < 50; ++z) line.push_back({0, 0, 0.1 * z});
  const NeighborGrid grid(line.data(), line.size(), 0.25);
  EXPECT_EQ(differences(grid, every(grid, 0, 1)), 0u);
}
