// Internal: the seed's raw test with its working data kept, so that the finishing stages
// (normals, extraction, hole filling) reuse the grid and the neighbour lists.
#pragma once

#include <memory>
#include <vector>

#include "core/progress_tracker.h"
#include "particlemesh/spatial/neighbor_grid.h"
#include "particlemesh/surface/triangulate.h"
#include "surface/neighbor_lists.h"

namespace particlemesh::detail {

struct RawTriangulation {
  TriangulateStats stats;
  std::unique_ptr<NeighborGrid> grid;  ///< points in cell order (sorted indices)
  std::vector<uint32_t> rep;           ///< sorted index -> sorted index of its representative
  NeighborLists neighbors;             ///< sorted indices, within 2L/sqrt(3)
  double neighbor_radius = 0;
  /// (a < b < c), sorted; original indices, or sorted ones when asked for (see below).
  std::vector<Triangle> triangles;
};

/// The indices `RawTriangulation::triangles` are given in. The finishing stages take sorted
/// (cell order) indices: no mapping and no sort, and the triangles come in space-filling order.
enum class TriangleIndices { Original, Sorted };

/// Validates options and cloud, then runs the test. Call inside detail::with_threads.
/// Progress goes to [begin, end) of the tracker's overall fraction.
RawTriangulation run_raw_triangulation(const PointCloud& cloud, const TriangulateOptions& options,
                                       ProgressTracker& tracker, double begin, double end,
                                       TriangleIndices indices = TriangleIndices::Original);

}  // namespace particlemesh::detail
