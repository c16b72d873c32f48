// Internal: the finished surface's vertex normals.
#pragma once

#include "particlemesh/core/config.h"

#include <cstddef>
#include <cstdint>
#include <vector>

#include "particlemesh/core/vec3.h"
#include "surface/editable_surface.h"

namespace PM_NAMESPACE::detail {

/// The surface's angle-weighted vertex normals (G. Thürmer and C. A. Wüthrich, "Computing
/// vertex normals from polygonal facets", 1998), so they agree with the winding. Where a
/// vertex's triangles cancel (two folded onto each other at a scan's depth edge) it keeps
/// `fallback` (its particle's normal), else its widest triangle's; points in no triangle keep
/// `fallback`. Per vertex in parallel, over its triangles in triangle order: the sums (so the
/// bits) of a serial pass, for any thread count. Counts the active points in no triangle into
/// `unused`.
std::vector<Vec3> surface_vertex_normals(const EditableSurface& s, const std::vector<uint8_t>& active,
                                         const std::vector<Vec3>& fallback, size_t& unused);

}  // namespace particlemesh::detail
