// Internal: the corner angles the surface stages rank and weight triangles by.
#pragma once

#include "particlemesh/core/config.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <numbers>

#include "particlemesh/core/vec3.h"
#include "particlemesh/mesh/tri_mesh.h"

namespace PM_NAMESPACE::detail {

/// The cosine of the triangle (p, q, r)'s angle at p.
inline double corner_cosine(const Vec3& p, const Vec3& q, const Vec3& r) {
  const Vec3 u = q - p, v = r - p;
  return dot(u, v) / std::sqrt(squared_norm(u) * squared_norm(v));
}

/// The cosine of a triangle's largest angle (the smallest of its corners' cosines): the same
/// order as the largest angle, without the arc-cosines.
inline double min_corner_cosine(const Vec3& a, const Vec3& b, const Vec3& c) {
  return std::min({corner_cosine(a, b, c), corner_cosine(b, c, a), corner_cosine(c, a, b)});
}

/// A triangle's largest angle, in radians.
inline double max_angle(const Vec3& a, const Vec3& b, const Vec3& c) {
  auto ang = [](const Vec3& p, const Vec3& q, const Vec3& r) { return std::acos(std::clamp(corner_cosine(p, q, r), -1.0, 1.0)); };
  return std::max({ang(a, b, c), ang(b, c, a), ang(c, a, b)});
}

/// acos(x) for x in [-1, 1] within 2e-8 rad (Abramowitz and Stegun 4.4.46): the corner
/// angles that weight the vertex normals, where std::acos was the largest cost of that stage.
inline double fast_acos(double x) {
  const double a = std::min(std::abs(x), 1.0);
  const double r = std::sqrt(1.0 - a) *
                   (1.5707963050 + a * (-0.2145988016 + a * (0.0889789874 + a * (-0.0501743046 + a * (0.0308918810 +
                    a * (-0.0170881256 + a * (0.0066700901 + a * -0.0012624911)))))));
  return x >= 0 ? r : std::numbers::pi - r;
}

/// The corner (0, 1 or 2) of t at vertex v (t must hold v).
inline int corner_of(const Triangle& t, uint32_t v) { return t[0] == v ? 0 : (t[1] == v ? 1 : 2); }

}  // namespace particlemesh::detail
