// Inside or outside a closed surface: how many times a ray from a point crosses a mesh.
#pragma once

#include "particlemesh/core/config.h"

#include <cstdint>
#include <vector>

#include "particlemesh/core/export.h"
#include "particlemesh/core/vec3.h"
#include "particlemesh/mesh/tri_mesh.h"

namespace PM_NAMESPACE {

/// Per point: how many of the mesh's triangles the ray from it straight up (+z) crosses. A
/// point lies inside a closed surface when its count is odd, whatever the surface's winding.
/// The count is watertight: a ray through an edge or a vertex is counted once (the point moved
/// off it symbolically), and each edge's side test is evaluated from its lower-numbered end,
/// so that the triangles on either side round it alike. Each triangle's share depends on that
/// triangle alone: meshes cut from one, their vertices numbered in the same relative order,
/// give counts that add up to the whole one's (a surface split across processes:
/// particlemesh.distributed). In parallel
/// (`threads`, 0 = all); the same counts for any thread count.
/// @throws Error(InvalidArgument) naming a triangle with an index beyond the vertices, and
/// Error(InvalidInput) naming a point or vertex that is not finite.
PM_EXPORT std::vector<uint64_t> ray_crossings(const TriMesh& mesh, const std::vector<Vec3>& points, int threads = 0);

}  // namespace particlemesh
