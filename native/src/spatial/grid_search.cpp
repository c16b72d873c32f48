#include "spatial/grid_search.h"

#include <algorithm>
#include <cmath>

#include "spatial/cell_hash.h"

namespace particlemesh::detail {

std::vector<uint32_t> find_duplicates(const NeighborGrid& grid, size_t* duplicate_count) {
  const size_t n = grid.point_count();
  std::vector<uint32_t> rep(n);
  size_t dups = 0;
  std::vector<uint32_t> order;
  for (uint32_t c = 0; c < grid.cell_count(); ++c) {
    const uint32_t b = grid.cell_begin(c), e = grid.cell_end(c);
    for (uint32_t s = b; s < e; ++s) rep[s] = s;
    if (e - b < 2) continue;
    order.assign(e - b, 0);
    for (uint32_t s = b; s < e; ++s) order[s - b] = s;
    // Sort by coordinates, then by input index, so each run of equal points starts with its
    // lowest input index. Cells hold a few points unless the cloud is degenerate.
    std::sort(order.begin(), order.end(), [&](uint32_t a, uint32_t bb) {
      const Vec3& p = grid.sorted_point(a);
      const Vec3& q = grid.sorted_point(bb);
      if (p.x != q.x) return p.x < q.x;
      if (p.y != q.y) return p.y < q.y;
      if (p.z != q.z) return p.z < q.z;
      return grid.original_index(a) < grid.original_index(bb);
    });
    for (size_t t = 1; t < order.size(); ++t) {
      if (grid.sorted_point(order[t]) == grid.sorted_point(order[t - 1])) {
        rep[order[t]] = rep[order[t - 1]];
        ++dups;
      }
    }
  }
  if (duplicate_count) *duplicate_count = dups;
  return rep;
}

int neighbor_cells(const NeighborGrid& grid, uint32_t c, uint32_t out[27]) {
  const auto& cc = grid.cell_coord(c);
  int count = 0;
  for (int dx = -1; dx <= 1; ++dx)
    for (int dy = -1; dy <= 1; ++dy)
      for (int dz = -1; dz <= 1; ++dz) {
        const uint32_t nc = grid.find_cell({cc[0] + dx, cc[1] + dy, cc[2] + dz});
        if (nc != NeighborGrid::kNoCell) out[count++] = nc;
      }
  return count;
}

size_t count_occupied_cells(const Vec3* points, size_t n, double h) {
  if (n == 0) return 0;
  Vec3 lo = points[0];
  for (size_t i = 1; i < n; ++i)
    lo = {std::min(lo.x, points[i].x), std::min(lo.y, points[i].y), std::min(lo.z, points[i].z)};
  uint64_t size = 16;
  while (size < 2 * uint64_t(n)) size <<= 1;
  std::vector<std::array<int32_t, 3>> table(size);
  std::vector<uint8_t> used(size, 0);
  const uint64_t mask = size - 1;
  const double inv = 1.0 / h;
  size_t occupied = 0;
  for (size_t i = 0; i < n; ++i) {
    auto axis = [&](double v, double o) {
      return int32_t(std::clamp(std::floor((v - o) * inv), -1.0, double(1 << 30)));
    };
    const std::array<int32_t, 3> c{axis(points[i].x, lo.x), axis(points[i].y, lo.y),
                                   axis(points[i].z, lo.z)};
    uint64_t slot = hash_cell(c) & mask;
    while (used[slot] && table[slot] != c) slot = (slot + 1) & mask;
    if (!used[slot]) {
      used[slot] = 1;
      table[slot] = c;
      ++occupied;
    }
  }
  return occupied;
}

}  // namespace particlemesh::detail
