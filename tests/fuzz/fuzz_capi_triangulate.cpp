// Fuzz target: the C ABI's particle entry points fed arbitrary arrays and parameter structs:
// pm_cloud_create(_f32) (NaN/Inf, duplicates, coincident and collinear points, lattices
// full of co-circular sets), pm_cloud_set_attribute, pm_estimate_spacing and pm_triangulate
// with every option field fuzzed (struct_size included), a progress callback that may
// cancel, stats structs of any declared size. Checks: statuses and messages, outputs untouched
// on failure, a returned mesh indexes only its own vertices and keeps the particles' order.
//
// Inputs stay small (at most 64 particles) so that one run takes milliseconds whatever the
// parameters: the point is the code paths, not the scale.
#include <cmath>
#include <cstddef>
#include <vector>

#include "fuzz_support.h"
#include "particlemesh/sample/shapes.h"

using namespace particlemesh;
using fuzz::check_status;

namespace {

struct Cancel {
  int calls = 0;
  int cancel_at = -1;
  double last = -1;
};

int progress(void* user, const char* stage, double fraction) {
  // A struct_size that covers `progress` but not `progress_user_data` gives NULL here.
  if (user == nullptr) return 0;
  auto* c = static_cast<Cancel*>(user);
  PM_FUZZ_CHECK(stage != nullptr);
  PM_FUZZ_CHECK(fraction >= 0 && fraction <= 1);
  c->last = fraction;
  return ++c->calls == c->cancel_at ? 1 : 0;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  fuzz::Input in(data, size);
  const uint8_t mode = in.take<uint8_t>();
  const size_t n = size_t(in.range(0, 64));

  // Positions (and maybe normals): fuzzed numbers, or a sphere sample with fuzzed changes.
  std::vector<double> pos(3 * n), nrm;
  const bool with_normals = mode & 1;
  if (mode & 2) {
    const PointCloud s = fibonacci_sphere(std::max<size_t>(n, 1), 1.0 + double(in.take<uint8_t>()) / 64.0);
    for (size_t i = 0; i < n; ++i) {
      pos[3 * i] = s.positions[i].x;
      pos[3 * i + 1] = s.positions[i].y;
      pos[3 * i + 2] = s.positions[i].z;
    }
    const size_t edits = in.range(0, 8);
    for (size_t e = 0; e < edits && n > 0; ++e) pos[in.range(0, 3 * n - 1)] = in.number(0.125);
  } else {
    for (double& v : pos) v = in.number(0.125);
  }
  if (with_normals) {
    nrm.resize(3 * n);
    for (double& v : nrm) v = in.number(0.5);
  }

  pm_cloud* cloud = reinterpret_cast<pm_cloud*>(0x1);
  pm_status s;
  if (mode & 4) {  // float32 entry point
    std::vector<float> p32(pos.begin(), pos.end()), n32(nrm.begin(), nrm.end());
    s = pm_cloud_create_f32(n ? p32.data() : nullptr, with_normals ? n32.data() : nullptr, n, &cloud);
  } else {
    s = pm_cloud_create(n ? pos.data() : nullptr, with_normals ? nrm.data() : nullptr, n, &cloud);
  }
  check_status(s);
  if (s != PM_OK) {
    PM_FUZZ_CHECK(cloud == reinterpret_cast<pm_cloud*>(0x1));
    return 0;
  }
  size_t count = 0;
  check_status(pm_cloud_get_count(cloud, &count));
  PM_FUZZ_CHECK(count == n);

  // An attribute, sometimes with a wrong vertex count (the buffer holds what it claims).
  if (mode & 8) {
    const int32_t comps = int32_t(in.range(0, 5)) - 1;  // -1..4
    const size_t claimed = n + size_t(in.range(0, 2)) - 1;  // n-1, n, n+1
    std::vector<float> values(claimed * size_t(std::max(comps, 0)));
    for (float& v : values) v = float(in.number(1.0));
    const pm_status a = pm_cloud_set_attribute(cloud, "velocity", comps, values.data(), claimed);
    check_status(a);
    if (a == PM_OK) PM_FUZZ_CHECK(comps >= 1 && claimed == n);
  }

  if (mode & 16) {
    double spacing = -1;
    const pm_status e = pm_estimate_spacing(cloud, int32_t(in.range(0, 3)) - 1, &spacing);
    check_status(e);
    if (e == PM_OK) PM_FUZZ_CHECK(spacing > 0 && std::isfinite(spacing));
    else PM_FUZZ_CHECK(spacing == -1);
  }

  // Options: defaults, then fuzzed fields, in a buffer of the full size whatever
  // struct_size claims (a caller's struct is at least as large as it says).
  pm_triangulate_options opt;
  pm_triangulate_options_init(&opt);
  const uint8_t which = in.take<uint8_t>();
  if (which & 1) opt.spacing = in.number(0.125);
  if (which & 2) opt.max_edge_factor = in.number(0.25);
  if (which & 4) opt.threads = int32_t(in.range(0, 4)) - 1;
  if (which & 8) opt.max_neighbors = uint32_t(in.take<uint16_t>());
  if (which & 16) {
    opt.flags = in.flag() ? uint32_t(in.range(0, 31)) : in.take<uint32_t>();
    // Local or global spacing, and a viewpoint (any value: a non-finite one is refused).
    if (opt.flags & PM_TRIANGULATE_VIEWPOINT)
      for (double& v : opt.viewpoint) v = in.number(1.0);
  }
  if (which & 32) opt.normal_angle = in.number(8.0);
  if (which & 64) {
    opt.fill_holes = uint32_t(in.take<uint32_t>() % 200001);
    opt.fill_edge_factor = in.number(0.25);
    opt.min_component_triangles = in.flag() ? uint32_t(in.range(0, 8)) : in.take<uint32_t>();
  }
  if (which & 128) opt.normals = int32_t(in.range(0, 4)) - 1;
  const uint8_t size_mode = in.take<uint8_t>();
  if (size_mode % 8 == 1) opt.struct_size = uint32_t(in.range(0, sizeof(opt) + 8));
  Cancel cancel;
  if ((size_mode & 8) && opt.struct_size >= offsetof(pm_triangulate_options, progress_user_data) + sizeof(void*)) {  // (a struct_size cutting a pointer in two is refused)
    opt.progress = progress;
    opt.progress_user_data = &cancel;
    cancel.cancel_at = int(in.range(0, 6));
  }
  pm_triangulate_stats stats{};
  stats.struct_size = sizeof(stats);
  if (size_mode & 16) stats.struct_size = uint32_t(in.range(0, sizeof(stats)));
  const bool want_stats = !(size_mode & 32);
  const bool pass_options = !(size_mode & 64);

  pm_mesh* mesh = reinterpret_cast<pm_mesh*>(0x2);
  s = pm_triangulate(cloud, pass_options ? &opt : nullptr, &mesh, want_stats ? &stats : nullptr);
  check_status(s);
  if (s == PM_OK) {
    size_t nv = 0, nt = 0;
    check_status(pm_mesh_get_counts(mesh, &nv, &nt));
    PM_FUZZ_CHECK(nv == n);
    std::vector<int32_t> tris(3 * nt + 3);
    check_status(pm_mesh_copy_triangles(mesh, tris.data(), nt));
    for (size_t i = 0; i < 3 * nt; ++i) PM_FUZZ_CHECK(tris[i] >= 0 && size_t(tris[i]) < nv);
    std::vector<double> out(3 * nv + 3);
    check_status(pm_mesh_copy_positions(mesh, out.data(), nv));
    for (size_t i = 0; i < 3 * n; ++i) PM_FUZZ_CHECK(out[i] == pos[i] || (mode & 4));  // particles, in order
    pm_topology_report r{};
    r.struct_size = sizeof(r);
    check_status(pm_mesh_report(mesh, &r));
    PM_FUZZ_CHECK(r.triangles == nt);
    // The finished surface is a 2-manifold (the raw set is not).
    // The library copies the first struct_size bytes: a size ending inside `flags` still
    // reads its first byte, which holds PM_TRIANGULATE_RAW (found by fuzzing: size 33).
    const bool flags_read = pass_options && opt.struct_size > offsetof(pm_triangulate_options, flags);
    const bool raw = flags_read && (opt.flags & PM_TRIANGULATE_RAW);
    if (!raw) PM_FUZZ_CHECK(r.nonmanifold_edges == 0 && r.duplicate_triangles == 0);
    if (cancel.cancel_at > 0) PM_FUZZ_CHECK(cancel.calls < cancel.cancel_at);
    pm_mesh_destroy(mesh);
  } else {
    PM_FUZZ_CHECK(mesh == reinterpret_cast<pm_mesh*>(0x2));  // untouched
    if (s == PM_STATUS_CANCELLED) PM_FUZZ_CHECK(cancel.calls == cancel.cancel_at);
  }
  pm_cloud_destroy(cloud);
  return 0;
}
