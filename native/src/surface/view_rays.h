// Internal: depth jumps of a scan, told by the sensor's position.
//
// A scan taken from one viewpoint samples the surfaces its rays meet first. Where a surface in
// front ends, the next samples along the neighbouring rays lie on whatever is behind it: an
// edge between the two runs (nearly) along a view ray. Such "shadow" edges join a foreground
// surface to the background across a depth jump, never one surface, so no triangle may have
// one (the angle tolerance of PCL's OrganizedFastMesh, 12.5 degrees, whose shadow test this is).
#pragma once

#include "particlemesh/core/config.h"

#include <cmath>
#include <cstdint>
#include <vector>

#include "particlemesh/core/vec3.h"

namespace PM_NAMESPACE::detail {

struct ViewRays {
  bool active = false;
  Vec3 origin;
  /// cos of the largest angle between an edge and the view ray through its midpoint that makes
  /// it a shadow edge.
  double cos_limit = std::cos(12.5 * 3.14159265358979323846 / 180.0);

  /// Does the edge a b run along the view ray through its midpoint?
  bool along_ray(const Vec3& a, const Vec3& b) const {
    if (!active) return false;
    const Vec3 e = b - a, r = (a + b) * 0.5 - origin;
    const double d = dot(e, r);
    return d * d > cos_limit * cos_limit * squared_norm(e) * squared_norm(r);
  }
  bool shadows(const Vec3& a, const Vec3& b, const Vec3& c) const {
    return active && (along_ray(a, b) || along_ray(b, c) || along_ray(c, a));
  }
};

/// Is `origin` plausibly where the scan was taken from? Its rays must meet the surface at
/// well below grazing angles for most points (a sensor samples few points at grazing angles;
/// a viewpoint that was only written as a default, say at the origin of an object's model
/// coordinates, sees much of the surface edge-on): at most kMaxGrazing of the points with a
/// normal (unit or zero, either sense) have their normal within 12.5 degrees of perpendicular
/// to the ray, and no point coincides with it.
constexpr double kMaxGrazing = 0.2;
bool plausible_viewpoint(const std::vector<Vec3>& positions, const std::vector<Vec3>& normals,
                         const std::vector<uint8_t>& active, const Vec3& origin);

}  // namespace particlemesh::detail
