// Internal: turning the closed components of the finished surface to face outward.
#pragma once

#include "particlemesh/core/config.h"

#include <cstddef>
#include <cstdint>
#include <vector>

#include "particlemesh/core/vec3.h"
#include "particlemesh/mesh/tri_mesh.h"

namespace PM_NAMESPACE::detail {

/// Turn every closed component (one holding none of the `boundary` half-edges, a << 32 | b)
/// to face away from the solid it bounds: outward (positive volume), or into the cavity for
/// one inside an odd number of others (mesh/nesting.h: a hollow ball's inner wall), negating
/// its points' `vertex_normals` (if given) to match; returns how many flipped. Components are
/// by shared vertices (the same as by shared edges on a manifold without pinches). The result
/// does not depend on the thread count.
size_t orient_closed_components_outward(const std::vector<Vec3>& positions, std::vector<Triangle>& triangles,
                                        const std::vector<uint64_t>& boundary,
                                        std::vector<Vec3>* vertex_normals = nullptr);

}  // namespace particlemesh::detail
