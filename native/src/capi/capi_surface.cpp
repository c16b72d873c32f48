// C ABI: triangulation of surface particles.
#include <cmath>
#include <memory>

#include "capi/conversions.h"
#include "capi/firewall.h"
#include "capi/handles.h"
#include "particlemesh/surface/reconstruct.h"
#include "particlemesh/surface/triangulate.h"

using namespace particlemesh;
using particlemesh::capi::guarded;
using particlemesh::capi::wrap_progress;
using particlemesh::capi::require;

extern "C" {

void pm_triangulate_options_init(pm_triangulate_options* options) {
  if (!capi::reset_versioned(options)) return;
  const SurfaceOptions d;
  options->spacing = d.spacing;
  options->max_edge_factor = d.max_edge_factor;
  options->threads = d.threads;
  options->max_neighbors = uint32_t(d.max_neighbors);
  options->flags = 0;
  options->normal_angle = d.normal_angle;
  options->fill_holes = uint32_t(d.fill_holes);
  options->fill_edge_factor = d.fill_edge_factor;
  options->normals = PM_NORMALS_AUTO;
  options->max_triplets_per_point = uint32_t(d.max_triplets_per_point);
  options->min_component_triangles = uint32_t(d.min_component_triangles);
}

pm_status pm_triangulate(const pm_cloud* cloud, const pm_triangulate_options* options,
                         pm_mesh** out_mesh, pm_triangulate_stats* out_stats) {
  return guarded([&] {
    require(cloud, "cloud");
    require(out_mesh, "out_mesh");
    const pm_triangulate_options o = capi::read_options(options, pm_triangulate_options_init);
    if (out_stats) capi::check_versioned(out_stats, "out_stats");
    if (o.flags & ~uint32_t(PM_TRIANGULATE_RAW | PM_TRIANGULATE_NO_REPAIR | PM_TRIANGULATE_NO_ORIENT |
                            PM_TRIANGULATE_GLOBAL_SPACING | PM_TRIANGULATE_VIEWPOINT))
      throw Error(Status::InvalidArgument, "options->flags has unknown bits");
    if ((o.flags & PM_TRIANGULATE_VIEWPOINT) &&
        !(std::isfinite(o.viewpoint[0]) && std::isfinite(o.viewpoint[1]) && std::isfinite(o.viewpoint[2])))
      throw Error(Status::InvalidArgument, "options->viewpoint is not finite");
    if (o.normals < PM_NORMALS_AUTO || o.normals > PM_NORMALS_ESTIMATE)
      throw Error(Status::InvalidArgument, "options->normals must be PM_NORMALS_AUTO, _INPUT or _ESTIMATE");
    SurfaceOptions opt;
    opt.spacing = o.spacing;
    opt.max_edge_factor = o.max_edge_factor;
    opt.threads = o.threads;
    opt.max_neighbors = o.max_neighbors;
    opt.max_triplets_per_point = o.max_triplets_per_point;
    opt.progress = wrap_progress(o.progress, o.progress_user_data);
    opt.normal_angle = o.normal_angle;
    opt.fill_holes = o.fill_holes;
    opt.fill_edge_factor = o.fill_edge_factor;
    opt.min_component_triangles = o.min_component_triangles;
    opt.repair = !(o.flags & PM_TRIANGULATE_NO_REPAIR);
    opt.orient = !(o.flags & PM_TRIANGULATE_NO_ORIENT);
    opt.local_spacing = !(o.flags & PM_TRIANGULATE_GLOBAL_SPACING);
    opt.has_viewpoint = (o.flags & PM_TRIANGULATE_VIEWPOINT) != 0;
    opt.viewpoint = {o.viewpoint[0], o.viewpoint[1], o.viewpoint[2]};
    opt.normals = o.normals == PM_NORMALS_INPUT ? SurfaceOptions::NormalSource::Input
                  : o.normals == PM_NORMALS_ESTIMATE ? SurfaceOptions::NormalSource::Estimate
                                                     : SurfaceOptions::NormalSource::Auto;
    SurfaceResult r;
    if (o.flags & PM_TRIANGULATE_RAW) {
      TriangulateResult raw = triangulate_raw(cloud->cloud, opt);
      r.mesh = std::move(raw.mesh);
      r.triangulation = raw.stats;
    } else {
      r = reconstruct_surface(cloud->cloud, opt);
    }
    auto handle = std::make_unique<pm_mesh>();
    handle->mesh = std::move(r.mesh);
    if (out_stats) {
      pm_triangulate_stats s{};
      s.struct_size = sizeof(s);
      s.spacing = r.triangulation.spacing;
      s.max_edge = r.triangulation.max_edge;
      s.spacing_estimated = r.triangulation.spacing_estimated;
      s.points = r.triangulation.points;
      s.duplicate_points = r.triangulation.duplicate_points;
      s.max_neighbors_seen = r.triangulation.max_neighbors_seen;
      s.candidates = r.triangulation.candidates;
      s.kept = r.triangulation.kept;
      s.holes_filled = r.surface.holes_filled;
      s.holes_left = r.surface.holes_left;
      s.largest_hole_left = r.surface.largest_hole_left;
      s.pinches_resolved = r.surface.pinches_resolved;
      s.unused_points = r.surface.unused_points;
      s.normals_estimated = r.surface.normals_estimated;
      s.triplets = r.triangulation.triplets;
      s.rejected_conormal = r.surface.rejected_conormal;
      const SurfaceStats::Spread& h = r.surface.local_spacing;
      s.local_spacing[0] = h.min;
      s.local_spacing[1] = h.p10;
      s.local_spacing[2] = h.median;
      s.local_spacing[3] = h.p90;
      s.local_spacing[4] = h.max;
      s.viewpoint_used = r.surface.viewpoint_used;
      s.rejected_shadow = r.surface.rejected_shadow;
      s.looks_like_volume = r.surface.looks_like_volume;
      s.narrow_loops = r.surface.narrow_loops.count;
      s.narrow_loop_width = r.surface.narrow_loops.width;
      s.narrow_loop_edges = r.surface.narrow_loops.edges;
      s.sampling_irregularity = r.triangulation.sampling_irregularity;
      s.reach_factor = r.triangulation.reach_factor;
      s.sampling_thickness = r.triangulation.sampling_thickness;
      s.components_removed = r.surface.components_removed;
      s.component_triangles_removed = r.surface.component_triangles_removed;
      s.stray_pieces = r.surface.stray_pieces.count;
      s.stray_piece_triangles = r.surface.stray_pieces.triangles;
      s.stray_piece_largest = r.surface.stray_pieces.largest;
      s.small_handles_removed = r.surface.small_handles_removed;
      s.shortened_limits = r.triangulation.shortened_limits;
      s.near_duplicates = r.triangulation.near_duplicates;
      s.flat_pieces_opened = r.surface.flat_pieces_opened;
      s.nearly_closed_turned = r.surface.nearly_closed_turned;
      s.folded_triangles = r.surface.folded_triangles;
      s.uncapped_spacing_p90 = r.triangulation.uncapped_spacing_p90;
      s.capped_spacing_over_nn = r.triangulation.capped_spacing_over_nn;
      capi::write_versioned(out_stats, s, "out_stats");
    }
    *out_mesh = handle.release();
  });
}

}  // extern "C"
