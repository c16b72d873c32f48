// Internal: from the raw triangles to the finished surface's triangles and vertex normals -
// the extraction and repair stages in order:
//   candidates.h   co-normality, orientation by the normals, ranking, corner lists
//   growth.h       best-first manifold growth in blocks, then across their seams
//   repair.h       loop filling (hole_fill.h), unpinching, fragments, unused particles
//   vertex_normals.h
// (orient_outward.h turns closed components outward afterwards.)
#pragma once

#include "particlemesh/core/config.h"

#include <cmath>
#include <cstdint>
#include <utility>
#include <vector>

#include "core/progress_tracker.h"
#include "particlemesh/core/vec3.h"
#include "particlemesh/mesh/tri_mesh.h"
#include "surface/repair.h"
#include "surface/view_rays.h"

namespace PM_NAMESPACE::detail {

struct BuilderOptions {
  double cos_normal_angle = -0.5;  ///< co-normality: corner normals and face normal agree within
  /// Per point (sorted index): its edge limit L of the raw test (RawTriangulation::max_edge).
  const std::vector<double>* max_edge = nullptr;
  double edge_cap = INFINITY;     ///< no repair edge longer than this (RawTriangulation::edge_cap)
  size_t small_hole = 6;          ///< loops up to this many edges are filled before unpinching
  size_t max_hole = 100;          ///< loops up to this many edges may be filled (0 = none)
  double fill_edge_factor = 1.5;  ///< fill triangles' edges at most this x L
  size_t min_component_triangles = 0;  ///< pieces of fewer triangles are removed (0 = none)
  ViewRays view;                  ///< a scan's sensor: no triangle bridges a depth jump
  bool trace_loops = false;       ///< give the loops left open as vertex sequences (BuilderStats::loops)
};

struct BuilderStats {
  size_t candidates = 0;          ///< oriented candidates after co-normality
  size_t rejected_conormal = 0;   ///< raw triangles dropped by co-normality
  size_t rejected_shadow = 0;     ///< raw triangles dropped for bridging a depth jump
  size_t grown = 0;               ///< triangles accepted by growth
  size_t seeds = 0;
  size_t pinches_resolved = 0;    ///< fans removed at pinched vertices
  size_t small_handles_removed = 0;  ///< handles smaller than the sampling taken out
  size_t holes_filled = 0;
  size_t hole_triangles = 0;
  size_t holes_left = 0;          ///< boundary loops left open
  size_t largest_hole_left = 0;   ///< edges of the largest loop left open
  size_t components_flipped = 0;  ///< closed components turned to face outward
  size_t unused_points = 0;       ///< distinct points in no triangle
  PieceStats pieces;  ///< removed for min_component_triangles, and the strays left
  double seconds_candidates = 0, seconds_growth = 0, seconds_repair = 0;
  std::vector<uint64_t> boundary;  ///< boundary half-edges (a << 32 | b), sorted
  /// With BuilderOptions::trace_loops: the loops left open (EditableSurface::trace_loops).
  std::vector<std::vector<uint32_t>> loops;
  std::vector<std::pair<size_t, double>> open_loops;  ///< (edges, width / L) of loops left open
  std::vector<size_t> holes_left_edges;  ///< the edges of every loop left open, ascending
};

/// positions/normals (normals unit or zero = unknown); `active[i]` false for duplicates; `raw`
/// the raw triangles (sorted indices). Returns oriented triangles, and in `vertex_normals` the
/// surface's angle-weighted vertex normals (a point in no triangle keeps its normal).
std::vector<Triangle> build_surface(const std::vector<Vec3>& positions, const std::vector<Vec3>& normals,
                                    const std::vector<uint8_t>& active, const std::vector<Triangle>& raw,
                                    const BuilderOptions& options, bool repair, BuilderStats& stats,
                                    ProgressTracker& tracker, std::vector<Vec3>& vertex_normals);

}  // namespace particlemesh::detail
