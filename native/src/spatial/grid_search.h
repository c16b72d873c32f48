// Internal helpers over NeighborGrid used by the spacing estimate and the triangulation.
#pragma once

#include <cstdint>
#include <vector>

#include "particlemesh/spatial/neighbor_grid.h"

namespace particlemesh::detail {

/// For every sorted index s: the sorted index of the lowest-input-index point with exactly the
/// same coordinates (s itself when the point is distinct). Identical points share a cell.
std::vector<uint32_t> find_duplicates(const NeighborGrid& grid, size_t* duplicate_count);

/// The occupied cells among the 27 around cell `c` (including c), in lexicographic order of
/// their coordinates, so points come out in increasing sorted index.
int neighbor_cells(const NeighborGrid& grid, uint32_t c, uint32_t out[27]);

/// Number of occupied cells of edge h (a hash set; no sorting). Used to size grids.
size_t count_occupied_cells(const Vec3* points, size_t n, double h);

}  // namespace particlemesh::detail
