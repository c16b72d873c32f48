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
#include "volume/ray_cancel.h"
#include "particlemesh/core/error.h"

namespace PM_NAMESPACE {

namespace {

constexpr double kDeg = std::numbers::pi / 180.0;

struct Frame {
  Vec3 forward, right, up;  // orthonormal; right = forward x up
};

Frame camera_frame(const Camera& c) {
  for (int a = 0; a < 3; ++a)
    if (!std::isfinite(c.eye[a]) || !std::isfinite(c.target[a]) || !std::isfinite(c.up[a]))
      throw Error(Status::InvalidArgument, "camera eye, target and up must be finite");
  if (!(c.fov_degrees > 0 && c.fov_degrees < 180))
    throw Error(Status::InvalidArgument, "camera fov is " + detail::format_number(c.fov_degrees) + " degrees (must be in (0, 180))");
  const Vec3 f = c.target - c.eye;
  if (!(norm(f) > 0)) throw Error(Status::InvalidArgument, "camera eye and target coincide");
  Frame fr;
  fr.forward = normalized(f);
  const Vec3 r = cross(fr.forward, c.up);
  if (!(norm(r) > 1e-9 * norm(c.up)) || !(norm(c.up) > 0))
    throw Error(Status::InvalidArgument, "camera up is zero or parallel to the view direction");
  fr.right = normalized(r);
  fr.up = cross(fr.right, fr.forward);
  return fr;
}

uint8_t to_byte(double v) { return uint8_t(std::lround(std::clamp(v, 0.0, 1.0) * 255.0)); }

}  // namespace

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
  const Frame fr = camera_frame(r.camera);
  const double tv = std::tan(0.5 * r.camera.fov_degrees * kDeg);
  const double th = tv * double(W) / double(H);
  // Key light from the camera's upper left (and a little behind it), plus ambient.
  const Vec3 light = normalized(-fr.forward * 1.0 + fr.up * 0.7 - fr.right * 0.5);
  const Vec3 albedo{0.85, 0.70, 0.52};
  const Vec3 background{0.93, 0.94, 0.96};
  r.image.width = W;
  r.image.height = H;
  r.image.rgb.assign(size_t(W) * size_t(H) * 3, 0);
  std::vector<uint32_t> row_hits(size_t(H), 0);
  tracker.stage("rendering", 0.0, 1.0, uint64_t(H));
  detail::with_threads(options.threads, [&] {
    detail::parallel_blocks(size_t(H), 1, [&](size_t y0, size_t y1) {
      const detail::RayCancelScope scope(&tracker);  // a long ray checks it too
      for (size_t y = y0; y < y1; ++y) {
        if (tracker.cancelled()) return;
        const double py = 1.0 - 2.0 * (double(y) + 0.5) / double(H);
        for (int x = 0; x < W; ++x) {
          // Every pixel: with a huge radius a row of rays takes seconds.
          if (tracker.cancelled()) return;
          tracker.tick(0);
          const double px = 2.0 * (double(x) + 0.5) / double(W) - 1.0;
          const Vec3 dir = fr.forward + fr.right * (px * th) + fr.up * (py * tv);
          const auto hit = caster.first_hit(r.camera.eye, dir);
          uint8_t* out = r.image.pixel(x, int(y));
          Vec3 color = background;
          if (hit) {
            ++row_hits[y];
            Vec3 n = hit->normal;
            if (dot(n, dir) > 0) n = -n;  // seen from inside: shade the side facing the camera
            if (options.shading == Shading::Normal) {
              const Vec3 c = (hit->normal + Vec3{1, 1, 1}) * 0.5;
              out[0] = to_byte(c.x);
              out[1] = to_byte(c.y);
              out[2] = to_byte(c.z);
              continue;
            }
            const double shade = 0.18 + 0.82 * std::max(0.0, dot(n, light));
            color = albedo * shade;
          }
          // Linear to display (gamma 2.2).
          out[0] = to_byte(std::pow(color.x, 1.0 / 2.2));
          out[1] = to_byte(std::pow(color.y, 1.0 / 2.2));
          out[2] = to_byte(std::pow(color.z, 1.0 / 2.2));
        }
        tracker.tick();
      }
    });
  });
  tracker.check();
  for (uint32_t h : row_hits) r.hits += h;
  r.rays = uint64_t(W) * uint64_t(H);
  r.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  tracker.finish();
  return r;
}

}  // namespace particlemesh
