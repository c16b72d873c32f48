// Internal: a mesh's per-vertex arrays with some vertices taken out, the rest kept in order
// (dropping small pieces, collapsing short edges).
#pragma once

#include "particlemesh/core/config.h"

#include <algorithm>
#include <cstdint>
#include <vector>

#include "particlemesh/mesh/tri_mesh.h"

namespace PM_NAMESPACE::detail {

/// Vertex v moves to remap[v], or goes when remap[v] is `gone`; `kept` vertices stay. Moves
/// the positions, the normals and every attribute that has one value set per vertex (an array
/// of another length is left as it is); the triangles are the caller's.
inline void compact_vertices(TriMesh& mesh, const std::vector<uint32_t>& remap, uint32_t kept, uint32_t gone) {
  const size_t nv = remap.size();
  auto compact = [&](auto& values, size_t k) {
    if (values.size() != nv * k) return;
    for (size_t v = 0; v < nv; ++v)
      if (remap[v] != gone)
        for (size_t j = 0; j < k; ++j) values[size_t(remap[v]) * k + j] = values[v * k + j];
    values.resize(size_t(kept) * k);
  };
  compact(mesh.positions, 1);
  compact(mesh.normals, 1);
  for (VertexAttribute& at : mesh.attributes) compact(at.values, size_t(std::max(at.components, 1)));
}

}  // namespace particlemesh::detail
