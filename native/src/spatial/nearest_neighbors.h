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

/// The cell nearest_neighbors searches `grid`'s points in: the grid's own (0 returned), unless
/// a sample of 512 of its points has its k-th nearest farther than 1.6 of its cells (points
/// dropped at random on a surface: the median nearest distance, which sets the grid, is short
/// against the 16th, at about 2.4 cells, and 90 % of such a search went on to ring 3, its
/// costliest part); then one that brings the sample's median k-th nearest to 1.6 cells (at
/// most twice the grid's), so that ring 2 holds it for most points. The lists are the grid's
/// own either way: ties are broken by the grid's indices, and the points whose k nearest the
/// grid's own rings would not reach are searched on it. Clouds under 4096 points keep it.
double nearest_neighbors_cell(const NeighborGrid& grid, size_t k);

}  // namespace particlemesh::detail
