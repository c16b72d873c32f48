// Internal: mesh_edges on raw arrays, writing straight into the caller's buffers (the C ABI's
// pm_triangle_edges: no copy of the triangles in, none of the edges out).
#pragma once

#include "particlemesh/core/config.h"

#include <cstddef>
#include <cstdint>
#include <functional>

namespace PM_NAMESPACE::detail {

/// The edges of `triangle_count` triangles (3 vertex indices each) over `vertex_count`
/// vertices: writes per corner its edge into `corner_edges` (3 per triangle), then asks
/// `edges_at(count)` where to write the `count` edges (2 vertex indices each, a < b, ordered
/// by a then b; it may throw) and fills it. Returns the edge count. The same for any thread
/// count. @throws Error(InvalidArgument) as mesh_edges.
size_t number_edges(const uint32_t* triangles, size_t triangle_count, size_t vertex_count, int threads,
                    uint32_t* corner_edges, const std::function<uint32_t*(size_t)>& edges_at);

}  // namespace particlemesh::detail
