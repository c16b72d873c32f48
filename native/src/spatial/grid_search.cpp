#include "spatial/grid_search.h"

#include <algorithm>
#include <atomic>

#include "core/parallel.h"

namespace PM_NAMESPACE::detail {

std::vector<uint32_t> find_duplicates(const NeighborGrid& grid, size_t* duplicate_count) {
  const size_t n = grid.point_count();
  std::vector<uint32_t> rep(n);
  std::atomic<size_t> dups{0};
  detail::parallel_blocks(grid.cell_count(), 1024, [&](size_t cb, size_t ce) {
   for (size_t c = cb; c < ce; ++c) {
    const uint32_t b = grid.cell_begin(uint32_t(c)), e = grid.cell_end(uint32_t(c));
    for (uint32_t s = b; s < e; ++s) rep[s] = s;
    if (e - b < 2) continue;
    // Most cells hold a few points and no copies: compared pair by pair, without the sort and
    // its allocation (a search per cell of a million-point cloud otherwise costs ~0.1 s).
    if (e - b <= 32) {
      bool any = false;
      for (uint32_t s = b; s < e && !any; ++s)
        for (uint32_t t = s + 1; t < e && !any; ++t) any = grid.sorted_point(s) == grid.sorted_point(t);
      if (!any) continue;
    }
    std::vector<uint32_t> order(e - b);
    for (uint32_t s = b; s < e; ++s) order[s - b] = s;
    // Sort by coordinates, then by input index, so each run of equal points starts with its
    // lowest input index. Cells hold a few points unless the cloud is degenerate.
    std::sort(order.begin(), order.end(), [&](uint32_t x, uint32_t y) {
      const Vec3& p = grid.sorted_point(x);
      const Vec3& q = grid.sorted_point(y);
      if (p.x != q.x) return p.x < q.x;
      if (p.y != q.y) return p.y < q.y;
      if (p.z != q.z) return p.z < q.z;
      return grid.original_index(x) < grid.original_index(y);
    });
    size_t local = 0;
    for (size_t t = 1; t < order.size(); ++t) {
      if (grid.sorted_point(order[t]) == grid.sorted_point(order[t - 1])) {
        rep[order[t]] = rep[order[t - 1]];
        ++local;
      }
    }
    dups += local;
   }
  });
  if (duplicate_count) *duplicate_count = dups.load();
  return rep;
}

}  // namespace particlemesh::detail
