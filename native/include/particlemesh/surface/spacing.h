// The particle spacing r0 that the triangulation's edge limit is measured in.
#pragma once

#include <cstddef>

#include "particlemesh/core/export.h"
#include "particlemesh/core/progress.h"
#include "particlemesh/core/vec3.h"

namespace particlemesh {

struct SpacingEstimate {
  double spacing = 0;          ///< median nearest-neighbour distance over distinct points
  size_t distinct_points = 0;  ///< points left after exact duplicates are set aside
  size_t duplicate_points = 0; ///< points with exactly the coordinates of a lower-index point
};

/// Median nearest-neighbour distance of the distinct points: exact (not sampled), so it does
/// not depend on the order of the points or the thread count. O(N) expected on evenly
/// spaced points (a uniform grid sized from the data).
/// @throws Error(InvalidInput) if fewer than two distinct points or a non-finite coordinate.
PM_EXPORT SpacingEstimate estimate_spacing(const Vec3* points, size_t n, int threads = 0,
                                           const ProgressCallback& progress = {});

}  // namespace particlemesh
