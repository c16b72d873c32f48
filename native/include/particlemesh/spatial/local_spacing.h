// Each particle's own spacing, from its neighbourhood: real scans are sampled unevenly (a
// depth camera's samples spread with the distance; a turntable scan is denser where the
// surface faces the sensor), so one spacing for the whole cloud is too short in some places
// and too long in others.
#pragma once

#include <cstddef>
#include <vector>

#include "particlemesh/core/export.h"
#include "particlemesh/core/progress.h"
#include "particlemesh/core/vec3.h"

namespace particlemesh {

struct LocalSpacing {
  /// Per input point: the spacing of the sampling around it (see estimate_local_spacing).
  /// Exact duplicates get their first copy's.
  std::vector<double> spacing;
  /// The median nearest-neighbour distance of the distinct points (what estimate_spacing
  /// returns): the cloud's typical spacing r0.
  double median_nn = 0;
};

/// The local spacing of every point: the larger of
///  - the median of the nearest-neighbour distances of the point and its 16 nearest
///    neighbours (on an even sampling: r0 there; unaffected by an opening or an edge nearby,
///    where a point has neighbours on one side only), and
///  - the spacing an even sampling of the density around the point would have, from the
///    distance to its 16th nearest neighbour (larger on irregular samplings, whose gaps are
///    wider than their median nearest-neighbour distance suggests),
/// then smoothed: the median of these over the point and its 16 nearest neighbours, so that
/// the spacing varies gradually over the cloud. Deterministic and linear in the points for
/// surface samplings (a uniform grid); O(N) memory.
/// @throws Error(InvalidInput) if fewer than two distinct points or a non-finite coordinate.
PM_EXPORT LocalSpacing estimate_local_spacing(const Vec3* points, size_t n, int threads = 0,
                                              const ProgressCallback& progress = {});

}  // namespace particlemesh
