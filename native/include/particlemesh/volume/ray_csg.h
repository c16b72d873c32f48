// Constructive solid geometry of particle fields along rays (thesis section 5.1.3: the ray
// caster returns *all* crossings, which is what CSG needs). The solids are the insides
// (F >= T) of two fields; a ray's crossings with each, in order and with the state at t_min,
// describe the ray's inside intervals exactly, and the combination is computed by merging
// the two sorted lists: the result is inside where op(inside A, inside B) holds, and it has
// a hit wherever that changes.
//
// Normals of the result face out of the result: a crossing of A keeps A's normal; a crossing
// of B keeps B's normal in a union or an intersection and is flipped in a difference (the
// surface of B bounds A - B from the other side). Crossings of A and B at the same t are
// taken together (A ∪ A = A and A - A = ∅ exactly, not up to a tolerance).
#pragma once

#include "particlemesh/core/config.h"

#include <limits>
#include <optional>

#include "particlemesh/core/export.h"
#include "particlemesh/volume/raycast.h"

namespace PM_NAMESPACE {

enum class CsgOp : int32_t {
  Union = 0,         ///< inside A or inside B
  Intersection = 1,  ///< inside A and inside B
  Difference = 2,    ///< inside A and not inside B
};

/// "union", "intersection", "difference".
PM_EXPORT const char* csg_op_name(CsgOp op);

/// Combine one ray's crossings with A and with B (both from the same ray and t range).
/// Cost: O(|a| + |b|).
/// @throws Error(InvalidArgument) for an op out of range, or hits not in increasing t.
PM_EXPORT RayHits csg_hits(const RayHits& a, const RayHits& b, CsgOp op);

/// Cast the ray against both fields and combine (all crossings of the result).
PM_EXPORT RayHits csg_all_hits(const RayCaster& a, const RayCaster& b, CsgOp op, const Vec3& origin,
                               const Vec3& direction, double t_min = 0,
                               double t_max = std::numeric_limits<double>::infinity());

/// The first crossing of the combination, or none.
PM_EXPORT std::optional<RayHit> csg_first_hit(const RayCaster& a, const RayCaster& b, CsgOp op, const Vec3& origin,
                                              const Vec3& direction, double t_min = 0,
                                              double t_max = std::numeric_limits<double>::infinity());

}  // namespace particlemesh
