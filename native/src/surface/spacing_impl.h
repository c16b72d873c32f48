// Internal entry of the spacing estimate, sharing the caller's progress tracker.
#pragma once

#include "core/progress_tracker.h"
#include "particlemesh/surface/spacing.h"

namespace particlemesh::detail {

/// Assumes finite coordinates. Runs in the caller's TBB arena; reports progress in
/// [begin, end) of the overall fraction.
SpacingEstimate estimate_spacing_impl(const Vec3* points, size_t n, ProgressTracker& tracker,
                                      double begin, double end);

}  // namespace particlemesh::detail
