// Internal: compressed lists of each point's neighbours within a radius.
#pragma once

#include "particlemesh/core/config.h"

#include <cstdint>
#include <vector>

#include "core/progress_tracker.h"
#include "core/uninit_allocator.h"
#include "particlemesh/spatial/neighbor_grid.h"

namespace PM_NAMESPACE::detail {

/// CSR over sorted indices: neighbours of s are index[offset[s] .. offset[s+1]), ascending,
/// excluding s itself and every point whose rep != itself (exact duplicates). Points that are
/// duplicates get empty lists.
struct NeighborLists {
  std::vector<uint64_t> offset;
  /// (Filled whole by a parallel pass: left uninitialised, not zeroed on one core first.)
  std::vector<uint32_t, UninitAllocator<uint32_t>> index;
  size_t max_count = 0;
  uint32_t max_point = 0;  ///< sorted index of a point with max_count neighbours
  size_t shortened = 0;    ///< radii shortened to hold max_neighbors (the per-point build's `shorten`)

  const uint32_t* begin(uint32_t s) const { return index.data() + offset[s]; }
  const uint32_t* end(uint32_t s) const { return index.data() + offset[s + 1]; }
};

/// `grid` must have cells of edge >= radius. Fails with LimitExceeded when some point has
/// more than max_neighbors neighbours (naming the lowest input index among them).
NeighborLists build_neighbor_lists(const NeighborGrid& grid, const std::vector<uint32_t>& rep,
                                   double radius, size_t max_neighbors,
                                   ProgressTracker& tracker);

/// The same over a radius per point (sorted index): s's list holds every t with
/// |s t| <= max(radius[s], radius[t]) (so t is in s's list iff s is in t's). Any cell size.
/// Without `shorten` it fails as above when a list holds more than max_neighbors. With it, a
/// point whose own radius holds more than max_neighbors others gets the longest radius that
/// holds at most max_neighbors (written to `radius`; NeighborLists::shortened counts them),
/// and a list may then hold more through the radii of others (at most max_neighbors of its
/// own, so the lists hold at most 2 max_neighbors per point on average).
NeighborLists build_neighbor_lists(const NeighborGrid& grid, const std::vector<uint32_t>& rep,
                                   std::vector<double>& radius, size_t max_neighbors, bool shorten,
                                   ProgressTracker& tracker);

}  // namespace particlemesh::detail
