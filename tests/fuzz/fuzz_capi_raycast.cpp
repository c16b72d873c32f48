// Fuzz target: the ray casting C ABI fed arbitrary arrays and parameter structs:
// pm_field_create (particles, radii, strengths, every option field including anisotropic
// kernels, struct_size), then
// batches of rays with any origins and directions (zero, NaN, Inf, huge) through
// pm_raycast_first (any output NULL), pm_raycast_all and pm_raycast_csg (any op), with fuzzed
// t ranges, struct sizes and a progress callback that may cancel; pm_field_values.
// Checks: statuses and messages, outputs untouched on failure, per ray hits in [t_min, t_max]
// in increasing order and alternating entering/leaving, offsets consistent with the counts.
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

void check_hits(const pm_ray_hits* hits, size_t rays, double t_min, double t_max) {
  size_t nr = 0, nh = 0;
  check_status(pm_ray_hits_get_counts(hits, &nr, &nh));
  PM_FUZZ_CHECK(nr == rays);
  std::vector<uint64_t> off(nr + 1);
  check_status(pm_ray_hits_copy_offsets(hits, off.data(), nr + 1));
  PM_FUZZ_CHECK(off[0] == 0 && off[nr] == nh);
  std::vector<double> t(nh + 1), p(3 * nh + 3), n(3 * nh + 3);
  std::vector<int32_t> entering(nh + 1), inside(nr + 1);
  check_status(pm_ray_hits_copy(hits, t.data(), p.data(), n.data(), entering.data(), nh));
  check_status(pm_ray_hits_copy_starts_inside(hits, inside.data(), nr));
  for (size_t r = 0; r < nr; ++r) {
    PM_FUZZ_CHECK(off[r] <= off[r + 1]);
    bool in = inside[r] != 0;
    for (uint64_t h = off[r]; h < off[r + 1]; ++h) {
      PM_FUZZ_CHECK(t[h] >= t_min && t[h] <= t_max);
      if (h > off[r]) PM_FUZZ_CHECK(t[h] >= t[h - 1]);
      PM_FUZZ_CHECK(bool(entering[h]) == !in);  // hits alternate, starting from the ray's side
      in = !in;
      for (int a = 0; a < 3; ++a) PM_FUZZ_CHECK(std::isfinite(p[3 * h + a]) && std::isfinite(n[3 * h + a]));
    }
  }
  // A capacity one short is refused.
  if (nh > 0) PM_FUZZ_CHECK(pm_ray_hits_copy(hits, t.data(), nullptr, nullptr, nullptr, nh - 1) != PM_OK);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  fuzz::Input in(data, size);
  const uint8_t mode = in.take<uint8_t>();
  const size_t n = size_t(in.range(1, 32));
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
  pm_field_options fo;
  pm_field_options_init(&fo);
  const uint8_t which = in.take<uint8_t>();
  if (which & 1) fo.kernel = int32_t(in.range(0, 5)) - 1;
  if (which & 2) fo.radius = in.number(0.25);
  if (which & 4) fo.threshold = in.number(1.0);
  if (which & 8) fo.threads = int32_t(in.range(0, 3)) - 1;
  if (which & 16) fo.struct_size = uint32_t(in.range(0, sizeof(fo) + 8));
  Cancel field_cancel;
  if ((which & 32) && fo.struct_size >= offsetof(pm_field_options, progress_user_data) + sizeof(void*)) {
    fo.progress = progress;
    fo.progress_user_data = &field_cancel;
    field_cancel.cancel_at = int(in.range(0, 4));
  }
  // Anisotropic kernels (the last free bit of `which`: inputs without it keep their meaning).
  const uint8_t extra = (which & 128) ? in.take<uint8_t>() | 1 : 0;
  if (extra & 1) {
    fo.anisotropic = 1;
    if (extra & 2) fo.aniso_neighbor_radius = in.flag() ? 0.5 + double(in.take<uint8_t>()) / 64.0 : in.number(1.0);
    if (extra & 4) fo.aniso_max_stretch = in.flag() ? 1.0 + double(in.take<uint8_t>()) / 16.0 : in.number(4.0);
    if (extra & 8) fo.aniso_min_neighbors = int32_t(in.range(0, 40)) - 2;
    if (extra & 16) fo.aniso_smoothing = in.flag() ? double(in.take<uint8_t>()) / 255.0 : in.number(0.25);
  }
  pm_field* field = reinterpret_cast<pm_field*>(0x2);
  s = pm_field_create(cloud, radii.empty() ? nullptr : radii.data(), strengths.empty() ? nullptr : strengths.data(),
                      (which & 64) ? nullptr : &fo, &field);
  check_status(s);
  pm_cloud_destroy(cloud);
  if (s != PM_OK) {
    PM_FUZZ_CHECK(field == reinterpret_cast<pm_field*>(0x2));
    return 0;
  }
  double R = 0, T = 0;
  check_status(pm_field_get_params(field, &R, &T));
  PM_FUZZ_CHECK(R > 0 && T > 0 && std::isfinite(R) && std::isfinite(T));

  // Rays: mostly through the particles' neighbourhood, some anything.
  const size_t rays = size_t(in.range(0, 16));
  std::vector<double> o(3 * rays + 3), d(3 * rays + 3);
  for (size_t r = 0; r < rays; ++r)
    for (int a = 0; a < 3; ++a) {
      o[3 * r + a] = in.flag() ? pos[3 * (r % n) + a] - 4 * R : in.number(0.25);
      d[3 * r + a] = in.number(0.25);
    }
  pm_raycast_options ro;
  pm_raycast_options_init(&ro);
  const uint8_t rwhich = in.take<uint8_t>();
  if (rwhich & 1) ro.t_min = in.number(1.0);
  if (rwhich & 2) ro.t_max = in.number(1.0);
  if (rwhich & 4) ro.threads = int32_t(in.range(0, 3)) - 1;
  if (rwhich & 8) ro.struct_size = uint32_t(in.range(0, sizeof(ro) + 8));
  Cancel ray_cancel;
  if ((rwhich & 16) && ro.struct_size >= offsetof(pm_raycast_options, progress_user_data) + sizeof(void*)) {
    ro.progress = progress;
    ro.progress_user_data = &ray_cancel;
    ray_cancel.cancel_at = int(in.range(0, 4));
  }
  const pm_raycast_options* rop = (rwhich & 32) ? nullptr : &ro;
  // The t range the call uses: the fields struct_size covers, defaults for the rest.
  const bool has_min = rop && ro.struct_size >= offsetof(pm_raycast_options, t_min) + sizeof(double);
  const bool has_max = rop && ro.struct_size >= offsetof(pm_raycast_options, t_max) + sizeof(double);
  const double t_min = has_min ? ro.t_min : 0, t_max = has_max ? ro.t_max : INFINITY;

  // First hits, with any of the outputs NULL.
  {
    std::vector<double> t(rays + 1, -7), p(3 * rays + 3, -7), nn(3 * rays + 3, -7);
    std::vector<int32_t> e(rays + 1, -7);
    size_t hit_count = 12345;
    const uint8_t outs = in.take<uint8_t>();
    const pm_status f = pm_raycast_first(field, rays ? o.data() : nullptr, rays ? d.data() : nullptr, rays, rop,
                                         (outs & 1) ? nullptr : t.data(), (outs & 2) ? nullptr : p.data(),
                                         (outs & 4) ? nullptr : nn.data(), (outs & 8) ? nullptr : e.data(),
                                         (outs & 16) ? nullptr : &hit_count);
    check_status(f);
    if (f == PM_OK) {
      size_t hits = 0;
      for (size_t r = 0; r < rays && !(outs & 1); ++r) {
        PM_FUZZ_CHECK(std::isinf(t[r]) || (t[r] >= t_min && t[r] <= t_max));
        hits += std::isfinite(t[r]);
      }
      if (!(outs & 1) && !(outs & 16)) PM_FUZZ_CHECK(hit_count == hits);
    } else {
      PM_FUZZ_CHECK(t[0] == -7 && p[0] == -7 && nn[0] == -7 && e[0] == -7 && hit_count == 12345);
    }
  }
  // All hits, and a CSG of the field with itself.
  {
    pm_ray_hits* hits = reinterpret_cast<pm_ray_hits*>(0x3);
    const pm_status a = pm_raycast_all(field, rays ? o.data() : nullptr, rays ? d.data() : nullptr, rays, rop, &hits);
    check_status(a);
    if (a == PM_OK) {
      check_hits(hits, rays, t_min, t_max);
      pm_ray_hits_destroy(hits);
    } else {
      PM_FUZZ_CHECK(hits == reinterpret_cast<pm_ray_hits*>(0x3));
    }
    const int32_t op = int32_t(in.range(0, 4)) - 1;
    hits = reinterpret_cast<pm_ray_hits*>(0x3);
    const pm_status c = pm_raycast_csg(field, field, op, rays ? o.data() : nullptr, rays ? d.data() : nullptr, rays,
                                       rop, &hits);
    check_status(c);
    if (c == PM_OK) {
      check_hits(hits, rays, t_min, t_max);
      pm_ray_hits_destroy(hits);
    } else {
      PM_FUZZ_CHECK(hits == reinterpret_cast<pm_ray_hits*>(0x3));
    }
  }
  // Field values at the ray origins.
  {
    std::vector<double> v(rays + 1, -7);
    const pm_status f = pm_field_values(field, rays ? o.data() : nullptr, rays, v.data());
    check_status(f);
    if (f == PM_OK)
      for (size_t r = 0; r < rays; ++r) PM_FUZZ_CHECK(std::isfinite(v[r]) && v[r] >= 0 || !strengths.empty());
  }
  pm_field_destroy(field);
  return 0;
}
