// Internal: OpenSubdiv's Loop refinement of a control mesh and the pieces around it (attribute
// channels, OpenSubdiv's limit), shared by smooth_mesh() and the refine-once Smoother
// (smoother.h); implemented in loop_opensubdiv.cpp.
#pragma once

#include <cstdint>
#include <memory>
#include <utility>
#include <vector>

#include <opensubdiv/far/topologyRefiner.h>

#include "particlemesh/core/vec3.h"
#include "particlemesh/mesh/tri_mesh.h"
#include "particlemesh/smooth/subdivide.h"
#include "smooth/control_mesh.h"

namespace PM_NAMESPACE::detail {

/// Far::TopologyRefiner for the control mesh under Loop's rules (boundary rule, creases and
/// crease method from the options), refined uniformly to options.levels; with
/// `full_last_level` the last level also gets its edges and incidences (OpenSubdiv's limit
/// masks need them).
std::unique_ptr<OpenSubdiv::Far::TopologyRefiner> loop_refiner(const ControlMesh& control, const SmoothOptions& options,
                                                               const std::vector<std::pair<uint32_t, uint32_t>>& crease_pairs,
                                                               const std::vector<float>& crease_sharpness,
                                                               bool full_last_level);

/// The triangles of a refined level (all Loop's levels are triangles), in its face order.
void copy_triangles(const OpenSubdiv::Far::TopologyLevel& level, std::vector<Triangle>& out);

/// Whether the limit is taken by loop_limit.h (a closed surface without creases) rather than
/// by OpenSubdiv's PrimvarRefiner::Limit.
inline bool own_loop_limit(const ControlMesh& control, const SmoothOptions& options, size_t creases) {
  return options.limit && control.boundary_edges == 0 && creases == 0 && control.nonmanifold_edges == 0 &&
         control.nonmanifold_vertices == 0;
}

/// Every attribute's values as doubles, vertex-major: vertex i's channels are
/// [i * channels, (i + 1) * channels), the attributes one after another. `*channels` is set to
/// the sum of their components.
std::vector<double> interleave_channels(const std::vector<VertexAttribute>& attributes, size_t vertex_count,
                                        int* channels);

/// The inverse of interleave_channels for `vertex_count` (refined) vertices: attributes named
/// and shaped as `like`, their values the channels rounded to float.
std::vector<VertexAttribute> split_channels(const std::vector<VertexAttribute>& like, const std::vector<double>& values,
                                            int channels, size_t vertex_count);

/// OpenSubdiv's limit (PrimvarRefiner::Limit) on the last level of `refiner` (refined with its
/// full last level): `positions` and `values` (interleaved channels) of that level's vertices
/// are replaced by their limits; `normals` gets normalize(T1 x T2) of the limit tangents, or a
/// zero vector where the tangents are (nearly) parallel, which smooth_mesh() replaces by
/// area-weighted normals.
void opensubdiv_limit(const OpenSubdiv::Far::TopologyRefiner& refiner, std::vector<Vec3>& positions,
                      std::vector<double>& values, int channels, std::vector<Vec3>& normals);

}  // namespace particlemesh::detail
