// The vertices of polygonize's mesh, placed on the true field: a crossing on a lattice edge
// (Newton steps corrected for the curvature, safeguarded by bisection), and the vertex inside
// a cell that a loop of crossings is fanned around. Both return the field's gradient
// direction as the normal.
#pragma once

#include <cstdint>
#include <vector>

#include "particlemesh/core/vec3.h"
#include "particlemesh/volume/field.h"

namespace PM_NAMESPACE::detail {

struct Crossing {
  Vec3 position, normal;
  int evaluations = 0;  // field evaluations it took
};

/// Vertices stay at least this fraction of an edge away from its nodes (no two coincide).
constexpr double kEdgeClamp = 1e-3;

/// The particles whose spheres can reach one lattice edge, gathered once from the field's
/// grid for all the evaluations on that edge (its Newton steps, then its vertex's attributes).
/// A query of the field visits the 27 grid cells around its point and tests every particle
/// in them; the particles near an edge are about a third of those, so each evaluation here
/// tests only them. Every result is bit for bit the field's own: the same particles (those
/// in the cells the field's query would visit and within its radius), in the same order
/// (increasing grid index; the particles kept apart from the grid's cells last, those whose
/// support meets the edge), with the same arithmetic. Spherical kernels only
/// (ParticleField::anisotropic() false); one per thread, reused from edge to edge.
class EdgeNeighbours {
 public:
  /// Gather the particles for the edge from node position a to a + h e_axis.
  void gather(const ParticleField& field, const Vec3& a, int axis, double h);
  /// As ParticleField::value_and_gradient(x, gradient), for x on the gathered edge.
  double value_and_gradient(const Vec3& x, Vec3* gradient) const;
  /// As ParticleField::for_each_contributor(x, f) (f(input index, s)), for x on the edge.
  /// The particles' test is sum()'s, written out again: sharing one visitor between the two
  /// measured 3-4 % slower polygonize (sum() is its innermost loop).
  template <class F>
  void for_each_contributor(const Vec3& x, F&& f) const {
    const double r = field_->cell_reach();
    const double r2 = r * r;
    const NeighborGrid& grid = field_->grid();
    const int32_t lo = grid.coord_on_axis(x[axis_] - r, axis_), hi = grid.coord_on_axis(x[axis_] + r, axis_);
    const bool uniform = field_->uniform_radius();
    const std::vector<double>& inv_r2s = field_->sorted_inverse_squared_radii();
    for (size_t k = 0; k < count_; ++k) {
      const Near& n = near_[k];
      if (n.cell < lo || n.cell > hi) continue;
      const double d2 = squared_distance(grid.sorted_point(n.sorted), x);
      if (!(d2 <= r2)) continue;
      const double s = d2 * (uniform ? inv_r2_ : inv_r2s[n.sorted]);
      if (s < 1.0) f(size_t(grid.original_index(n.sorted)), s);
    }
    for (const uint32_t t : apart_) {
      const double s = squared_distance(grid.sorted_point(t), x) * inv_r2s[t];
      if (s < 1.0) f(size_t(grid.original_index(t)), s);
    }
  }

 private:
  // A gathered particle: 8 bytes, its centre read from the grid (just read by the gather,
  // so still in cache) rather than copied.
  struct Near {
    uint32_t sorted;  // its grid (sorted) index
    int32_t cell;     // its grid cell's coordinate along the edge's axis
  };
  template <Kernel K, bool General, bool AllCells>
  double sum(const Vec3& x, Vec3* gradient, int32_t lo, int32_t hi) const;
  template <int A>
  void gather_along(const ParticleField& field, const Vec3& a, double h);
  template <int A>
  static double get(const Vec3& v) { return A == 0 ? v.x : A == 1 ? v.y : v.z; }

  // sum<K, false, *> two particles at a time, from columns_ (polynomial kernels).
  template <Kernel K>
  double sum_by_coordinate(const Vec3& x, Vec3* gradient, int32_t lo, int32_t hi) const;
  // One radius and unit strengths: the evaluations with a gradient need no per-particle
  // option (sum()'s General false), and polynomial kernels take sum_by_coordinate.
  static bool one_radius_unit_strengths(const ParticleField& f) {
    return f.uniform_radius() && f.sorted_strengths().empty();
  }

  const ParticleField* field_ = nullptr;
  int axis_ = 0;
  double inv_r2_ = 0;
  std::vector<Near> near_;  // the first count_ are the edge's
  size_t count_ = 0;
  // The gathered particles' centres and cells by coordinate for sum_by_coordinate: stride_
  // x, then y, z and cells (as doubles), stride_ = count_ rounded up to even (the pad's cell
  // NaN). Filled only where sum_by_coordinate is taken.
  std::vector<double> columns_;
  size_t stride_ = 0;
  std::vector<uint32_t> apart_;  // the particles kept apart from the cells whose support meets the edge
  int32_t box_lo_ = 0, box_hi_ = 0;  // the gathered box's cells along the edge's axis
  struct Run {
    uint32_t begin, end;  // sorted indices
    int32_t cell;         // their cell's coordinate along the edge's axis
  };
  // Per axis, the last kBoxes gathers' boxes of grid cells and their runs (replaced in turn):
  // neighbouring edges along one axis mostly have one of them (a box is whole grid cells, each
  // several lattice cells wide: four with the default cell and radius), whose runs are then
  // taken again rather than walked again. With one box per axis a third of the walks were
  // saved on the live frame, with four two thirds.
  struct Box {
    const ParticleField* field = nullptr;
    NeighborGrid::CellCoord lo{}, hi{};
    std::vector<Run> runs;  // room for the runs, reused
    size_t count = 0, room = 0;
  };
  static constexpr size_t kBoxes = 4;
  Box boxes_[3][kBoxes];
  size_t next_box_[3] = {};
};

/// The crossing on the edge from node position a (sample fa) to a + h e_axis (sample fb):
/// linear interpolation of the samples, then safeguarded Newton steps corrected for the
/// curvature (a quadratic through what is known) on the true field.
Crossing refine_crossing(const ParticleField& field, const Vec3& a, int axis, double h, double fa, double fb,
                         double T);
/// The same, bit for bit, evaluated through `near` gathered for that edge.
Crossing refine_crossing(const EdgeNeighbours& near, const Vec3& a, int axis, double h, double fa, double fb,
                         double T);

/// A vertex inside the cell with lower corner cell_lo (edge h, corner samples cv) for the
/// loop of `len` marching-cubes edges `loop`: the mean of the loop's linearly interpolated
/// crossings, moved onto the surface along the gradient (kept in the cell).
Crossing center_vertex(const ParticleField& field, const Vec3& cell_lo, double h, const float cv[8],
                       const uint8_t* loop, int len, double T);

}  // namespace PM_NAMESPACE::detail
