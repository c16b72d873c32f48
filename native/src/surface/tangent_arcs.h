// Internal: directions about a vertex normal, for the wedge rule of the surface extraction and
// for walking a vertex's fan when tracing boundary loops.
//
// A triangle's corner at v covers an arc of directions in v's tangent plane; the wedge rule
// says the arcs of the triangles at a vertex must not overlap (its fan stays a disk). Angles
// are pseudo-angles (see angle_of): only their order matters, so no trigonometry is needed.
#pragma once

#include "particlemesh/core/config.h"

#include <algorithm>
#include <cmath>

#include "particlemesh/core/vec3.h"

namespace PM_NAMESPACE::detail {

constexpr double kTwoPi = 4.0;    ///< the period of angle_of's pseudo-angles
constexpr float kArcEps = 1e-5f;  ///< in pseudo-angle units (about 1.5e-5 rad); arcs are floats

/// Two unit vectors spanning the tangent plane of a unit normal.
struct Frame {
  Vec3 u, w;
};

inline Frame tangent_frame(const Vec3& n) {
  const Vec3 axis = std::abs(n.x) < 0.57 ? Vec3{1, 0, 0} : (std::abs(n.y) < 0.57 ? Vec3{0, 1, 0} : Vec3{0, 0, 1});
  const Vec3 u = normalized(cross(n, axis));
  return {u, cross(n, u)};
}

/// The direction of d around the normal as a pseudo-angle in [0, 4): monotonic in the true
/// angle (counter-clockwise from u) but with no trigonometry; the wedge tests only compare
/// and order angles, so any order-preserving measure with a fixed period serves.
inline double angle_of(const Frame& f, const Vec3& d) {
  const double x = dot(d, f.u), y = dot(d, f.w);
  const double s = std::abs(x) + std::abs(y);
  if (!(s > 0)) return 0;
  const double r = y / s;
  return x >= 0 ? (r >= 0 ? r : 4 + r) : 2 - r;
}

/// A counter-clockwise arc (about the vertex normal) of a triangle's corner.
struct Arc {
  float start, length;
};

/// The arc of the corner at v of a triangle (v, succ, pred), wound counter-clockwise.
inline Arc make_arc(const Frame& f, const Vec3& v, const Vec3& succ, const Vec3& pred) {
  const double a = angle_of(f, succ - v), b = angle_of(f, pred - v);
  double len = b - a;
  if (len < 0) len += kTwoPi;
  return {float(a), float(len)};
}

/// Do two arcs at one vertex overlap by more than kArcEps?
inline bool arcs_overlap(const Arc& a, const Arc& b) {
  float d = b.start - a.start;
  if (d < 0) d += float(kTwoPi);
  if (d >= float(kTwoPi)) d -= float(kTwoPi);
  return d < a.length - kArcEps || d + b.length > float(kTwoPi) + kArcEps;
}

}  // namespace particlemesh::detail
