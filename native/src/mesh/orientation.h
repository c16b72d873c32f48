// Internal: which way a closed piece of a mesh faces. Every stage that orients or reports
// orientation (the finished surface's outward turn, the smoothing's control mesh, the
// topology report, the mesh components' volumes) sums this one quantity over a piece's
// triangles: the divergence theorem gives the enclosed volume, positive when it faces
// outward.
#pragma once

#include "particlemesh/core/config.h"

#include "particlemesh/core/vec3.h"

namespace PM_NAMESPACE::detail {

/// Six times the signed volume of the tetrahedron (o, a, b, c): a triangle's term in the
/// enclosed volume of its piece. Taken about a point `o` of the piece (one of its vertices),
/// the sum keeps its precision far from the world's origin.
inline double signed_volume6(const Vec3& o, const Vec3& a, const Vec3& b, const Vec3& c) {
  return dot(a - o, cross(b - o, c - o));
}

/// A closed, consistently wound piece faces outward when it encloses positive volume.
inline bool faces_outward(double signed_volume) { return signed_volume > 0; }

}  // namespace particlemesh::detail
