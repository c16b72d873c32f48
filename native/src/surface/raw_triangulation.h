// Internal: the raw smallest-sphere test (Tonnesen) with its working data kept, so that the
// finishing stages (normals, extraction, hole filling) reuse the grid and the neighbour lists.
#pragma once

#include "particlemesh/core/config.h"

#include <cmath>
#include <memory>
#include <vector>

#include "core/progress_tracker.h"
#include "particlemesh/spatial/neighbor_grid.h"
#include "particlemesh/spatial/spacing.h"
#include "particlemesh/surface/triangulate.h"
#include "surface/neighbor_lists.h"

namespace PM_NAMESPACE::detail {

struct RawTriangulation {
  TriangulateStats stats;
  std::unique_ptr<NeighborGrid> grid;  ///< points in cell order (sorted indices)
  std::vector<uint32_t> rep;           ///< sorted index -> sorted index of its representative
  /// Sorted indices: s's list holds every t within 2 max(L_s, L_t) / sqrt(3).
  NeighborLists neighbors;
  /// Per sorted index: the point's edge limit L_s (every point's is stats.max_edge unless a
  /// local spacing was given). An edge (s, t) may be up to pair_limit(L_s, L_t) long.
  std::vector<double> max_edge;
  /// The longest edge any point's limit allows (with a local spacing: max_edge_factor x
  /// kMaxLocalSpacing x r0 x stats.reach_factor); the repair holds its triangles to it too.
  /// Infinite otherwise.
  double edge_cap = INFINITY;
  /// (a < b < c), sorted; original indices, or sorted ones when asked for (see below).
  std::vector<Triangle> triangles;
};

/// The longest edge allowed between two points with edge limits la and lb: their mean (the
/// limit halfway along the edge, where the local spacing varies). Equal limits give that limit
/// exactly.
inline double pair_limit(double la, double lb) { return 0.5 * (la + lb); }

/// The indices `RawTriangulation::triangles` are given in. The finishing stages take sorted
/// (cell order) indices: no mapping and no sort, and the triangles come in space-filling order.
enum class TriangleIndices { Original, Sorted };

/// Validates options and cloud, then runs the test. Call inside detail::with_threads.
/// Progress goes to [begin, end) of the tracker's overall fraction. With `local_spacing` each
/// point's edge limit is max_edge_factor x its own spacing (estimate_local_spacing, scaled by
/// r0 / the measured median nearest-neighbour distance when options.spacing gives r0, and by
/// the sampling's reach factor, irregular_reach) instead of max_edge_factor x r0; the test
/// itself is unchanged. `known`: the cloud's spacing estimate (estimate_spacing_impl), when
/// the caller already took it.
RawTriangulation run_raw_triangulation(const PointCloud& cloud, const TriangulateOptions& options,
                                       ProgressTracker& tracker, double begin, double end,
                                       TriangleIndices indices = TriangleIndices::Original,
                                       bool local_spacing = false, const SpacingEstimate* known = nullptr);

}  // namespace particlemesh::detail
