// Internal: the control mesh both subdivision schemes start from.
//
// OpenSubdiv and OpenMesh each reject (or misbehave on) some input: OpenMesh's add_face
// refuses complex edges and vertices, its butterfly indexes weight tables by valence, and
// OpenSubdiv wants every vertex referenced. prepare_control_mesh() checks the input once,
// with messages in the caller's indices, and hands both schemes the same clean mesh.
#pragma once

#include "particlemesh/core/config.h"

#include <cstdint>
#include <utility>
#include <vector>

#include "particlemesh/mesh/tri_mesh.h"

namespace PM_NAMESPACE::detail {

class ProgressTracker;

struct ControlMesh {
  std::vector<Vec3> positions;                ///< referenced input vertices, input order
  std::vector<Triangle> triangles;            ///< in control indices, orientation repaired
  std::vector<VertexAttribute> attributes;    ///< compacted like positions
  std::vector<uint32_t> original_vertex;      ///< control index -> input index
  std::vector<uint32_t> control_index;        ///< input index -> control index (kDropped)
  /// Undirected edges as (min, max) input-index pairs, sorted: the crease lookup.
  std::vector<std::pair<uint32_t, uint32_t>> edges;
  size_t boundary_edges = 0;
  size_t nonmanifold_edges = 0;     ///< edges in more than two triangles (allowed for Loop only)
  size_t nonmanifold_vertices = 0;  ///< vertices joining several fans (allowed for Loop only)
  size_t reoriented_triangles = 0;
  size_t dropped_vertices = 0;
  /// Closed components whose orientation was repaired: which way they face came from their
  /// signed volume, so from the positions. Per component: its triangles in flood-fill order,
  /// each one's flip relative to the first, and whether the whole was then turned outward.
  struct VolumeDecision {
    std::vector<uint32_t> triangles;
    std::vector<uint8_t> flips;
    bool turned = false;
  };
  std::vector<VolumeDecision> volume_decisions;

  static constexpr uint32_t kDropped = UINT32_MAX;
};

/// Check `mesh` (see smooth/subdivide.h for the rules), drop unreferenced vertices and
/// repair the orientation. Parallel parts run in the caller's thread arena. With
/// `allow_nonmanifold` (Loop: OpenSubdiv subdivides them) edges in more than two triangles and
/// vertices joining several fans pass; else they are errors (OpenMesh's butterfly).
/// @throws Error(InvalidInput | LimitExceeded) naming the triangle, edge or vertex.
ControlMesh prepare_control_mesh(const TriMesh& mesh, bool allow_nonmanifold);

/// The positions and attribute values of the referenced vertices (`original_vertex`, in
/// control order), checked as prepare_control_mesh checks them: attribute sizes, finite and
/// not too large values (Error(InvalidInput) naming the vertex).
void compact_vertex_values(const std::vector<Vec3>& positions, const std::vector<VertexAttribute>& attributes,
                           const std::vector<uint32_t>& original_vertex, std::vector<Vec3>* out_positions,
                           std::vector<VertexAttribute>* out_attributes);

/// Whether the repaired closed components of `mesh` (same triangles as the control mesh was
/// made from) would be turned outward with these positions as they were (see
/// ControlMesh::volume_decisions): when not, the repaired orientation differs.
bool same_volume_decisions(const ControlMesh& control, const std::vector<Triangle>& triangles,
                           const std::vector<Vec3>& positions);

/// Area-weighted unit vertex normals (sum of the adjacent triangles' cross products).
/// A vertex whose sum vanishes gets (0, 0, 0).
std::vector<Vec3> area_weighted_normals(const std::vector<Vec3>& positions,
                                        const std::vector<Triangle>& triangles);

}  // namespace particlemesh::detail
