// Internal: the short edges of a closed, oriented 2-manifold collapsed, each into one vertex,
// keeping it a closed, oriented 2-manifold: marching cubes' slivers (the thin triangles where
// the surface passes close to a lattice node, whose crossings on that node's edges all lie
// next to it) become ordinary triangles, as the vertex clustering of Moore and Warren
// ("Compact isocontours from sampled data", Graphics Gems III, 1992) makes them, but by
// checked edge collapses (Hoppe et al., "Mesh optimization", 1993) so that no configuration
// can pinch the surface.
//
// Written here rather than taken from OpenMesh's decimater (OpenMesh::Decimater with
// ModEdgeLength and ModNormalFlipping does the same collapses): the merged vertex is placed on
// the implicit surface by the caller while the collapse is being checked, and polygonize's
// 1.5M-triangle meshes would be copied into and out of OpenMesh's half-edge mesh for a pass
// touching a few percent of its edges.
#pragma once

#include "particlemesh/core/config.h"

#include <cstddef>
#include <cstdint>
#include <functional>
#include <vector>

#include "particlemesh/mesh/tri_mesh.h"

namespace PM_NAMESPACE::detail {

struct ShortEdgeCollapse {
  size_t collapsed = 0;         ///< edges collapsed: vertices removed (2 triangles each)
  std::vector<uint32_t> moved;  ///< the vertices that took in others (their new indices, ascending)
};

/// Collapses the edges of `mesh` shorter than `max_length`, one at a time, shortest first (ties
/// by their vertices' indices), each into the point place(a, b) gives for its ends' positions
/// a and b (the later vertex is removed, the earlier takes the place). An edge is collapsed
/// only where that keeps the surface a 2-manifold: the edge lies in exactly two triangles that
/// run it opposite ways, its ends share no neighbour but those two triangles' third corners
/// (the link condition), every vertex keeps at least three neighbours, and no other triangle
/// at its ends turns by more than acos(min_cos) or loses its area. Edges on a boundary or in
/// more than two triangles, and the edges of vertices on them, are left alone, as is an edge
/// no longer shorter than max_length when its turn comes (an end moved). The merged vertex
/// gets the normalised sum of both normals and the mean of both attribute values (the caller
/// may set better ones: `moved`). Vertices and triangles keep their order, less the removed
/// ones; a vertex no triangle used stays. `place` is called from several threads (it must be
/// safe to); the result does not depend on their number.
/// `check` (when given) is called on the calling thread every few thousand edges, so that a
/// long run can be cancelled by its throwing; the mesh is then left half done.
ShortEdgeCollapse collapse_short_edges(TriMesh& mesh, double max_length, double min_cos,
                                       const std::function<Vec3(const Vec3&, const Vec3&)>& place,
                                       const std::function<void()>& check = {});

}  // namespace particlemesh::detail
