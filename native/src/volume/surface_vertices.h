// The vertices of polygonize's mesh, placed on the true field: a crossing on a lattice edge
// (Newton's method safeguarded by bisection), and the vertex inside a cell that a loop of
// crossings is fanned around. Both return the field's gradient direction as the normal.
#pragma once

#include <cstdint>

#include "particlemesh/core/vec3.h"
#include "particlemesh/volume/field.h"

namespace PM_NAMESPACE::detail {

struct Crossing {
  Vec3 position, normal;
  int evaluations = 0;  // field evaluations it took
};

/// Vertices stay at least this fraction of an edge away from its nodes (no two coincide).
constexpr double kEdgeClamp = 1e-3;

/// The crossing on the edge from node position a (sample fa) to a + h e_axis (sample fb):
/// linear interpolation of the samples, then safeguarded Newton on the true field.
Crossing refine_crossing(const ParticleField& field, const Vec3& a, int axis, double h, double fa, double fb,
                         double T);

/// A vertex inside the cell with lower corner cell_lo (edge h, corner samples cv) for the
/// loop of `len` marching-cubes edges `loop`: the mean of the loop's linearly interpolated
/// crossings, moved onto the surface along the gradient (kept in the cell).
Crossing center_vertex(const ParticleField& field, const Vec3& cell_lo, double h, const float cv[8],
                       const uint8_t* loop, int len, double T);

}  // namespace PM_NAMESPACE::detail
