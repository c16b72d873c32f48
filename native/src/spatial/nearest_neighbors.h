// Internal: the k nearest neighbours of every point of a NeighborGrid (the local spacing's
// neighbourhoods).
#pragma once

#include "particlemesh/core/config.h"

#include <cstdint>
#include <vector>

#include "core/progress_tracker.h"
#include "particlemesh/spatial/neighbor_grid.h"

namespace PM_NAMESPACE::detail {

/// Marks "no neighbour" in nearest_neighbors' lists.
inline constexpr uint32_t kNoNeighbor = 0xffffffffu;
/// Rings of cells searched at most around a point (a point farther than this from its
/// neighbours' cells keeps what it found).
inline constexpr int32_t kMaxNeighborRing = 24;

/// The k (1..64) nearest distinct neighbours (at a distance > 0) of each point, as sorted
/// indices of `grid`, k per point, nearest first (ties by distance, then index); kNoNeighbor
/// where a point has fewer within reach. A point's neighbours are searched in rings of cells
/// around its cell, from ring 2 on, until k lie within the rings' reach (ring x cell size);
/// at ring kMaxNeighborRing whatever the rings hold is taken. Surface samplings want a cell
/// of about twice their spacing (k = 16 then lie within ring 2). The same for any thread count.
std::vector<uint32_t> nearest_neighbors(const NeighborGrid& grid, int k, ProgressTracker& tracker);

}  // namespace particlemesh::detail
