#include "surface/surface_builder.h"

#include <chrono>

#include "surface/candidates.h"
#include "surface/editable_surface.h"
#include "surface/growth.h"
#include "surface/repair.h"
#include "surface/vertex_normals.h"

namespace PM_NAMESPACE::detail {

std::vector<Triangle> build_surface(const std::vector<Vec3>& positions, const std::vector<Vec3>& normals,
                                    const std::vector<uint8_t>& active, const std::vector<Triangle>& raw,
                                    const BuilderOptions& options, bool repair, BuilderStats& stats,
                                    ProgressTracker& tracker, std::vector<Vec3>& vertex_normals) {
  using Clock = std::chrono::steady_clock;
  auto since = [](Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); };
  auto t0 = Clock::now();
  const std::vector<Frame> frames = tangent_frames(normals);
  CandidateSet cands =
      rank_candidates(positions, normals, frames, active, raw, options.cos_normal_angle, tracker, options.view);
  stats.candidates = cands.cand.size();
  stats.rejected_conormal = cands.rejected_conormal;
  stats.rejected_shadow = cands.rejected_shadow;
  stats.seconds_candidates = since(t0);
  t0 = Clock::now();
  GrownSurface grown = grow_surface(positions.size(), std::move(cands), tracker);
  stats.grown = grown.grown;
  stats.seeds = grown.seeds;
  EditableSurface surface(positions, frames, std::move(grown), tracker);
  stats.seconds_growth = since(t0);
  t0 = Clock::now();
  if (repair) {
    RepairOptions ro;
    ro.fill.max_edge = options.max_edge;
    ro.fill.fill_edge_factor = options.fill_edge_factor;
    ro.fill.edge_cap = options.edge_cap;
    ro.fill.view = options.view;
    ro.fill.small_hole = options.small_hole;
    ro.max_hole = options.max_hole;
    ro.min_component_triangles = options.min_component_triangles;
    RepairStats rs;
    repair_surface(surface, active, raw, ro, rs, tracker);
    stats.pinches_resolved = rs.pinches_resolved;
    stats.small_handles_removed = rs.small_handles_removed;
    stats.holes_filled = rs.holes_filled;
    stats.hole_triangles = rs.hole_triangles;
    stats.holes_left = rs.holes_left;
    stats.largest_hole_left = rs.largest_hole_left;
    stats.open_loops = std::move(rs.open_loops);
    stats.holes_left_edges = std::move(rs.holes_left_edges);
    stats.pieces = rs.pieces;
  } else {
    sort_out_pieces(surface, options.min_component_triangles, stats.pieces);
  }
  stats.seconds_repair = since(t0);
  stats.boundary = surface.boundary();
  if (options.trace_loops && !stats.boundary.empty()) stats.loops = surface.trace_loops();
  tracker.check();
  vertex_normals = surface_vertex_normals(surface, active, normals, stats.unused_points);
  return surface.take();
}

}  // namespace particlemesh::detail
