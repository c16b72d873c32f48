// Internal: NeighborGrid::neighbor_cells for a run of cells taken in increasing order.
#pragma once

#include "particlemesh/core/config.h"

#include <algorithm>
#include <array>
#include <cstdint>
#include <vector>

#include "particlemesh/spatial/neighbor_grid.h"

namespace PM_NAMESPACE::detail {

/// The occupied cells among the 27 around each cell of a walk through the grid's cells in
/// increasing order: the same cells, in the same (increasing) order, as
/// NeighborGrid::neighbor_cells, found without a hash look-up. The grid's cells are sorted by
/// (x, y, z), so as the walk's cell increases, the cells (x + dx, y + dy, z - 1 .. z + 1) of
/// each neighbouring column lie ever further on in that order: one cursor per column offset
/// moves forward over them, reading the cells next to those it read for the previous cell
/// (where a look-up reads a random slot of the hash table). Cells may be skipped; a cell not
/// above the previous one starts the cursors afresh (correct, only slower). One walk per thread.
class NeighborCellWalk {
 public:
  explicit NeighborCellWalk(const NeighborGrid& grid) : grid_(grid) { at_.fill(kUnset); }

  /// Writes the occupied cells around cell c (c included) to `out`; returns how many.
  int around(uint32_t c, uint32_t out[27]) {
    if (c <= last_ && last_ != kUnset) at_.fill(kUnset);
    last_ = c;
    using Coord = NeighborGrid::CellCoord;
    const Coord cc = grid_.cell_coord(c);
    const auto cells = uint32_t(grid_.cell_count());
    int count = 0;
    for (int32_t dx = -1; dx <= 1; ++dx)
      for (int32_t dy = -1; dy <= 1; ++dy) {
        const int32_t x = cc[0] + dx, y = cc[1] + dy;
        if (x < 0 || y < 0) continue;  // no cell has a negative coordinate
        if (dx == 0 && dy == 0) {      // c's own column: c and the cells next to it
          if (c > 0 && grid_.cell_coord(c - 1) == Coord{x, y, cc[2] - 1}) out[count++] = c - 1;
          out[count++] = c;
          if (c + 1 < cells && grid_.cell_coord(c + 1) == Coord{x, y, cc[2] + 1}) out[count++] = c + 1;
          continue;
        }
        const Coord lo{x, y, std::max(cc[2] - 1, int32_t(0))}, hi{x, y, cc[2] + 1};
        uint32_t& at = at_[size_t((dx + 1) * 3 + dy + 1)];
        if (at == kUnset) {
          uint32_t a = 0, b = cells;  // the first cell at or above lo
          while (a < b) {
            const uint32_t mid = a + (b - a) / 2;
            if (grid_.cell_coord(mid) < lo)
              a = mid + 1;
            else
              b = mid;
          }
          at = a;
        }
        while (at < cells && grid_.cell_coord(at) < lo) ++at;
        for (uint32_t b = at; b < cells && !(hi < grid_.cell_coord(b)); ++b) out[count++] = b;
      }
    return count;
  }

 private:
  static constexpr uint32_t kUnset = 0xffffffffu;
  const NeighborGrid& grid_;
  std::array<uint32_t, 9> at_;
  uint32_t last_ = kUnset;
};

/// Per cell of `grid`: 2 where more than `most` of its points are ones `counts` accepts (a
/// crowded cell: a cluster far denser than the cells, whose points are searched on a finer
/// grid instead), 1 where a crowded cell is among its 27 (every point within one cell of a
/// crowded cell's points lies in those), else 0. Empty when no cell is crowded.
template <class Counts>
std::vector<uint8_t> crowded_cells(const NeighborGrid& grid, size_t most, Counts&& counts) {
  const auto cells = uint32_t(grid.cell_count());
  std::vector<uint8_t> take;
  uint32_t around[27];
  NeighborCellWalk walk(grid);
  for (uint32_t c = 0; c < cells; ++c) {
    if (grid.cell_end(c) - grid.cell_begin(c) <= most) continue;
    size_t count = 0;
    for (uint32_t s = grid.cell_begin(c); s < grid.cell_end(c); ++s) count += counts(s) ? 1 : 0;
    if (count <= most) continue;
    if (take.empty()) take.assign(cells, 0);
    take[c] = 2;
    const int na = walk.around(c, around);
    for (int a = 0; a < na; ++a) take[around[a]] = std::max<uint8_t>(take[around[a]], 1);
  }
  return take;
}

}  // namespace particlemesh::detail
