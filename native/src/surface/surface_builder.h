// Internal: grows a consistently oriented 2-manifold from the seed's candidate triangles and
// repairs what growth leaves (holes, pinched vertices).
//
// The rules, in the order they matter (measured in shared/notes/manifold-extraction.md):
//  1. Every candidate is oriented by the particles' normals, and each directed edge may be
//     used by one triangle only: no edge can get a third triangle and neighbours always agree
//     on the winding.
//  2. Wedge rule: at each vertex, the new triangle's angular wedge in the vertex's tangent
//     plane must not overlap the wedges already there; fans stay disks and sheets that merely
//     touch are not joined (genus stays right).
//  3. Growth runs best-first from the front of the surface built so far; a candidate that
//     would start a second fan at a vertex (a pinch) waits until nothing else is left;
//     a new seed is only taken when the front is exhausted. It runs in parallel in fixed
//     blocks of points, then across the seams between them, where no flat candidate is
//     taken (see Builder::grow()).
//  4. Repair in a fixed order: split boundary loops at repeated vertices, fill small loops,
//     keep only the largest fan at each pinched vertex, then fill the larger loops whose
//     fill stays within the edge limit (real openings are wider than that and stay open).
#pragma once

#include <cstdint>
#include <vector>

#include "core/progress_tracker.h"
#include "particlemesh/core/vec3.h"
#include "particlemesh/mesh/tri_mesh.h"

namespace particlemesh::detail {

struct BuilderOptions {
  double cos_normal_angle = -0.5;  ///< co-normality: corner normals and face normal agree within
  double max_edge = 0;            ///< L of the raw test
  size_t small_hole = 6;          ///< loops up to this many edges are filled before unpinching
  size_t max_hole = 100;          ///< loops up to this many edges may be filled (0 = none)
  double fill_edge_factor = 1.5;  ///< fill triangles' edges at most this x L
};

struct BuilderStats {
  size_t candidates = 0;          ///< oriented candidates after co-normality
  size_t rejected_conormal = 0;   ///< raw triangles dropped by co-normality
  size_t grown = 0;               ///< triangles accepted by growth
  size_t seeds = 0;
  size_t pinches_resolved = 0;    ///< fans removed at pinched vertices
  size_t holes_filled = 0;
  size_t hole_triangles = 0;
  size_t holes_left = 0;          ///< boundary loops left open
  size_t largest_hole_left = 0;   ///< edges of the largest loop left open
  size_t components_flipped = 0;  ///< closed components turned to face outward
  size_t unused_points = 0;       ///< distinct points in no triangle
  double seconds_candidates = 0, seconds_growth = 0, seconds_repair = 0;
  std::vector<uint64_t> boundary;  ///< boundary half-edges (a << 32 | b), sorted
  std::vector<std::pair<size_t, double>> open_loops;  ///< (edges, width / L) of loops left open
};

/// positions/normals (normals unit or zero = unknown); `active[i]` false for duplicates; `raw`
/// the seed's triangles. Returns oriented triangles, and in `vertex_normals` the surface's
/// angle-weighted vertex normals (a point in no triangle keeps its normal).
std::vector<Triangle> build_surface(const std::vector<Vec3>& positions, const std::vector<Vec3>& normals,
                                    const std::vector<uint8_t>& active, const std::vector<Triangle>& raw,
                                    const BuilderOptions& options, bool repair, BuilderStats& stats,
                                    ProgressTracker& tracker, std::vector<Vec3>& vertex_normals);

/// Turn every closed component (one holding none of the `boundary` half-edges) so that it
/// encloses positive volume, negating its points' `vertex_normals` (if given) to match;
/// returns how many flipped.
size_t orient_closed_components_outward(const std::vector<Vec3>& positions, std::vector<Triangle>& triangles,
                                        const std::vector<uint64_t>& boundary,
                                        std::vector<Vec3>* vertex_normals = nullptr);

}  // namespace particlemesh::detail
