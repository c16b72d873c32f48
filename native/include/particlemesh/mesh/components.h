// Connected pieces of a triangle mesh, their enclosed volumes, and dropping the small ones
// (the splashes and lone droplets of a fluid surface, the specks of a scan).
#pragma once

#include "particlemesh/core/config.h"

#include <cstddef>
#include <cstdint>
#include <vector>

#include "particlemesh/core/export.h"
#include "particlemesh/mesh/tri_mesh.h"

namespace PM_NAMESPACE {

struct MeshComponents {
  /// Per vertex: its component, or UINT32_MAX for a vertex no triangle uses. Components are
  /// numbered in the order of their first triangle.
  std::vector<uint32_t> vertex_component;
  /// Per component: triangles, area and enclosed volume (the divergence theorem over its
  /// triangles: exact for a closed, consistently oriented piece, positive when it faces
  /// outward; for an open piece, the volume of the cone over it from the first corner of its
  /// first triangle: 0 for a flat piece).
  std::vector<size_t> triangles;
  std::vector<double> area;
  std::vector<double> volume;
};

/// The pieces of `mesh` whose triangles share vertices. Cost: O(V + F).
/// @throws Error(InvalidArgument) a triangle index >= the vertex count.
PM_EXPORT MeshComponents mesh_components(const TriMesh& mesh);

/// Drop every piece whose enclosed volume is below `min_volume` (its absolute value, so an
/// inward-facing cavity counts by its size): its triangles, and the vertices (with their
/// normals and attributes) that only it used; the kept triangles keep their values per
/// corner. Vertices and triangles keep their order. Returns the number of pieces dropped.
/// min_volume <= 0 drops nothing.
/// @throws Error(InvalidArgument) a triangle index >= the vertex count, or a NaN min_volume.
PM_EXPORT size_t remove_small_components(TriMesh& mesh, double min_volume);

}  // namespace particlemesh
