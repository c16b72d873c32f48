// The edges of a triangle mesh, numbered, and each triangle corner's edge: what a host
// application with an edge list (Blender) otherwise derives by hashing every corner itself.
#pragma once

#include "particlemesh/core/config.h"

#include <array>
#include <cstdint>
#include <vector>

#include "particlemesh/core/export.h"
#include "particlemesh/mesh/tri_mesh.h"

namespace PM_NAMESPACE {

struct MeshEdges {
  /// Each edge once as (a, b), a < b: ordered by a, then b (the same for any thread count).
  std::vector<std::array<uint32_t, 2>> edges;
  /// Per triangle corner (3 t + k): the edge from corner k to corner k + 1 (mod 3).
  std::vector<uint32_t> corner_edges;
};

/// The edges of `triangles` over `vertex_count` vertices, in parallel (`threads`, 0 = all).
/// @throws Error(InvalidArgument) naming the triangle with an index >= vertex_count or a
/// repeated vertex (such a triangle has no three edges). Keeps up to 64 MiB of working memory
/// (8 bytes a corner) for the next call, which then faults in no fresh pages for it.
PM_EXPORT MeshEdges mesh_edges(const std::vector<Triangle>& triangles, size_t vertex_count, int threads = 0);

}  // namespace particlemesh
