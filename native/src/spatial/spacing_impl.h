// Internal entry of the spacing estimate, sharing the caller's progress tracker.
#pragma once

#include "particlemesh/core/config.h"

#include "core/progress_tracker.h"
#include "particlemesh/spatial/spacing.h"

namespace PM_NAMESPACE::detail {

/// Assumes finite coordinates. Runs in the caller's TBB arena; reports progress in
/// [begin, end) of the overall fraction. With stride > 1 the median is taken over the points
/// whose input index is a multiple of stride, and duplicates are not looked for.
SpacingEstimate estimate_spacing_impl(const Vec3* points, size_t n, ProgressTracker& tracker,
                                      double begin, double end, size_t stride = 1);

}  // namespace particlemesh::detail
