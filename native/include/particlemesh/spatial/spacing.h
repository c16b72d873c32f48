// The particle spacing r0 that the triangulation's edge limit is measured in.
#pragma once

#include "particlemesh/core/config.h"

#include <cstddef>

#include "particlemesh/core/export.h"
#include "particlemesh/core/progress.h"
#include "particlemesh/core/vec3.h"

namespace PM_NAMESPACE {

struct SpacingEstimate {
  double spacing = 0;          ///< median nearest-neighbour distance over distinct points
  size_t distinct_points = 0;  ///< points left after exact duplicates are set aside
  size_t duplicate_points = 0; ///< points with exactly the coordinates of a lower-index point
  /// Near copies, where the cloud is twinned: at least a quarter of its distinct points have
  /// a neighbour ten times nearer than every other (an airborne scanner's first and last
  /// returns off hard ground, a cloud merged with itself shifted by a hair). `spacing` is then
  /// the copies' offset, not the sampling's; reconstruct_surface sets them aside (each pair is
  /// one particle, its lower index) and measures the rest. 0 otherwise (as by chance about 1 %
  /// of particles dropped at random on a surface have such a neighbour).
  size_t near_duplicates = 0;
  /// The median nearest-neighbour distance with the near copies set aside: reconstruct_surface's
  /// r0 (`spacing` where near_duplicates is 0). Only estimate_spacing fills it; 0 elsewhere.
  double spacing_apart = 0;
};

/// Median nearest-neighbour distance of the distinct points: exact (not sampled), so it does
/// not depend on the order of the points or the thread count. O(N) expected on evenly
/// spaced points (a uniform grid sized from the data).
/// @throws Error(InvalidInput) if fewer than two distinct points or a non-finite coordinate.
PM_EXPORT SpacingEstimate estimate_spacing(const Vec3* points, size_t n, int threads = 0,
                                           const ProgressCallback& progress = {});

/// The same median over an evenly strided sample of at most max_samples points (input indices
/// 0, k, 2k, ...; each one's nearest neighbour is searched among all the points), for quick
/// previews of big clouds: within about 1 % of estimate_spacing on evenly spaced particles,
/// at a fraction of its cost. Duplicates are not looked for
/// (duplicate_points is 0). max_samples >= n gives the exact estimate.
/// @throws Error(InvalidArgument) if max_samples is 0; as estimate_spacing otherwise.
PM_EXPORT SpacingEstimate estimate_spacing_sampled(const Vec3* points, size_t n, size_t max_samples,
                                                   int threads = 0);

}  // namespace particlemesh
