// Internal: the marching-cubes case table, with the ambiguous faces resolved per face.
//
// Cube numbering (all of polygonize uses it):
//   corner c = x + 2y + 4z                      (x, y, z in {0, 1})
//   edge   e = 4 * axis + u + 2v                (u, v: the corner's coordinates on the other
//                                                two axes, in increasing axis order; the
//                                                edge runs from coordinate 0 to 1 on `axis`)
//   face   f = 2 * axis + side                  (side 0: coordinate 0 on axis, outward -axis)
//
// Why generated rather than copied: the classic 256-entry tables resolve an ambiguous face
// (inside corners on one diagonal, outside on the other) by the case alone, so two cells that
// share the face can disagree and leave a crack. Here every ambiguous face of a case has a
// decision bit (1 = the two inside corners are joined across the face, 0 = they are cut off
// separately), taken at run time from that face's four samples only (asymptotic decider), so
// both cells sharing a face take the same decision. The table holds the triangles for every
// (case, decisions) pair (656 in all); it is built once by tracing, for each pair, the closed
// loops that the face segments form around the cube, and triangulating each loop with
// diagonals that lie on no cube face (a diagonal in a face could be produced by the
// neighbouring cell too, giving an edge with four triangles); the few loops that admit no such
// triangulation (8-, 9- and 12-gons around joined ambiguous faces) are fanned around a vertex
// inside the cell. Each face segment is oriented with the inside corners on its right seen
// from outside the cube, which makes every loop, and so every triangle, counter-clockwise seen
// from outside the surface.
#pragma once

#include "particlemesh/core/config.h"

#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

namespace PM_NAMESPACE::detail {

/// Corner index (c = x + 2y + 4z) of the lower end of edge e, and the edge's axis.
constexpr int mc_edge_axis(int e) { return e >> 2; }
constexpr int mc_edge_lower_corner(int e) {
  // Along x the corner is (0, u, v), along y (u, 0, v), along z (u, v, 0).
  constexpr int kLower[12] = {0, 2, 4, 6, 0, 1, 4, 5, 0, 1, 2, 3};
  return kLower[e];
}

/// The four corners of face f in cyclic order around the face.
const std::array<int, 4>& mc_face_corners(int f);

/// Triangle corners at or above this index are vertices inside the cell (see McTable).
constexpr int kCenterBase = 12;

class McTable {
 public:
  /// The table, built on first use (thread-safe).
  static const McTable& get();

  /// Bit f set: face f is ambiguous in case c (c = the set of inside corners, bit per corner).
  uint8_t ambiguous_faces(int c) const { return ambiguous_[c]; }

  /// Triangles (three edge indices each, or a centre vertex kCenterBase + k; counter-clockwise
  /// seen from outside the surface) of
  /// case c for the decision bits `d`: bit j belongs to the j-th ambiguous face of the case in
  /// increasing face order, 1 = the inside corners of that face are joined.
  const uint8_t* triangles_begin(int c, unsigned d) const { return tris_.data() + offset_[base_[c] + d]; }
  const uint8_t* triangles_end(int c, unsigned d) const { return tris_.data() + offset_[base_[c] + d + 1]; }
  int triangle_count(int c, unsigned d) const {
    return int(offset_[base_[c] + d + 1] - offset_[base_[c] + d]) / 3;
  }
  /// Total number of (case, decisions) entries (for tests).
  size_t entries() const { return offset_.size() - 1; }

  /// Vertices inside the cell that the entry needs: a loop that cannot be triangulated with
  /// diagonals off the cube faces (an 8-, 9- or 12-gon around joined ambiguous faces) is
  /// fanned around one, referenced as kCenterBase + k in the triangles. Its loop (length,
  /// then the edges) is at center_loops_begin: k-th after skipping k earlier loops.
  int center_count(int c, unsigned d) const { return center_count_[base_[c] + d]; }
  const uint8_t* center_loops_begin(int c, unsigned d) const {
    return center_loops_.data() + center_offset_[base_[c] + d];
  }

 private:
  McTable();
  std::array<uint8_t, 256> ambiguous_{};
  std::array<uint32_t, 256> base_{};
  std::vector<uint32_t> offset_;
  std::vector<uint8_t> tris_;
  std::vector<uint8_t> center_count_;
  std::vector<uint32_t> center_offset_;
  std::vector<uint8_t> center_loops_;
};

}  // namespace particlemesh::detail
