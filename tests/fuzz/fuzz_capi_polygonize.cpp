// Fuzz target: pm_polygonize_ex and pm_default_radius fed arbitrary arrays and
// parameter structs:
// particles (NaN/Inf, duplicates, far apart), per-particle radii and strengths (<= 0, NaN,
// huge), every option field (kernel, radius, threshold, cell size, threads, the grid budget,
// struct_size, anisotropic kernels, dropping pieces, Taubin smoothing; a tile's flags,
// domain_min, domain_max_radius and cell range), stats structs of any declared size, a
// progress callback that may cancel.
// Checks: statuses and messages, outputs untouched on failure, a returned mesh is closed,
// 2-manifold, indexes its own finite vertices, has normals, and its grid kept to the budget.
//
// The grid budget is kept at 16 MiB or less whatever the input (a short struct_size that
// leaves it out also leaves out the cell size and radius that would need it), so that one
// run stays small; the budget check itself is what is fuzzed.
#include <cmath>
#include <cstddef>
#include <vector>

#include "fuzz_support.h"

using namespace particlemesh;
using fuzz::check_status;

namespace {

struct Cancel {
  int calls = 0;
  int cancel_at = -1;
};

int progress(void* user, const char* stage, double fraction) {
  // A struct_size that covers `progress` but not `progress_user_data` gives NULL here.
  if (user == nullptr) return 0;
  auto* c = static_cast<Cancel*>(user);
  PM_FUZZ_CHECK(stage != nullptr);
  PM_FUZZ_CHECK(fraction >= 0 && fraction <= 1);
  return ++c->calls == c->cancel_at ? 1 : 0;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  fuzz::Input in(data, size);
  const uint8_t mode = in.take<uint8_t>();
  const size_t n = size_t(in.range(1, 48));
  std::vector<double> pos(3 * n);
  for (double& v : pos) v = in.number(0.25);
  pm_cloud* cloud = nullptr;
  pm_status s = pm_cloud_create(pos.data(), nullptr, n, &cloud);
  check_status(s);
  if (s != PM_OK) return 0;

  std::vector<double> radii, strengths;
  if (mode & 1) {
    radii.resize(n);
    for (double& r : radii) r = in.flag() ? 0.5 + double(in.take<uint8_t>()) / 64.0 : in.number(0.25);
  }
  if (mode & 2) {
    strengths.resize(n);
    for (double& w : strengths) w = in.flag() ? 1.0 : in.number(1.0);
  }

  pm_polygonize_options opt;
  pm_polygonize_options_init(&opt);
  const uint8_t which = in.take<uint8_t>();
  if (which & 1) opt.kernel = int32_t(in.range(0, 5)) - 1;
  if (which & 2) opt.radius = in.number(0.25);
  if (which & 4) opt.threshold = in.number(1.0);
  if (which & 8) opt.cell_size = in.number(1.0 / 64);
  if (which & 16) opt.threads = int32_t(in.range(0, 3)) - 1;
  opt.max_grid_bytes = (which & 32) ? in.take<uint32_t>() % (uint64_t(16) << 20) : (uint64_t(16) << 20);
  if (opt.max_grid_bytes == 0) opt.max_grid_bytes = 1;  // 0 would be "no limit"
  const uint8_t size_mode = in.take<uint8_t>();
  if (size_mode % 8 == 1) {
    opt.struct_size = uint32_t(in.range(0, sizeof(opt) + 8));
    if (opt.struct_size < offsetof(pm_polygonize_options, max_grid_bytes) + sizeof(uint64_t)) {
      // The budget is not read (4 GiB default): keep the grid to the defaults' size.
      opt.radius = 0;
      opt.cell_size = 0;
      radii.clear();
    }
  }
  Cancel cancel;
  if ((size_mode & 8) && opt.struct_size >= offsetof(pm_polygonize_options, progress_user_data) + sizeof(void*)) {  // (a struct_size cutting a pointer in two is refused)
    opt.progress = progress;
    opt.progress_user_data = &cancel;
    cancel.cancel_at = int(in.range(0, 8));
  }
  pm_polygonize_stats stats{};
  stats.struct_size = sizeof(stats);
  if (size_mode & 16) stats.struct_size = uint32_t(in.range(0, sizeof(stats)));
  stats.grid_bytes = 12345;
  // The appended fields, from bytes after everything above (older inputs keep their meaning):
  // anisotropic kernels with parameters in and out of range, dropping pieces, smoothing.
  const uint8_t extra = in.take<uint8_t>();
  if (extra & 1) {
    opt.anisotropic = 1;
    if (extra & 2) opt.aniso_neighbor_radius = in.flag() ? 0.5 + double(in.take<uint8_t>()) / 64.0 : in.number(1.0);
    if (extra & 4) opt.aniso_max_stretch = in.flag() ? 1.0 + double(in.take<uint8_t>()) / 16.0 : in.number(4.0);
    if (extra & 8) opt.aniso_min_neighbors = int32_t(in.range(0, 40)) - 2;
    if (extra & 16) opt.aniso_smoothing = in.flag() ? double(in.take<uint8_t>()) / 255.0 : in.number(0.25);
  }
  if (extra & 32) opt.min_component_volume = in.number(1.0 / 64);
  if (extra & 64) opt.min_component_particles = in.number(1.0);
  if (extra & 128) {
    opt.taubin_iterations = int32_t(in.range(0, 12)) - 1;
    if (in.flag()) opt.taubin_lambda = in.number(0.25);
    if (in.flag()) opt.taubin_mu = in.number(0.25);
  }

  // A tile's options, read last (inputs made before they existed leave them off).
  const uint8_t tile = in.take<uint8_t>();
  if (tile & 1) {
    opt.flags = uint32_t(in.take<uint8_t>()) & ((tile & 2) ? 0xffu : 0x3u);
    double lo[3] = {pos[0], pos[1], pos[2]};
    for (size_t i = 0; i < n; ++i)
      for (int a = 0; a < 3; ++a) lo[a] = std::fmin(lo[a], pos[3 * i + a]);
    for (int a = 0; a < 3; ++a) opt.domain_min[a] = (tile & 4) ? in.number(0.25) : lo[a] - std::fabs(in.number(1.0 / 16));
    if (tile & 8) opt.domain_max_radius = in.number(0.25);
    for (int a = 0; a < 3; ++a) {
      opt.cell_min[a] = (tile & 16) ? int64_t(in.take<uint64_t>()) : int64_t(in.range(0, 64)) - 8;
      opt.cell_max[a] = int64_t(uint64_t(opt.cell_min[a]) + in.range(0, 64) - 2);  // wraps, never overflows
    }
  }
  // Short edges collapsed, read after the tile's options: in range (up to 0.64 cells, over the
  // limit too) or any number; the mesh must stay as manifold as without.
  const uint8_t collapse = in.take<uint8_t>();
  if (collapse & 1) opt.collapse_edges = (collapse & 2) ? in.number(0.25) : double(in.take<uint8_t>()) / 400.0;
  const bool ranged = (opt.flags & PM_POLYGONIZE_CELL_RANGE) && opt.struct_size >= sizeof(opt) && !(size_mode & 32);

  // The default radius alone (pm_default_radius): on success what pm_polygonize_ex resolves
  // for the same cloud, strengths and kernel (checked below); on failure nothing written.
  double default_radius = -7;
  const pm_status ds = pm_default_radius(cloud, strengths.empty() ? nullptr : strengths.data(), opt.kernel,
                                         opt.threads, &default_radius);
  check_status(ds);
  PM_FUZZ_CHECK(ds == PM_OK ? default_radius > 0 && std::isfinite(default_radius) : default_radius == -7);
  const bool same_default = ds == PM_OK && radii.empty() && opt.radius == 0 && !opt.anisotropic && opt.flags == 0 &&
                            opt.struct_size == sizeof(opt) && !(size_mode & 32) && !(size_mode & 64) &&
                            stats.struct_size == sizeof(stats);

  pm_mesh* mesh = reinterpret_cast<pm_mesh*>(0x2);
  s = pm_polygonize_ex(cloud, radii.empty() ? nullptr : radii.data(), strengths.empty() ? nullptr : strengths.data(),
                       (size_mode & 32) ? nullptr : &opt, &mesh, (size_mode & 64) ? nullptr : &stats);
  check_status(s);
  if (s == PM_OK) {
    size_t nv = 0, nt = 0;
    check_status(pm_mesh_get_counts(mesh, &nv, &nt));
    std::vector<int32_t> tris(3 * nt + 3);
    check_status(pm_mesh_copy_triangles(mesh, tris.data(), nt));
    for (size_t i = 0; i < 3 * nt; ++i) PM_FUZZ_CHECK(tris[i] >= 0 && size_t(tris[i]) < nv);
    std::vector<double> p(3 * nv + 3);
    check_status(pm_mesh_copy_positions(mesh, p.data(), nv));
    for (size_t i = 0; i < 3 * nv; ++i) PM_FUZZ_CHECK(std::isfinite(p[i]));
    if (nv > 0) {
      int32_t has = 0;
      check_status(pm_mesh_has_normals(mesh, &has));
      PM_FUZZ_CHECK(has == 1);
    }
    pm_topology_report r{};
    r.struct_size = sizeof(r);
    check_status(pm_mesh_report(mesh, &r));
    // A tile's cells end at its range's faces: open there, manifold everywhere.
    PM_FUZZ_CHECK((ranged || r.boundary_edges == 0) && r.nonmanifold_edges == 0 && r.duplicate_triangles == 0);
    if (!(size_mode & 64) && stats.struct_size == sizeof(stats) && !(size_mode & 32) &&
        opt.struct_size == sizeof(opt))
      PM_FUZZ_CHECK(stats.grid_bytes <= opt.max_grid_bytes && stats.triangles == nt);
    if (same_default) PM_FUZZ_CHECK(stats.radius == default_radius);
    pm_mesh_destroy(mesh);
  } else {
    PM_FUZZ_CHECK(mesh == reinterpret_cast<pm_mesh*>(0x2));
    PM_FUZZ_CHECK(stats.grid_bytes == 12345);
    if (s == PM_STATUS_CANCELLED) PM_FUZZ_CHECK(cancel.calls == cancel.cancel_at);
  }
  pm_cloud_destroy(cloud);
  return 0;
}
