// Internal: the two subdivision back ends behind smooth_mesh().
#pragma once

#include "particlemesh/core/config.h"

#include "core/progress_tracker.h"
#include "particlemesh/smooth/subdivide.h"
#include "smooth/control_mesh.h"

namespace PM_NAMESPACE::detail {

/// Loop through OpenSubdiv (Far::TopologyRefiner + PrimvarRefiner). Fills out.mesh
/// positions, triangles and attributes; normals too when options.limit (limit normals).
/// Creases are in control indices already.
void loop_subdivide(const ControlMesh& control, const SmoothOptions& options,
                    const std::vector<std::pair<uint32_t, uint32_t>>& crease_pairs,
                    const std::vector<float>& crease_sharpness, ProgressTracker& progress,
                    SmoothResult& out);

/// Modified butterfly through OpenMesh (ModifiedButterflyT). Fills out.mesh positions,
/// triangles and attributes (attributes run through the same subdivider on copies of the
/// connectivity, three channels per copy).
void butterfly_subdivide(const ControlMesh& control, const SmoothOptions& options,
                         ProgressTracker& progress, SmoothResult& out);

}  // namespace particlemesh::detail
