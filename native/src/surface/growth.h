// Internal: manifold extraction by best-first growth over the ranked candidates.
//
//  1. Every candidate is oriented by the particles' normals (see candidates.h), and each
//     directed edge may be used by one triangle only: no edge can get a third triangle and
//     neighbours always agree on the winding.
//  2. Wedge rule: at each vertex, the new triangle's angular wedge in the vertex's tangent
//     plane must not overlap the wedges already there; fans stay disks and sheets that merely
//     touch are not joined (genus stays right).
//  3. Growth runs best-first from the front of the surface built so far; a candidate that
//     would start a second fan at a vertex (a pinch) waits until nothing else is left;
//     a new seed is only taken when the front is exhausted. It runs in parallel in fixed
//     blocks of points, then across the seams between them, where no flat candidate is
//     taken (see growth.cpp).
#pragma once

#include "particlemesh/core/config.h"

#include <cstddef>
#include <cstdint>
#include <vector>

#include "core/progress_tracker.h"
#include "particlemesh/mesh/tri_mesh.h"
#include "surface/candidates.h"

namespace PM_NAMESPACE::detail {

struct GrownSurface {
  /// The accepted triangles in space order: each at its lowest vertex, in rank order there.
  std::vector<Triangle> triangles;
  /// The candidates' corner lists, with each vertex's accepted corners leading its list:
  /// accepted_count[v] of them.
  std::vector<Corner, UninitAllocator<Corner>> corners;
  std::vector<uint32_t> corner_offset;
  std::vector<uint32_t> accepted_count;
  size_t grown = 0;  ///< triangles accepted
  size_t seeds = 0;  ///< growth regions started
};

/// Grow the surface over `points` vertices from their ranked candidates (consumed).
/// The result does not depend on the thread count.
GrownSurface grow_surface(size_t points, CandidateSet&& candidates, ProgressTracker& tracker);

}  // namespace particlemesh::detail
