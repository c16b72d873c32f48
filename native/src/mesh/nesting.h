// Internal: which closed pieces of a mesh lie inside which. A closed piece bounds a solid on
// one side; pieces nested inside it alternate between the solid's cavities and solids again
// (a hollow ball: its outer surface, the cavity's wall inside it, a marble in the cavity).
// Facing "outward" means facing away from the solid: a piece at an even depth (inside no
// piece, or inside two, ...) encloses positive volume, one at an odd depth (a cavity's wall)
// negative volume. The finished surface's orientation stage and the topology report both
// judge a closed piece by this depth.
#pragma once

#include "particlemesh/core/config.h"

#include <cstddef>
#include <cstdint>
#include <vector>

#include "particlemesh/core/vec3.h"
#include "particlemesh/mesh/tri_mesh.h"

namespace PM_NAMESPACE::detail {

/// For each of `components` pieces (triangle f belongs to piece component_of[f]), how many of
/// the other closed pieces (closed[c] != 0) enclose it; 0 for open pieces and pieces without
/// triangles. A piece encloses another when the first corner of the other's first triangle
/// is inside it: a ray from that point crosses it an odd number of times (a watertight
/// test, whatever the piece's winding). Only pieces whose bounding box holds the other's are
/// tested (one closed piece, or
/// none nested by their boxes: one pass over the triangles). The result does not depend on
/// the thread count.
std::vector<uint32_t> nesting_depths(const std::vector<Vec3>& positions, const std::vector<Triangle>& triangles,
                                     const uint32_t* component_of, size_t components,
                                     const std::vector<uint8_t>& closed);

/// Whether a closed piece at nesting depth `depth` enclosing `signed_volume` faces away from
/// the solid it bounds (see above).
inline bool faces_away_from_its_solid(double signed_volume, uint32_t depth) {
  return depth % 2 == 0 ? signed_volume > 0 : signed_volume < 0;
}

}  // namespace particlemesh::detail
