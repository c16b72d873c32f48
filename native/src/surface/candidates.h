// Internal: the candidates of the surface extraction - the raw triangles that pass
// co-normality, oriented by the normals and ranked best first - with each vertex's corners.
//
// Co-normality (Tonnesen's thesis, section 5.2.4): a triangle's corner normals agree with
// each other within the co-normality angle (above 90 degrees: a sharp crease's sides, up to
// 180 - angle of dihedral), and its face normal agrees with every corner's within that angle
// and never beyond 90 degrees (a face turned away from a corner's normal is not the surface
// there). Sheets with opposite normals, folds and the faces of tetrahedral bridges fail it.
//
// Rank: the smallest largest angle first (the Delaunay diagonal of a quad beats the
// overlapping obtuse triangle), then the raw order - deterministic.
#pragma once

#include "particlemesh/core/config.h"

#include <cstddef>
#include <cstdint>
#include <memory>
#include <utility>
#include <vector>

#include "core/progress_tracker.h"
#include "core/uninit_allocator.h"
#include "particlemesh/core/vec3.h"
#include "particlemesh/mesh/tri_mesh.h"
#include "surface/tangent_arcs.h"
#include "surface/view_rays.h"

namespace PM_NAMESPACE::detail {

/// A candidate's corner at a vertex: the candidate, the vertices after and before the
/// vertex in its winding, and its arc about the vertex normal. Kept per vertex, so that the
/// growth tests read one short contiguous list instead of the candidates scattered in memory.
struct Corner {
  uint32_t c, succ, pred;
  Arc arc;
};

/// -cos(150 degrees): candidates whose largest angle is over 150 degrees are "flat" (nearly
/// collinear particles; see the growth).
constexpr float kFlatQuality = 0.866f;

struct CandidateSet {
  std::vector<Triangle> cand;  ///< by rank: oriented (wound about the normals), best first
  /// Vertex v's corners are corners[corner_offset[v] .. corner_offset[v + 1]). Within a list
  /// the order depends on the threads: read each list as a set.
  std::vector<Corner, UninitAllocator<Corner>> corners;
  std::vector<uint32_t> corner_offset;
  /// Candidates ranked from here on are flat: largest angle over 150 degrees.
  uint32_t flat_from = 0;
  size_t rejected_conormal = 0;  ///< raw triangles dropped by co-normality (or at an inactive/normal-less point)
  size_t rejected_shadow = 0;    ///< raw triangles dropped for bridging a depth jump (view_rays.h)
};

/// Tangent frames of the (unit or zero) normals; zero normals get none.
std::vector<Frame> tangent_frames(const std::vector<Vec3>& normals);

/// The candidates among `raw` (sorted indices): corners active, with non-zero normals, and
/// co-normal within cos_normal_angle (the face within max(cos_normal_angle, 0)); with an
/// active `view`, no edge along a view ray.
CandidateSet rank_candidates(const std::vector<Vec3>& positions, const std::vector<Vec3>& normals,
                             const std::vector<Frame>& frames, const std::vector<uint8_t>& active,
                             const std::vector<Triangle>& raw, double cos_normal_angle, ProgressTracker& tracker,
                             const ViewRays& view = {});

}  // namespace particlemesh::detail
