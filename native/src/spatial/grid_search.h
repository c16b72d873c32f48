// Internal helpers over NeighborGrid used by the spacing estimate and the triangulation.
#pragma once

#include "particlemesh/core/config.h"

#include <cstdint>
#include <vector>

#include "particlemesh/spatial/neighbor_grid.h"

namespace PM_NAMESPACE::detail {

/// For every sorted index s: the sorted index of the lowest-input-index point with exactly the
/// same coordinates (s itself when the point is distinct). Identical points share a cell.
std::vector<uint32_t> find_duplicates(const NeighborGrid& grid, size_t* duplicate_count);

}  // namespace particlemesh::detail
