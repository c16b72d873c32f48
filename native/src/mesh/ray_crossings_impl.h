// Internal: the watertight ray-crossing count behind ray_crossings and the closed pieces'
// nesting (mesh/nesting.h).
#pragma once

#include "particlemesh/core/config.h"

#include <cstddef>
#include <cstdint>
#include <limits>
#include <vector>

#include "particlemesh/core/vec3.h"
#include "particlemesh/mesh/tri_mesh.h"

namespace PM_NAMESPACE::detail {

/// Whether the ray from q straight up crosses triangle t over positions P (watertight, as
/// RayCrossings below counts).
bool ray_crosses(const std::vector<Vec3>& P, const Triangle& t, const Vec3& q);

/// How many of a set of triangles the ray from q straight up (+z) crosses. Watertight
/// (Woop, Benthin and Wald, "Watertight ray/triangle intersection", 2013, in spirit): each
/// edge's side test is evaluated once per edge, from its lower-numbered end, so the two
/// triangles that share an edge see the same number with opposite signs; a point exactly on
/// an edge's line is moved off it symbolically (by (eps, eps^2): Edelsbrunner and Muecke's
/// simulation of simplicity), so it lies in exactly one of the two. Every crossing is counted
/// once, also through edges and vertices, and each triangle's share depends on it alone.
/// The triangles are bucketed once, in parallel, in a grid over their xy box; queries are
/// read-only (any number of threads may ask at once).
class RayCrossings {
 public:
  /// The triangles T[tris[0 .. count)] over positions P (both kept by reference).
  RayCrossings(const std::vector<Vec3>& P, const std::vector<Triangle>& T, const uint32_t* tris, size_t count);
  size_t count(const Vec3& q) const { return count_if(q, [](uint32_t) { return true; }); }
  /// Only the triangles t with keep(t) (an index into T) counted.
  template <class Keep>
  size_t count_if(const Vec3& q, Keep&& keep) const {
    if (!(q.x >= lo_[0] && q.x <= hi_[0] && q.y >= lo_[1] && q.y <= hi_[1])) return 0;
    const size_t c = cell(q.y, 1) * side_ + cell(q.x, 0);
    size_t crossings = 0;
    for (size_t i = start_[c]; i < start_[c + 1]; ++i)
      if (keep(cells_[i])) crossings += ray_crosses(P_, T_[cells_[i]], q);
    return crossings;
  }

 private:
  size_t cell(double v, int a) const;

  const std::vector<Vec3>& P_;
  const std::vector<Triangle>& T_;
  double lo_[2] = {std::numeric_limits<double>::infinity(), std::numeric_limits<double>::infinity()};
  double hi_[2] = {-std::numeric_limits<double>::infinity(), -std::numeric_limits<double>::infinity()};
  double scale_[2] = {0, 0};
  size_t side_ = 1;
  std::vector<size_t> start_;
  std::vector<uint32_t> cells_;
};

}  // namespace particlemesh::detail
