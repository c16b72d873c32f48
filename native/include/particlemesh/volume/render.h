// A renderer of the exact iso-surface of volume particles: one primary ray per pixel through
// the ray caster (raycast.h), the first hit shaded by its normal (the field gradient). What
// it shows is the true surface F = T, not a mesh: there are no facets to see.
#pragma once

#include "particlemesh/core/config.h"

#include <cstdint>
#include <optional>

#include "particlemesh/core/export.h"
#include "particlemesh/core/progress.h"
#include "particlemesh/core/vec3.h"
#include "particlemesh/io/png.h"
#include "particlemesh/volume/raycast.h"

namespace PM_NAMESPACE {

enum class Shading : int32_t {
  Lambert = 0,  ///< a clay colour lit by a key light from the camera's upper left, plus ambient
  Normal = 1,   ///< the world-space normal as colour: (n + 1) / 2
};

/// "lambert", "normal"; and back (case-insensitive). @throws Error(InvalidArgument).
PM_EXPORT const char* shading_name(Shading shading);
PM_EXPORT Shading shading_from_name(std::string_view name);

/// A pinhole camera.
struct Camera {
  Vec3 eye;                      ///< where the camera is
  Vec3 target;                   ///< the point at the centre of the image
  Vec3 up{0, 1, 0};              ///< the image's up direction (need not be orthogonal to the view)
  double fov_degrees = 40;       ///< vertical field of view, in (0, 180)
};

/// The default camera: looks at the centre of the particles' box grown by 0.6 R (which holds
/// the surface of packed particles, and of a lone blob unless T is below ~0.2 x its
/// strength) from above, in front and to the right (25 degrees of elevation, 35 of azimuth
/// around `up`), from the distance at which the sphere around that box just fits the image
/// (both ways, for the given width / height aspect).
PM_EXPORT Camera default_camera(const ParticleField& field, double aspect, const Vec3& up = {0, 1, 0},
                                double fov_degrees = 40);

struct RenderOptions {
  int width = 640;   ///< pixels
  int height = 480;  ///< pixels
  std::optional<Camera> camera;  ///< none: default_camera(field, width / height)
  Shading shading = Shading::Lambert;
  int threads = 0;   ///< 0 = all cores; the image does not depend on it
  ProgressCallback progress;
};

struct RenderResult {
  Image image;
  Camera camera;          ///< the camera used
  uint64_t rays = 0;      ///< width x height
  uint64_t hits = 0;      ///< pixels showing the surface
  double seconds = 0;     ///< ray casting and shading (wall clock)
};

/// The direction (not unit length) of the camera's primary ray through the centre of pixel
/// (x, y) of a width x height image, x to the right and y down: the ray render() casts from
/// camera.eye for that pixel. @throws Error(InvalidArgument) a degenerate camera, a size out
/// of 1..16384 or a pixel outside the image.
PM_EXPORT Vec3 camera_ray_direction(const Camera& camera, int width, int height, int x, int y);

/// First hits of the camera's primary rays, pixel i = y * width + x (t in units of
/// camera_ray_direction's length): RayCaster::first_hit of each ray, bit for bit, but traced
/// in tiles of 12 x 12 pixels that share one walk of the hierarchy (render() uses it). threads:
/// 0 = all cores; the result does not depend on it. @throws as camera_ray_direction;
/// Error(Cancelled) from the progress callback.
PM_EXPORT FirstHits cast_camera_rays(const RayCaster& caster, const Camera& camera, int width, int height,
                                     int threads = 0, const ProgressCallback& progress = {});

/// Render the iso-surface of the caster's field. Cost: one first-hit query per pixel (traced
/// in tiles, as cast_camera_rays).
/// @throws Error(InvalidArgument) a size out of 1..16384, a degenerate camera (eye at the
///         target, up parallel to the view, fov out of range, non-finite values);
///         Error(Cancelled) from the progress callback.
PM_EXPORT RenderResult render(const RayCaster& caster, const RenderOptions& options = {});

}  // namespace particlemesh
