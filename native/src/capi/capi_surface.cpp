// C ABI: triangulation of surface particles.
#include <memory>

#include "capi/firewall.h"
#include "capi/handles.h"
#include "particlemesh/surface/triangulate.h"

using namespace particlemesh;
using particlemesh::capi::guarded;
using particlemesh::capi::require;

namespace {

ProgressCallback wrap_progress(pm_progress_fn fn, void* user) {
  if (fn == nullptr) return {};
  return [fn, user](std::string_view stage, double fraction) {
    const std::string s(stage);
    return fn(user, s.c_str(), fraction) == 0;
  };
}

}  // namespace

extern "C" {

void pm_triangulate_options_init(pm_triangulate_options* options) {
  if (options == nullptr) return;
  const TriangulateOptions d;
  *options = pm_triangulate_options{};
  options->struct_size = sizeof(pm_triangulate_options);
  options->spacing = d.spacing;
  options->max_edge_factor = d.max_edge_factor;
  options->threads = d.threads;
  options->max_neighbors = uint32_t(d.max_neighbors);
  options->flags = 0;
  options->progress = nullptr;
  options->progress_user_data = nullptr;
}

pm_status pm_triangulate(const pm_cloud* cloud, const pm_triangulate_options* options,
                         pm_mesh** out_mesh, pm_triangulate_stats* out_stats) {
  return guarded([&] {
    require(cloud, "cloud");
    require(out_mesh, "out_mesh");
    pm_triangulate_options defaults;
    pm_triangulate_options_init(&defaults);
    const pm_triangulate_options o = capi::read_versioned(options, defaults, "options");
    if (out_stats) capi::check_versioned(out_stats, "out_stats");
    TriangulateOptions opt;
    opt.spacing = o.spacing;
    opt.max_edge_factor = o.max_edge_factor;
    opt.threads = o.threads;
    opt.max_neighbors = o.max_neighbors;
    opt.progress = wrap_progress(o.progress, o.progress_user_data);
    TriangulateResult r = triangulate_raw(cloud->cloud, opt);
    auto handle = std::make_unique<pm_mesh>();
    handle->mesh = std::move(r.mesh);
    if (out_stats) {
      pm_triangulate_stats s{};
      s.struct_size = sizeof(s);
      s.spacing = r.stats.spacing;
      s.max_edge = r.stats.max_edge;
      s.spacing_estimated = r.stats.spacing_estimated;
      s.points = r.stats.points;
      s.duplicate_points = r.stats.duplicate_points;
      s.max_neighbors_seen = r.stats.max_neighbors_seen;
      s.candidates = r.stats.candidates;
      s.kept = r.stats.kept;
      capi::write_versioned(out_stats, s, "out_stats");
    }
    *out_mesh = handle.release();
  });
}

}  // extern "C"
