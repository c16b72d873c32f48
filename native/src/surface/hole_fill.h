// Internal: filling the surface's boundary loops.
//
// A loop is filled only if it can be triangulated with edges no longer than
// fill_edge_factor x L that keep every fan a disk: holes left by sampling and extraction are
// that narrow, while a real opening (no particles within that distance across it) is wider
// and stays open. Small loops (wrong diagonals, sampling gaps) take the triangulation that
// minimises the largest angle; larger ones the one that minimises the largest dihedral angle,
// then the area (P. Liepa, "Filling holes in meshes", SGP 2003).
#pragma once

#include "particlemesh/core/config.h"

#include <cstddef>
#include <cmath>
#include <cstdint>
#include <vector>

#include "particlemesh/core/vec3.h"
#include "surface/editable_surface.h"
#include "surface/view_rays.h"

namespace PM_NAMESPACE::detail {

struct FillOptions {
  /// Per point: its edge limit L of the raw test (raw_triangulation.h: an edge's is the pair
  /// limit of its ends'). Must outlive the calls.
  const std::vector<double>* max_edge = nullptr;
  double fill_edge_factor = 1.5;  ///< fill triangles' edges at most this x L
  /// No repair edge is longer than this, whatever the points' limits (the longest edge the
  /// raw test may have; see SurfaceOptions::local_spacing).
  double edge_cap = INFINITY;
  size_t small_hole = 6;          ///< loops up to this many edges take the min-max-angle fill
  ViewRays view;                  ///< with a viewpoint: no repair edge along a view ray
  /// The raw test's limit for an edge a b (the pair limit of the points' max_edge).
  double edge_limit(uint32_t a, uint32_t b) const;
  /// The longest a repair triangle's edge a b may be: fill_edge_factor x edge_limit, at most
  /// edge_cap.
  double fill_limit(uint32_t a, uint32_t b) const;
};

struct FillStats {
  size_t holes_filled = 0;
  size_t hole_triangles = 0;
};

/// The sharpest fold a fill may make against the surface across a loop edge, or (larger
/// loops) between its own triangles: about 137 degrees. A fill that folds back further would
/// lay a reversed copy on the surface (the outline of a small isolated patch is its outside).
constexpr double kMaxFillDihedral = 2.4;
/// The sharper folds allowed where a loop lies inside a large component (fill_folded_loops):
/// about 160 degrees, the corners and creases of sharp-edged parts.
constexpr double kMaxCreaseDihedral = 2.8;

/// Fill one loop (a vertex sequence along boundary half-edges), keeping the surface manifold:
/// no edge that exists elsewhere may become a diagonal, edges stay within the fill limit, no
/// fold sharper than max_fold against the surface across a loop edge or (larger loops) between
/// the fill's own triangles. Returns false (and adds nothing) when no such triangulation exists.
bool fill_loop(EditableSurface& s, const std::vector<uint32_t>& loop, const FillOptions& o, FillStats& stats,
               double max_fold = kMaxFillDihedral);

/// Fill every loop with at most `max_size` edges; returns how many were filled.
size_t fill_loops(EditableSurface& s, size_t max_size, const FillOptions& o, FillStats& stats);

/// The loops that fill_loops leaves for folding too sharply, filled with folds up to
/// kMaxCreaseDihedral where the loop lies in a component of more than m^2 triangles (m: its
/// edges). Returns how many were filled.
size_t fill_folded_loops(EditableSurface& s, size_t max_size, const FillOptions& o, FillStats& stats);

/// The smallest possible longest edge over all triangulations of a loop (a min-max dynamic
/// program, cubic in the loop's edges), each edge in units of its limit (FillOptions::
/// edge_limit): how far apart the particles across the loop are.
double loop_width(const std::vector<Vec3>& positions, const std::vector<uint32_t>& loop, const FillOptions& o);

}  // namespace particlemesh::detail
