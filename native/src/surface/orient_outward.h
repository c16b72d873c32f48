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
/// With `flat` given, closed components that enclose no volume (flat pillows: a patch and a
/// reversed copy of it, as points exactly in one plane, e.g. quantized coordinates, can give)
/// are taken out first, their triangles removed (the rest keep their order) and counted in
/// `flat`; with `turn` false nothing is turned.
struct FlatPieces {
  size_t pieces = 0, triangles = 0, points = 0;
};
size_t orient_closed_components_outward(const std::vector<Vec3>& positions, std::vector<Triangle>& triangles,
                                        const std::vector<uint64_t>& boundary,
                                        std::vector<Vec3>* vertex_normals = nullptr, bool turn = true,
                                        FlatPieces* flat = nullptr);

}  // namespace particlemesh::detail
