// Internal: NeighborGrid::neighbor_cells for a run of cells taken in increasing order.
#pragma once

#include "particlemesh/core/config.h"

#include <algorithm>
#include <array>
#include <cstdint>

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

}  // namespace particlemesh::detail
