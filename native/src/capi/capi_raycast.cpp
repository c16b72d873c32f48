// C ABI: ray casting of the iso-surface of volume particles.
#include <cmath>
#include <cstring>
#include <memory>
#include <string>

#include "capi/conversions.h"
#include "capi/firewall.h"
#include "capi/handles.h"
#include "particlemesh/volume/ray_csg.h"
#include "particlemesh/volume/raycast.h"

using namespace particlemesh;
using particlemesh::capi::guarded;
using particlemesh::capi::wrap_progress;
using particlemesh::capi::require;

struct pm_field {
  RayCaster caster;
};

struct pm_ray_hits {
  AllHits hits;
};

namespace {

const Vec3* as_vec3(const double* p) { return reinterpret_cast<const Vec3*>(p); }

RaycastOptions to_options(const pm_raycast_options* options) {
  const pm_raycast_options o = capi::read_options(options, pm_raycast_options_init);
  RaycastOptions r;
  r.t_min = o.t_min;
  r.t_max = o.t_max;
  r.threads = o.threads;
  r.progress = wrap_progress(o.progress, o.progress_user_data);
  return r;
}

void check_rays(const double* origins, const double* directions, size_t count) {
  if (count == 0) return;
  require(origins, "origins");
  require(directions, "directions");
}

}  // namespace

