#include "particlemesh/volume/render.h"

#include <algorithm>
#include <cctype>
#include <chrono>
#include <cmath>
#include <numbers>
#include <string>

#include "core/parallel.h"
#include "core/progress_tracker.h"
#include "core/format_number.h"
#include "volume/camera_rays.h"
#include "particlemesh/core/error.h"

namespace PM_NAMESPACE {

namespace {

constexpr double kDeg = std::numbers::pi / 180.0;

uint8_t to_byte(double v) { return uint8_t(std::lround(std::clamp(v, 0.0, 1.0) * 255.0)); }

}  // namespace

namespace detail {

CameraRays::CameraRays(const Camera& c, int W, int H) : eye(c.eye), width(W), height(H) {
  if (W < 1 || H < 1 || W > 16384 || H > 16384)
    throw Error(Status::InvalidArgument, "image size " + std::to_string(W) + " x " + std::to_string(H) +
                                             " is out of range (1..16384 each way)");
  for (int a = 0; a < 3; ++a)
    if (!std::isfinite(c.eye[a]) || !std::isfinite(c.target[a]) || !std::isfinite(c.up[a]))
      throw Error(Status::InvalidArgument, "camera eye, target and up must be finite");
  if (!(c.fov_degrees > 0 && c.fov_degrees < 180))
    throw Error(Status::InvalidArgument, "camera fov is " + detail::format_number(c.fov_degrees) + " degrees (must be in (0, 180))");
  const Vec3 f = c.target - c.eye;
  if (!(norm(f) > 0)) throw Error(Status::InvalidArgument, "camera eye and target coincide");
  forward = normalized(f);
  const Vec3 r = cross(forward, c.up);
  if (!(norm(r) > 1e-9 * norm(c.up)) || !(norm(c.up) > 0))
    throw Error(Status::InvalidArgument, "camera up is zero or parallel to the view direction");
  right = normalized(r);
  up = cross(right, forward);
  tv = std::tan(0.5 * c.fov_degrees * kDeg);
  th = tv * double(W) / double(H);
}

}  // namespace detail

const char* shading_name(Shading shading) {
  switch (shading) {
    case Shading::Lambert: return "lambert";
    case Shading::Normal: return "normal";
  }
  return "unknown";
}

Shading shading_from_name(std::string_view name) {
  std::string lower(name);
  std::transform(lower.begin(), lower.end(), lower.begin(), [](unsigned char c) { return char(std::tolower(c)); });
  if (lower == "lambert") return Shading::Lambert;
  if (lower == "normal") return Shading::Normal;
  throw Error(Status::InvalidArgument, "unknown shading '" + std::string(name) + "' (use lambert or normal)");
}

Camera default_camera(const ParticleField& field, double aspect, const Vec3& up, double fov_degrees) {
  if (!(aspect > 0) || !std::isfinite(aspect)) throw Error(Status::InvalidArgument, "aspect must be > 0");
  if (!(norm(up) > 0) || !is_finite(up)) throw Error(Status::InvalidArgument, "camera up must be a finite non-zero vector");
  // The particles' box grown by 0.6 R: packed particles' surface lies about R / 4 outside the
  // outermost ones, a lone blob's within 0.6 R for thresholds above ~0.2 x its strength.
  // (The supports' box, R all round, would leave most of the image empty.)
  const NeighborGrid& grid = field.grid();
  Vec3 lo = grid.sorted_point(0), hi = lo;
  for (uint32_t k = 0; k < uint32_t(field.size()); ++k) {
    const Vec3& p = grid.sorted_point(k);
    const double pad = 0.6 * field.radius(grid.original_index(k));
    lo = {std::min(lo.x, p.x - pad), std::min(lo.y, p.y - pad), std::min(lo.z, p.z - pad)};
    hi = {std::max(hi.x, p.x + pad), std::max(hi.y, p.y + pad), std::max(hi.z, p.z + pad)};
  }
  Camera c;
  c.target = (lo + hi) * 0.5;
  c.up = up;
  c.fov_degrees = fov_degrees;
  const double radius = 0.5 * norm(hi - lo);
  // A horizontal reference perpendicular to up: the z axis, or -y when up is near z.
  const Vec3 u = normalized(up);
  Vec3 front = std::abs(u.z) < 0.9 ? Vec3{0, 0, 1} : Vec3{0, -1, 0};
  front = normalized(front - u * dot(front, u));
  const Vec3 right = cross(u, front);
  const double el = 25 * kDeg, az = 35 * kDeg;
  const Vec3 dir = (front * std::cos(az) + right * std::sin(az)) * std::cos(el) + u * std::sin(el);
  const double half_v = 0.5 * fov_degrees * kDeg;
  const double half_h = std::atan(std::tan(half_v) * aspect);
  const double dist = radius / std::sin(std::min(half_v, half_h));
  c.eye = c.target + dir * dist;
  return c;
}

RenderResult render(const RayCaster& caster, const RenderOptions& options) {
  const int W = options.width, H = options.height;
  if (W < 1 || H < 1 || W > 16384 || H > 16384)
    throw Error(Status::InvalidArgument, "image size " + std::to_string(W) + " x " + std::to_string(H) +
                                             " is out of range (1..16384 each way)");
  if (options.shading != Shading::Lambert && options.shading != Shading::Normal)
    throw Error(Status::InvalidArgument, "shading is " + std::to_string(int(options.shading)) + " (0 lambert, 1 normal)");
  const auto t0 = std::chrono::steady_clock::now();
  detail::ProgressTracker tracker(options.progress);
  RenderResult r;
  r.camera = options.camera ? *options.camera : default_camera(caster.field(), double(W) / double(H));
  const detail::CameraRays rays(r.camera, W, H);
  // Key light from the camera's upper left (and a little behind it), plus ambient.
  const Vec3 light = normalized(-rays.forward * 1.0 + rays.up * 0.7 - rays.right * 0.5);
  const Vec3 albedo{0.85, 0.70, 0.52};
  const Vec3 background{0.93, 0.94, 0.96};
  r.image.width = W;
  r.image.height = H;
  r.image.rgb.assign(size_t(W) * size_t(H) * 3, 0);
  std::vector<uint8_t> hit_at(size_t(W) * size_t(H), 0);
  // Linear to display (gamma 2.2).
  auto display = [](const Vec3& c, uint8_t* out) {
    out[0] = to_byte(std::pow(c.x, 1.0 / 2.2));
    out[1] = to_byte(std::pow(c.y, 1.0 / 2.2));
    out[2] = to_byte(std::pow(c.z, 1.0 / 2.2));
  };
  uint8_t background_bytes[3];
  display(background, background_bytes);
  tracker.stage("rendering", 0.0, 1.0, uint64_t(H));
  detail::trace_camera(caster, rays, options.threads, tracker, [&](int x, int y, const RayHit* hit) {
    uint8_t* out = r.image.pixel(x, y);
    if (!hit) {
      std::copy(background_bytes, background_bytes + 3, out);
      return;
    }
    hit_at[size_t(y) * size_t(W) + size_t(x)] = 1;
    Vec3 n = hit->normal;
    if (dot(n, rays.direction(x, y)) > 0) n = -n;  // seen from inside: shade the side facing the camera
    if (options.shading == Shading::Normal) {
      const Vec3 c = (hit->normal + Vec3{1, 1, 1}) * 0.5;
      out[0] = to_byte(c.x);
      out[1] = to_byte(c.y);
      out[2] = to_byte(c.z);
      return;
    }
    display(albedo * (0.18 + 0.82 * std::max(0.0, dot(n, light))), out);
  });
  tracker.check();
  for (uint8_t h : hit_at) r.hits += h;
  r.rays = uint64_t(W) * uint64_t(H);
  r.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  tracker.finish();
  return r;
}

Vec3 camera_ray_direction(const Camera& camera, int width, int height, int x, int y) {
  const detail::CameraRays rays(camera, width, height);
  if (x < 0 || y < 0 || x >= width || y >= height)
    throw Error(Status::InvalidArgument, "pixel (" + std::to_string(x) + ", " + std::to_string(y) +
                                             ") is outside the " + std::to_string(width) + " x " +
                                             std::to_string(height) + " image");
  return rays.direction(x, y);
}

FirstHits cast_camera_rays(const RayCaster& caster, const Camera& camera, int width, int height, int threads,
                           const ProgressCallback& progress) {
  const detail::CameraRays rays(camera, width, height);
  detail::ProgressTracker tracker(progress);
  const size_t n = size_t(width) * size_t(height);
  FirstHits r;
  r.t.assign(n, std::numeric_limits<double>::infinity());
  r.positions.assign(n, Vec3{});
  r.normals.assign(n, Vec3{});
  r.entering.assign(n, 0);
  tracker.stage("ray casting", 0.0, 1.0, uint64_t(height));
  detail::trace_camera(caster, rays, threads, tracker, [&](int x, int y, const RayHit* hit) {
    if (!hit) return;
    const size_t i = size_t(y) * size_t(width) + size_t(x);
    r.t[i] = hit->t;
    r.positions[i] = hit->position;
    r.normals[i] = hit->normal;
    r.entering[i] = hit->entering ? 1 : 0;
  });
  tracker.check();
  for (size_t i = 0; i < n; ++i) r.hit_count += r.t[i] < std::numeric_limits<double>::infinity();
  tracker.finish();
  return r;
}

}  // namespace particlemesh
