// Internal: the grown surface as the repair edits it - vertex -> triangles (a CSR built once
// plus a small overflow for triangles added later) and the set of boundary half-edges (a -> b
// with no b -> a), kept up to date as triangles come and go, so that tracing loops and finding
// pinched vertices look only at the boundary, not at the whole surface.
#pragma once

#include "particlemesh/core/config.h"

#include <cstddef>
#include <cstdint>
#include <vector>

#include "core/hashing.h"
#include "core/progress_tracker.h"
#include "particlemesh/core/vec3.h"
#include "particlemesh/mesh/tri_mesh.h"
#include "surface/growth.h"
#include "surface/tangent_arcs.h"

namespace PM_NAMESPACE::detail {

class EditableSurface {
 public:
  /// Indexes the grown surface, read off the growth's corner lists (which are then freed): a
  /// vertex's accepted corners lead its list, each with its triangle's other two corners.
  /// `positions` and `frames` (the vertices' tangent frames) must outlive the surface.
  EditableSurface(const std::vector<Vec3>& positions, const std::vector<Frame>& frames, GrownSurface&& grown,
                  ProgressTracker& tracker);
  /// A surface of the given triangles (consistently wound, at most two per edge).
  EditableSurface(const std::vector<Vec3>& positions, const std::vector<Frame>& frames,
                  const std::vector<Triangle>& triangles);

  const std::vector<Vec3>& positions() const { return P_; }
  const std::vector<Frame>& frames() const { return frame_; }
  size_t point_count() const { return P_.size(); }

  /// f(t) for each live triangle at v: those of the index in order, then those added.
  template <class F>
  void for_each_tri(uint32_t v, F&& f) const {
    for (uint32_t i = vt_off_[v]; i < vt_off_[v + 1]; ++i)
      if (alive_[vt_[i]]) f(vt_[i]);
    if (const uint32_t x = extra_of_[v]; x != kNoList)
      for (uint32_t t : extra_[x])
        if (alive_[t]) f(t);
  }

  /// Triangle ids: [0, triangle_slots()); killed ones stay, not alive.
  size_t triangle_slots() const { return tris_.size(); }
  const Triangle& triangle(uint32_t t) const { return tris_[t]; }
  bool alive(uint32_t t) const { return alive_[t] != 0; }
  Vec3 face_normal(const Triangle& T) const { return normalized(cross(P_[T[1]] - P_[T[0]], P_[T[2]] - P_[T[0]])); }

  static constexpr uint32_t kNoTriangle = 0xffffffffu;
  /// The live triangle that holds the directed edge a -> b, or kNoTriangle.
  uint32_t triangle_with(uint32_t a, uint32_t b) const;
  /// Is the directed edge a -> b in a live triangle?
  bool directed_used(uint32_t a, uint32_t b) const { return triangle_with(a, b) != kNoTriangle; }
  bool edge_exists(uint32_t a, uint32_t b) const { return directed_used(a, b) || directed_used(b, a); }
  bool triangle_exists(uint32_t a, uint32_t b, uint32_t c) const;
  /// Does a boundary half-edge start at v (an edge v -> w of a triangle with no w -> v)?
  bool starts_boundary(uint32_t v) const;

  void add_triangle(const Triangle& T);
  void kill_triangle(uint32_t t);
  /// Brings a killed triangle back in its slot, as if it had never been killed.
  void revive_triangle(uint32_t t);

  static uint64_t half_key(uint32_t a, uint32_t b) { return (uint64_t(a) << 32) | b; }
  /// Boundary half-edges (a << 32 | b), unordered.
  const KeySet& boundary_set() const { return boundary_; }
  bool closed() const { return boundary_.empty(); }
  /// Whether v has triangles added since indexing (not held to the growth's wedge rule).
  bool has_added_triangles(uint32_t v) const { return extra_of_[v] != kNoList; }
  /// The vertices whose triangles changed (one added, killed or revived there) since the last
  /// call (since indexing, the first time), each once, in the order they first changed; the
  /// record then starts afresh. unpinch's: a vertex whose triangles did not change since it
  /// last looked is as it found it.
  std::vector<uint32_t> take_changed_vertices();

  /// Boundary loops, each a vertex sequence following the boundary edges v_i -> v_{i+1};
  /// loops through a vertex twice are split there. Sorted, each starting at its smallest
  /// vertex, so the repair is deterministic.
  std::vector<std::vector<uint32_t>> trace_loops() const;

  /// The pieces of the surface (triangles sharing a vertex are connected), by union-find:
  /// each vertex's piece, named by the piece's lowest vertex, and each piece's triangles,
  /// counted at that vertex.
  void surface_pieces(std::vector<uint32_t>& piece, std::vector<uint32_t>& triangles) const;
  struct Pieces {
    std::vector<uint32_t> piece, triangles;  ///< as surface_pieces gives them
  };
  Pieces pieces() const {
    Pieces p;
    surface_pieces(p.piece, p.triangles);
    return p;
  }

  /// The live triangles, in order.
  std::vector<Triangle> take() const;
  /// Boundary half-edges, sorted.
  std::vector<uint64_t> boundary() const;

 private:
  /// The boundary half-edges as T enters the surface (its edges' twins stop being boundary,
  /// its other edges become boundary) or, with entering false, leaves it.
  void toggle_boundary(const Triangle& T, bool entering);
  void mark_changed(const Triangle& T);

  const std::vector<Vec3>& P_;
  const std::vector<Frame>& frame_;
  std::vector<Triangle> tris_;
  std::vector<uint8_t> alive_;
  std::vector<uint32_t> vt_off_, vt_;
  /// The triangles added at a vertex, a list per vertex that has any (in the order the
  /// vertices got their first), and per vertex the index of its list, or kNoList.
  static constexpr uint32_t kNoList = 0xffffffffu;
  std::vector<std::vector<uint32_t>> extra_;
  std::vector<uint32_t> extra_of_;
  KeySet boundary_;
  std::vector<uint8_t> changed_;          ///< per vertex: in changed_list_
  std::vector<uint32_t> changed_list_;    ///< since take_changed_vertices
};

}  // namespace particlemesh::detail
