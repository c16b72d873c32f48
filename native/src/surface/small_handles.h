// Internal: handles smaller than the sampling, taken out of the repaired surface (topological
// noise removal: I. Guskov and Z. Wood, "Topological noise removal", Graphics Interface 2001).
//
// Where a part is thinner than the particles' spacing (a claw's tip, an ear's rim) the
// smallest-sphere test and the repair can join its sides into a handle a few edges around:
// a tunnel through the part that no surface sampled that sparsely can show. Such a handle
// lies inside a small ball: the surface's triangles within about an edge limit of one vertex
// form a patch of genus 1 or more, where a smooth surface's patch that size is a disk (or,
// around a tube, an annulus). A real handle, a tube's ring or a torus's hole, is larger than
// the ball and never lies inside one.
//
// Only pieces whose genus (from their Euler characteristic and loops) is above zero are
// searched, and only around vertices where the surface folds sharply (two triangles over 90
// degrees apart: the crumpled triangles of a part thinner than the spacing); a patch with a
// handle and one outline inside the surface is replaced by a fill of its outline (the fill's
// rules: edges within the limit, no fold back), and its inner particles are left for the
// insertion to put back. A patch whose outline does not fill, or that reaches a loop the
// surface left open, stays as it is.
#pragma once

#include "particlemesh/core/config.h"

#include <cstddef>
#include <cstdint>
#include <vector>

#include "surface/editable_surface.h"
#include "surface/hole_fill.h"

namespace PM_NAMESPACE::detail {

/// A patch searched for a handle reaches this many times its centre's edge limit L.
constexpr double kHandleReach = 1.5;

/// What the search saw of the surface on its way: its pieces, and its boundary loops if it
/// had to trace them (empty otherwise).
struct HandleSearch {
  EditableSurface::Pieces pieces;
  std::vector<std::vector<uint32_t>> loops;
};

/// Replaces every patch of the kind above whose outline has at most `max_loop` edges (the
/// fill's loop limit) by a fill of its outline; returns the handles removed (the genus taken
/// out). `unchanged`, if given, receives what the search saw when nothing was removed (the
/// surface is then as it was, and its caller need not find its pieces or trace its loops
/// again), else is emptied.
size_t remove_small_handles(EditableSurface& s, const FillOptions& o, size_t max_loop,
                            HandleSearch* unchanged = nullptr);

}  // namespace particlemesh::detail
