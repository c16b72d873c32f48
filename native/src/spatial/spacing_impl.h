// Internal entry of the spacing estimate, sharing the caller's progress tracker.
#pragma once

#include "particlemesh/core/config.h"

#include <cstdint>
#include <vector>

#include "core/progress_tracker.h"
#include "particlemesh/spatial/spacing.h"

namespace PM_NAMESPACE::detail {

/// A distinct point is a near copy (a twin) of its nearest neighbour when that is at most this
/// fraction as far as every other distinct point: an airborne scanner's first and last return
/// off hard ground, a cloud merged with a copy of itself shifted by a hair. On an even
/// sampling no point is; where points lie at random in a surface, about 1 % are (the squared
/// ratio of the two nearest distances is uniform there), in a volume 0.1 %.
constexpr double kTwinRatio = 0.1;
/// A cloud is twinned when at least this fraction of its distinct points are twins: its
/// median nearest-neighbour distance is then the twins' offset, not its sampling.
constexpr double kTwinnedFraction = 0.25;

/// Assumes finite coordinates. Runs in the caller's TBB arena; reports progress in
/// [begin, end) of the overall fraction. With stride > 1 the median is taken over the points
/// whose input index is a multiple of stride, and duplicates are not looked for.
/// `twin_of` (stride 1 only), when given: left empty unless the cloud is twinned
/// (kTwinnedFraction, SpacingEstimate::near_duplicates); then, per input index, the lowest
/// input index of the group of points it belongs to: linked by twins (a point and its nearest
/// distinct neighbour, kTwinRatio) and exact copies. The point's own index where it is alone.
SpacingEstimate estimate_spacing_impl(const Vec3* points, size_t n, ProgressTracker& tracker,
                                      double begin, double end, size_t stride = 1,
                                      std::vector<uint32_t>* twin_of = nullptr);

}  // namespace particlemesh::detail