extern "C" {

void pm_field_options_init(pm_field_options* options) {
  if (!capi::reset_versioned(options)) return;
  const FieldParams d;
  capi::kernel_settings_to_c(d, options);
  options->threads = 0;
}

pm_status pm_field_create(const pm_cloud* cloud, const double* radii, const double* strengths,
                          const pm_field_options* options, pm_field** out_field) {
  return guarded([&] {
    require(cloud, "cloud");
    require(out_field, "out_field");
    const pm_field_options o = capi::read_options(options, pm_field_options_init);
    FieldParams p;
    capi::kernel_settings_from_c(o, radii, strengths, cloud->cloud.size(), &p);
    auto handle = std::make_unique<pm_field>();
    handle->caster = RayCaster(ParticleField(cloud->cloud, p, o.threads, wrap_progress(o.progress, o.progress_user_data)));
    *out_field = handle.release();
  });
}

pm_status pm_field_get_params(const pm_field* field, double* out_radius, double* out_threshold) {
  return guarded([&] {
    require(field, "field");
    const auto& f = field->caster.field();
    if (out_radius) *out_radius = f.params().radius;
    if (out_threshold) *out_threshold = f.threshold();
  });
}

pm_status pm_field_values(const pm_field* field, const double* points, size_t count, double* out_values) {
  return guarded([&] {
    require(field, "field");
    if (count == 0) return;
    require(points, "points");
    require(out_values, "out_values");
    std::vector<double> v(count);
    const auto& f = field->caster.field();
    for (size_t i = 0; i < count; ++i) {
      const Vec3 x{points[3 * i], points[3 * i + 1], points[3 * i + 2]};
      if (!is_finite(x)) throw Error(Status::InvalidArgument, "points[" + std::to_string(i) + "] is not finite");
      v[i] = f.value(x);
    }
    std::memcpy(out_values, v.data(), count * sizeof(double));
  });
}

void pm_field_destroy(pm_field* field) { delete field; }

void pm_raycast_options_init(pm_raycast_options* options) {
  if (!capi::reset_versioned(options)) return;
  const RaycastOptions d;
  options->t_min = d.t_min;
  options->t_max = d.t_max;
  options->threads = d.threads;
}

pm_status pm_raycast_first(const pm_field* field, const double* origins, const double* directions, size_t count,
                           const pm_raycast_options* options, double* out_t, double* out_positions,
                           double* out_normals, int32_t* out_entering, size_t* out_hit_count) {
  return guarded([&] {
    require(field, "field");
    check_rays(origins, directions, count);
    const RaycastOptions o = to_options(options);
    const FirstHits r = cast_first_hits(field->caster, as_vec3(origins), as_vec3(directions), count, o);
    for (size_t i = 0; i < count; ++i) {
      if (out_t) out_t[i] = r.t[i];
      if (out_entering) out_entering[i] = r.entering[i];
    }
    if (out_positions && count) std::memcpy(out_positions, r.positions.data(), count * sizeof(Vec3));
    if (out_normals && count) std::memcpy(out_normals, r.normals.data(), count * sizeof(Vec3));
    if (out_hit_count) *out_hit_count = r.hit_count;
  });
}

pm_status pm_raycast_all(const pm_field* field, const double* origins, const double* directions, size_t count,
                         const pm_raycast_options* options, pm_ray_hits** out_hits) {
  return guarded([&] {
    require(field, "field");
    require(out_hits, "out_hits");
    check_rays(origins, directions, count);
    const RaycastOptions o = to_options(options);
    auto handle = std::make_unique<pm_ray_hits>();
    handle->hits = cast_all_hits(field->caster, as_vec3(origins), as_vec3(directions), count, o);
    *out_hits = handle.release();
  });
}

pm_status pm_raycast_csg(const pm_field* a, const pm_field* b, int32_t op, const double* origins,
                         const double* directions, size_t count, const pm_raycast_options* options,
                         pm_ray_hits** out_hits) {
  return guarded([&] {
    require(a, "a");
    require(b, "b");
    require(out_hits, "out_hits");
    check_rays(origins, directions, count);
    if (op != PM_CSG_UNION && op != PM_CSG_INTERSECTION && op != PM_CSG_DIFFERENCE)
      throw Error(Status::InvalidArgument, "op is " + std::to_string(op) + " (must be PM_CSG_UNION, _INTERSECTION or _DIFFERENCE)");
    const RaycastOptions o = to_options(options);
    const AllHits ha = cast_all_hits(a->caster, as_vec3(origins), as_vec3(directions), count, o);
    const AllHits hb = cast_all_hits(b->caster, as_vec3(origins), as_vec3(directions), count, o);
    auto handle = std::make_unique<pm_ray_hits>();
    AllHits& r = handle->hits;
    r.offsets.assign(count + 1, 0);
    r.starts_inside.assign(count, 0);
    for (size_t i = 0; i < count; ++i) {
      RayHits ra, rb;
      ra.starts_inside = ha.starts_inside[i];
      rb.starts_inside = hb.starts_inside[i];
      ra.hits.assign(ha.hits.begin() + std::ptrdiff_t(ha.offsets[i]), ha.hits.begin() + std::ptrdiff_t(ha.offsets[i + 1]));
      rb.hits.assign(hb.hits.begin() + std::ptrdiff_t(hb.offsets[i]), hb.hits.begin() + std::ptrdiff_t(hb.offsets[i + 1]));
      const RayHits c = csg_hits(ra, rb, static_cast<CsgOp>(op));
      r.starts_inside[i] = c.starts_inside ? 1 : 0;
      r.hits.insert(r.hits.end(), c.hits.begin(), c.hits.end());
      r.offsets[i + 1] = r.hits.size();
    }
    *out_hits = handle.release();
  });
}

pm_status pm_ray_hits_get_counts(const pm_ray_hits* hits, size_t* out_ray_count, size_t* out_hit_count) {
  return guarded([&] {
    require(hits, "hits");
    if (out_ray_count) *out_ray_count = hits->hits.starts_inside.size();
    if (out_hit_count) *out_hit_count = hits->hits.hits.size();
  });
}

pm_status pm_ray_hits_copy_offsets(const pm_ray_hits* hits, uint64_t* out_offsets, size_t capacity) {
  return guarded([&] {
    require(hits, "hits");
    require(out_offsets, "out_offsets");
    const auto& o = hits->hits.offsets;
    if (capacity < o.size())
      throw Error(Status::InvalidArgument, "capacity " + std::to_string(capacity) + " is less than ray_count + 1 = " +
                                               std::to_string(o.size()));
    std::memcpy(out_offsets, o.data(), o.size() * sizeof(uint64_t));
  });
}

pm_status pm_ray_hits_copy_starts_inside(const pm_ray_hits* hits, int32_t* out, size_t capacity) {
  return guarded([&] {
    require(hits, "hits");
    require(out, "out");
    const auto& s = hits->hits.starts_inside;
    if (capacity < s.size())
      throw Error(Status::InvalidArgument, "capacity " + std::to_string(capacity) + " is less than ray_count = " +
                                               std::to_string(s.size()));
    for (size_t i = 0; i < s.size(); ++i) out[i] = s[i];
  });
}

pm_status pm_ray_hits_copy(const pm_ray_hits* hits, double* out_t, double* out_positions, double* out_normals,
                           int32_t* out_entering, size_t capacity) {
  return guarded([&] {
    require(hits, "hits");
    const auto& h = hits->hits.hits;
    if (capacity < h.size())
      throw Error(Status::InvalidArgument, "capacity " + std::to_string(capacity) + " is less than hit_count = " +
                                               std::to_string(h.size()));
    for (size_t i = 0; i < h.size(); ++i) {
      if (out_t) out_t[i] = h[i].t;
      if (out_positions) std::memcpy(out_positions + 3 * i, &h[i].position, sizeof(Vec3));
      if (out_normals) std::memcpy(out_normals + 3 * i, &h[i].normal, sizeof(Vec3));
      if (out_entering) out_entering[i] = h[i].entering ? 1 : 0;
    }
  });
}

void pm_ray_hits_destroy(pm_ray_hits* hits) { delete hits; }

}  // extern "C"
