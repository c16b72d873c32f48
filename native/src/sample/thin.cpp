// Greedy Poisson-disk thinning over a grid of cell min_distance.
//
// Written here because no library on the list does it on our data: PCL's VoxelGrid and
// UniformSampling keep one point per cell, and two kept points in neighbouring cells can be
// arbitrarily close, which the triangulation's test turns into slivers and holes.
#include "particlemesh/sample/thin.h"

#include <cmath>
#include <string>

#include "core/parallel.h"
#include "particlemesh/core/error.h"
#include "particlemesh/spatial/neighbor_grid.h"

namespace particlemesh {

std::vector<uint32_t> thin_points(const Vec3* points, size_t n, double min_distance) {
  if (!(min_distance > 0) || !std::isfinite(min_distance))
    throw Error(Status::InvalidArgument,
                "min_distance must be a positive finite distance, got " + std::to_string(min_distance));
  if (points == nullptr && n > 0) throw Error(Status::InvalidArgument, "points is NULL");
  if (n > size_t(UINT32_MAX) - 1) throw Error(Status::LimitExceeded, "more than 2^32 - 2 points");
  for (size_t i = 0; i < n; ++i)
    if (!std::isfinite(points[i].x) || !std::isfinite(points[i].y) || !std::isfinite(points[i].z))
      throw Error(Status::InvalidInput, "point " + std::to_string(i) + " has a non-finite coordinate");
  std::vector<uint32_t> kept;
  if (n == 0) return kept;

  // Cells of edge 2 min_distance: the points closer than min_distance to p lie in the 2 x 2 x 2
  // cells that the box p +- min_distance touches, 8 lookups instead of the 27 of a grid of
  // edge min_distance. Each cell's 27 neighbours are looked up once, not once per point.
  const NeighborGrid grid(points, n, 2 * min_distance);
  const uint32_t cells = uint32_t(grid.cell_count());
  std::vector<uint32_t> cell_of(n);  // input index -> cell
  std::vector<uint32_t> around(size_t(cells) * 27);  // (dx+1)*9 + (dy+1)*3 + (dz+1) -> cell
  detail::parallel_blocks(cells, 1024, [&](size_t cb, size_t ce) {
    for (uint32_t c = uint32_t(cb); c < uint32_t(ce); ++c) {
      for (uint32_t s = grid.cell_begin(c); s < grid.cell_end(c); ++s) cell_of[grid.original_index(s)] = c;
      const auto cc = grid.cell_coord(c);
      uint32_t* out = &around[size_t(c) * 27];
      for (int dx = -1; dx <= 1; ++dx)
        for (int dy = -1; dy <= 1; ++dy)
          for (int dz = -1; dz <= 1; ++dz) *out++ = grid.find_cell({cc[0] + dx, cc[1] + dy, cc[2] + dz});
    }
  });

  // Kept points per cell as linked lists (a cell of this size holds a few dozen at most).
  constexpr uint32_t kEnd = 0xffffffffu;
  std::vector<uint32_t> head(cells, kEnd), next(n, kEnd);
  const double r2 = min_distance * min_distance;
  const Vec3 reach{min_distance, min_distance, min_distance};
  for (uint32_t i = 0; i < uint32_t(n); ++i) {
    const Vec3& p = points[i];
    const uint32_t c = cell_of[i];
    const auto cc = grid.cell_coord(c), lo = grid.coord_of(p - reach), hi = grid.coord_of(p + reach);
    bool free = true;
    for (int dx = lo[0] - cc[0]; free && dx <= hi[0] - cc[0]; ++dx)
      for (int dy = lo[1] - cc[1]; free && dy <= hi[1] - cc[1]; ++dy)
        for (int dz = lo[2] - cc[2]; free && dz <= hi[2] - cc[2]; ++dz) {
          const uint32_t nc = around[size_t(c) * 27 + size_t((dx + 1) * 9 + (dy + 1) * 3 + (dz + 1))];
          if (nc == NeighborGrid::kNoCell) continue;
          for (uint32_t k = head[nc]; k != kEnd; k = next[k])
            if (squared_distance(points[k], p) < r2) {
              free = false;
              break;
            }
          if (!free) break;
        }
    if (!free) continue;
    next[i] = head[c];
    head[c] = i;
    kept.push_back(i);
  }
  return kept;
}

}  // namespace particlemesh
