// What a mesh is, topologically: the facts an artist or a pipeline checks before using it.
#pragma once

#include "particlemesh/core/config.h"

#include <cstddef>
#include <cstdint>
#include <optional>
#include <vector>

#include "particlemesh/core/export.h"
#include "particlemesh/mesh/tri_mesh.h"

namespace PM_NAMESPACE {

/// One edge-connected component of the triangles.
struct ComponentReport {
  size_t triangles = 0;
  size_t vertices = 0;
  size_t edges = 0;
  size_t boundary_edges = 0;     ///< edges with one triangle
  size_t nonmanifold_edges = 0;  ///< edges with more than two triangles
  size_t boundary_loops = 0;
  int64_t euler_characteristic = 0;  ///< V - E + F of this component
  bool closed = false;               ///< no boundary edges and no non-manifold edges
  bool manifold = false;             ///< every edge has <= 2 triangles and every vertex one fan
  bool consistently_oriented = false;
  /// (2 - chi - boundary_loops) / 2 for a manifold component, -1 otherwise.
  int genus = -1;
  /// Signed volume (closed components only, else 0): > 0 when the winding faces outward.
  double signed_volume = 0;
  /// Closed components only: how many other closed components enclose this one. At an odd
  /// depth it is a cavity's wall (a hollow ball's inside), which faces into the cavity: its
  /// signed volume is negative when it faces away from the solid it bounds.
  uint32_t nesting_depth = 0;
};

/// Counts and checks over a whole mesh. Edge statistics use undirected edges.
struct TopologyReport {
  size_t vertices = 0;        ///< vertex array size
  size_t triangles = 0;
  size_t vertices_used = 0;   ///< vertices referenced by at least one triangle
  size_t edges = 0;
  size_t boundary_edges = 0;     ///< shared by exactly 1 triangle
  size_t manifold_edges = 0;     ///< shared by exactly 2 triangles
  size_t nonmanifold_edges = 0;  ///< shared by more than 2 triangles
  size_t nonmanifold_vertices = 0;  ///< used vertices whose triangles are not one fan
  size_t degenerate_triangles = 0;  ///< repeated vertex index or zero area
  size_t duplicate_triangles = 0;   ///< same three vertices as an earlier triangle
  size_t orientation_conflicts = 0; ///< 2-triangle edges traversed the same way by both
  size_t boundary_loops = 0;
  size_t components = 0;
  size_t closed_components = 0;
  int64_t euler_characteristic = 0;  ///< vertices_used - edges + triangles
  bool manifold = false;              ///< no non-manifold edges or vertices
  bool closed = false;                ///< manifold and no boundary edges (and not empty)
  bool consistently_oriented = false; ///< no orientation conflicts and no edge with > 2 faces
  /// Every closed component faces away from the solid it bounds: positive signed volume, or
  /// negative for a cavity's wall (odd nesting_depth); false without closed components.
  bool outward = false;
  std::vector<ComponentReport> per_component;  ///< largest first (then by lowest triangle)
  /// The edges of each boundary loop, smallest first (holes by size: a scan's sampling gaps
  /// are loops of a few edges, its real openings long ones).
  std::vector<size_t> boundary_loop_edges;
};

/// Compute the report. O(F log F).
/// Boundary loops are traced around vertex fans where the mesh is manifold and consistently
/// oriented (so two loops that touch at a pinched vertex count as two); elsewhere they are the
/// connected components of the boundary-edge graph.
PM_EXPORT TopologyReport topology_report(const TriMesh& mesh);

/// topology_report(refined), derived from the report of the mesh it was subdivided from,
/// when `refined` is `levels` rounds of uniform 1-to-4 splits of that mesh (Loop
/// subdivision: each edge halved by a new vertex, each triangle into its three corner
/// triangles and the middle one, every vertex kept; smooth_mesh's output of a mesh that
/// had no unreferenced vertex). Only the positions decide what is left to measure on
/// `refined` (zero-area triangles, the signed volume: one O(F) pass instead of the full
/// report's), so it is exactly the report topology_report(refined) gives. Returns nullopt,
/// and the caller takes the full report, unless `control` is one closed, manifold,
/// consistently oriented component whose every vertex is used and without duplicate
/// triangles (then one split keeps all of that, by induction: see the source), and the
/// refined vertex and triangle counts are those of such splits, and every index is in range.
PM_EXPORT std::optional<TopologyReport> subdivided_topology_report(const TopologyReport& control,
                                                                   const TriMesh& refined, int levels);

}  // namespace particlemesh
