// Internal: the primary rays of a pinhole camera (render.h), one through the centre of each
// pixel, and their first hits traced tile by tile (ray_tiles.cpp).
#pragma once

#include "particlemesh/core/config.h"

#include <functional>

#include "core/progress_tracker.h"
#include "particlemesh/volume/render.h"

namespace PM_NAMESPACE::detail {

struct CameraRays {
  /// @throws Error(InvalidArgument) a degenerate camera or an image size out of range.
  CameraRays(const Camera& camera, int width, int height);
  Vec3 eye, forward, right, up;  // forward, right, up orthonormal; right = forward x up
  double tv = 0, th = 0;         // tangents of the half field of view, vertical and horizontal
  int width = 0, height = 0;
  /// Through the centre of pixel (x, y), x to the right, y down; not unit length.
  Vec3 direction(int x, int y) const {
    const double py = 1.0 - 2.0 * (double(y) + 0.5) / double(height);
    const double px = 2.0 * (double(x) + 0.5) / double(width) - 1.0;
    return forward + right * (px * th) + up * (py * tv);
  }
};

/// Calls pixel(x, y, hit) for every pixel with the first hit of its ray (nullptr for none),
/// from `threads` threads (0: all cores), each pixel once; which thread calls which pixel
/// depends on the thread count, the hits do not. Ticks `tracker` once per image row and
/// stops early (leaving pixels uncalled) when it is cancelled.
void trace_camera(const RayCaster& caster, const CameraRays& rays, int threads, ProgressTracker& tracker,
                  const std::function<void(int x, int y, const RayHit* hit)>& pixel);

}  // namespace particlemesh::detail
