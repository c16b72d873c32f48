// Internal: Loop's exact limit positions and normals on a closed surface, in parallel.
//
// OpenSubdiv's PrimvarRefiner::Limit applies Loop's limit masks (Sdc::Scheme<SCHEME_LOOP>)
// vertex by vertex on one thread, and needs the full topology of the last refined level
// (edges, vertex-face and vertex-edge relations: about 40 % more memory and refinement time
// than its face-vertex lists). On a closed 2-manifold without creases every vertex follows
// the smooth rule, whose masks depend on the valence only: so here the masks come from the
// same Sdc::Scheme, once per valence, and are applied over each vertex's ring of neighbours
// (counter-clockwise, from its lowest neighbour) on all cores. The rings come from the level
// before the last, which OpenSubdiv keeps whole (loop_limit_refined: smooth_mesh), or from the
// last level's triangles (build_loop_rings: the Smoother, which keeps them, and level 0);
// both give the same rings, so the same bits. The positions agree with PrimvarRefiner::Limit
// to rounding (the sums may start at another neighbour); the normals are normalize(T1 x T2)
// as there. Meshes with a boundary or a crease keep OpenSubdiv's own limit.
#pragma once

#include <cstdint>
#include <vector>

#include <opensubdiv/far/topologyLevel.h>

#include "particlemesh/core/vec3.h"
#include "particlemesh/mesh/tri_mesh.h"

namespace PM_NAMESPACE::detail {

/// Every vertex's neighbours in counter-clockwise order seen from outside (the triangles'
/// winding), starting at its lowest-numbered neighbour (so that sums over a ring do not
/// depend on the order of the triangles or of their corners).
struct LoopRings {
  std::vector<uint32_t> offset;  ///< vertex count + 1
  std::vector<uint32_t> ring;
  int max_valence = 0;
};

/// The rings of a closed, consistently wound triangle mesh in which every vertex's
/// triangles form one closed fan. Returns false (and leaves `out` unspecified) when some
/// vertex's triangles do not: such a mesh takes OpenSubdiv's limit.
bool build_loop_rings(const std::vector<Triangle>& triangles, size_t vertex_count, LoopRings* out);

/// Loop's smooth-rule limit masks (Sdc::Scheme<SCHEME_LOOP>), per valence up to `max_valence`.
class LoopLimitMasks {
 public:
  explicit LoopLimitMasks(int max_valence);
  double vertex_weight(int valence) const { return vertex_[size_t(valence)]; }
  /// The position's edge weight (the same for every neighbour).
  double edge_weight(int valence) const { return edge_[size_t(valence)]; }
  /// The tangents' edge weights, `valence` each (their vertex weights are 0).
  const double* tangent1(int valence) const { return tan1_.data() + start_[size_t(valence)]; }
  const double* tangent2(int valence) const { return tan2_.data() + start_[size_t(valence)]; }

 private:
  std::vector<double> vertex_, edge_, tan1_, tan2_;
  std::vector<size_t> start_;
};

/// Limit positions and unit normals (zero where the tangents' cross product vanishes in
/// rounding: degenerate geometry; the caller fills those) of the points `src` of the level
/// the rings describe, in the order PrimvarRefiner::Limit sums them (edge weights, then the
/// vertex). `pos` and `normals` are resized to the vertex count.
void loop_limit_positions(const LoopRings& rings, const LoopLimitMasks& masks, const std::vector<Vec3>& src,
                          std::vector<Vec3>& pos, std::vector<Vec3>& normals);

/// The same for `channels` doubles per vertex (attributes): positions' masks only.
void loop_limit_channels(const LoopRings& rings, const LoopLimitMasks& masks, const double* src, int channels,
                         double* dst);

/// The limit of the last level of a uniform Loop refinement of a closed surface without
/// creases, each vertex's ring read from the level before it (`parent`, which OpenSubdiv
/// keeps with its full topology): a refined vertex's triangles are among the child faces
/// of its parent vertex's or parent edge's faces. No bucketing of all the last level's
/// triangles, no ring arrays: one pass over the parent's vertices and edges gives the
/// limit positions, unit normals (zero where the tangents' cross product vanishes) and
/// `channels` limit channels per vertex, exactly as loop_limit_positions and
/// loop_limit_channels do with build_loop_rings' rings. `src` (and `channels_src`) are the
/// last level's points; `pos` and `normals` are resized, `channels_dst` has room for them.
/// Returns false (outputs unspecified) when some vertex's triangles are not one closed fan.
bool loop_limit_refined(const OpenSubdiv::Far::TopologyLevel& parent, const OpenSubdiv::Far::TopologyLevel& last,
                        const std::vector<Vec3>& src, const double* channels_src, int channels, std::vector<Vec3>& pos,
                        std::vector<Vec3>& normals, double* channels_dst);

}  // namespace particlemesh::detail
