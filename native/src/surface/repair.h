// Internal: the repair of the grown surface, in a fixed order (measured: filling large loops
// before unpinching created wrong handles):
//  1. boundary loops are split at repeated vertices (EditableSurface::trace_loops) and loops
//     of up to `small_hole` edges are filled;
//  2. at each pinched vertex (more than one fan) only the largest fan is kept;
//  3. loops of up to `max_hole` edges whose fill stays within the edge limit are filled (real
//     openings are wider than that and stay open);
//  4. open fragments of a few triangles joined to another piece by a raw triangle are
//     dissolved, and particles the surface passed by are inserted into the triangle or edge
//     they lie over;
//  5. loops that only a sharper fold closes are filled inside large components;
//  (steps 1-5 fill with edges of at most kFirstFillFactor x L, or the caller's factor if
//  smaller; with a larger factor, the loops still open are then filled up to it, so that a
//  wide limit patches only the gaps left, not loops the particles put back would close with
//  short edges;)
//  then handles smaller than the sampling are taken out (small_handles.h) and their particles
//  put back;
//  6. with min_component_triangles, pieces of fewer triangles are removed (a scan's stray
//     triangles among its rows), before the loops left open are counted.
#pragma once

#include "particlemesh/core/config.h"

#include <cstddef>
#include <cstdint>
#include <memory>
#include <utility>
#include <vector>

#include "core/progress_tracker.h"
#include "particlemesh/mesh/tri_mesh.h"
#include "particlemesh/spatial/neighbor_grid.h"
#include "particlemesh/surface/reconstruct.h"
#include "surface/editable_surface.h"
#include "surface/hole_fill.h"

namespace PM_NAMESPACE::detail {

struct RepairOptions {
  FillOptions fill;
  size_t max_hole = 100;  ///< loops up to this many edges may be filled (0 = none)
  size_t min_component_triangles = 0;  ///< pieces of fewer triangles are removed (0 = none)
};

/// What sort_out_pieces did: the pieces removed for min_component_triangles and their
/// triangles; of the pieces left, when the surface is open, those of fewer than
/// kStrayPieceTriangles (SurfaceStats::stray_pieces).
struct PieceStats {
  size_t removed = 0, removed_triangles = 0;
  SurfaceStats::StrayPieces strays;
};

struct RepairStats : FillStats {
  size_t pinches_resolved = 0;    ///< fans removed at pinched vertices
  size_t small_handles_removed = 0;  ///< handles smaller than the sampling taken out (small_handles.h)
  size_t holes_left = 0;          ///< boundary loops left open
  size_t largest_hole_left = 0;   ///< edges of the largest loop left open
  std::vector<std::pair<size_t, double>> open_loops;  ///< (edges, width / L) of loops left open (at most 1000)
  std::vector<size_t> holes_left_edges;  ///< the edges of every loop left open, ascending
  PieceStats pieces;                     ///< sort_out_pieces'
};

/// The fill factor of every repair pass but the last (RepairOptions::fill's, if smaller).
constexpr double kFirstFillFactor = 1.5;

/// Fragments of at most this many triangles may be dissolved (see drop_fragments).
constexpr uint32_t kMaxFragment = 12;
/// Rounds of insert_unused at most (each lets particles attach to the ones the round before put in).
constexpr int kInsertRounds = 4;
/// loop_width is cubic in the loop's edges; above this many edges it is not computed (reported
/// as infinite: such loops are openings).
constexpr size_t kMaxWidthLoop = 128;

/// At vertices whose triangles form more than one fan, keep the largest fan. Such a vertex
/// has a gap between its fans, so it starts two or more boundary edges: only those, and the
/// corners of triangles added since indexing whose triangles changed since the last call
/// (EditableSurface::take_changed_vertices), are checked. Returns the fans removed.
size_t unpinch(EditableSurface& s);

/// A particle the surface passed by (active, in no triangle) is inserted into the surface
/// triangle it lies over (split in three), or beside the nearest edge: beyond a boundary edge
/// as a new triangle on it, else splitting the edge. Every new edge is within the fill limit
/// (FillOptions::fill_limit), no new triangle folds back over the surface or overlaps a
/// vertex's fan. Particles that fit nowhere stay out. Returns how many were inserted.
/// `near`: a grid over the particles, built when first needed and kept for the next round.
size_t insert_unused(EditableSurface& s, const std::vector<uint8_t>& active, const std::vector<Triangle>& raw,
                     const FillOptions& o, std::unique_ptr<NeighborGrid>& near);

/// Fragments of a few triangles that lie against a larger piece of surface (a lone triangle
/// or a tiny closed "bubble" grown from particles the main surface passed by, where it is
/// thin or sharp) are dissolved; insert_unused then puts their particles into the surface
/// around them. A small piece on its own (a droplet of four particles) is a surface of its
/// own and stays: a fragment is only dissolved if a raw triangle joins it to a larger piece.
/// Returns the triangles removed.
size_t drop_fragments(EditableSurface& s, const std::vector<Triangle>& raw);

/// Removes every piece (triangles joined through shared vertices) of fewer than
/// `min_triangles` triangles (their particles are then in no triangle), and, when the surface
/// left is open, counts its pieces of fewer than kStrayPieceTriangles: one pass over the
/// pieces, none for a closed surface with nothing to remove. `known`: the surface's pieces,
/// if the caller has them (EditableSurface::pieces) and the surface has not changed since.
void sort_out_pieces(EditableSurface& s, size_t min_triangles, PieceStats& out,
                     const EditableSurface::Pieces* known = nullptr);

/// The whole repair, in the order above; then counts the loops left open.
void repair_surface(EditableSurface& s, const std::vector<uint8_t>& active, const std::vector<Triangle>& raw,
                    const RepairOptions& o, RepairStats& stats, ProgressTracker& tracker);

}  // namespace particlemesh::detail
