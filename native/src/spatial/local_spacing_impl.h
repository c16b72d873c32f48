// Internal entry of the local spacing estimate, sharing the caller's progress tracker.
#pragma once

#include "particlemesh/core/config.h"

#include <vector>

#include "core/progress_tracker.h"
#include "particlemesh/spatial/local_spacing.h"

namespace PM_NAMESPACE::detail {

/// The neighbours each point's local spacing is taken over.
constexpr int kLocalSpacingNeighbors = 16;
/// On an even (Poisson-disk) surface sampling whose median nearest-neighbour distance is r,
/// the third nearest of the six 60-degree sectors' nearest neighbours around a point is about
/// kSectorReach x r away.
constexpr double kSectorReach = 1.22;
/// A neighbour more than this times as far as the one before ends a point's neighbourhood.
constexpr double kGap = 2.0;
/// The sector reaches are smoothed by this quantile over each point's neighbourhood ...
constexpr double kSmoothQuantile = 0.9;
/// ... divided by this, the quantile's bias on an even (Poisson-disk) sampling, so that its
/// local spacing is its median nearest-neighbour distance.
constexpr double kSmoothBias = 1.16;
/// Local spacings within this fraction of the cloud's r0 are taken as r0 (see triangulate.cpp).
constexpr double kSpacingBand = 0.15;
/// A mesh's local spacings are held to at most this many times its r0 (the median nearest-
/// neighbour distance): sparser than that, samples are too far apart to be one surface at the
/// cloud's scale.
constexpr double kMaxLocalSpacing = 3.0;
/// Neighbours spread along a line when the second variance of their plane fit is below this
/// fraction of the first (a half disk, at an edge of the surface: about 0.28).
constexpr double kElongated = 0.05;

/// A triangle with an angle over this many degrees is flat: its corners nearly in line (the
/// surface's growth takes such triangles last; see surface/candidates.h).
constexpr double kFlatAngle = 150.0;

/// Per input point (see estimate_local_spacing); r0 = the cloud's median nearest-neighbour
/// distance (sets the grid). Assumes finite coordinates; runs in the caller's TBB arena.
std::vector<double> local_spacing_impl(const Vec3* points, size_t n, double r0, ProgressTracker& tracker,
                                       double begin, double end);

}  // namespace particlemesh::detail
