// Internal: OpenSubdiv's Loop refinement of a control mesh, shared by smooth_mesh() and the
// refine-once Smoother (smoother.h).
#pragma once

#include <cstdint>
#include <memory>
#include <utility>
#include <vector>

#include <opensubdiv/far/topologyRefiner.h>

#include "particlemesh/smooth/subdivide.h"
#include "smooth/control_mesh.h"

namespace PM_NAMESPACE::detail {

/// Far::TopologyRefiner for the control mesh under Loop's rules (boundary rule, creases and
/// crease method from the options), refined uniformly to options.levels; with
/// `full_last_level` the last level also gets its edges and incidences (OpenSubdiv's limit
/// masks need them).
std::unique_ptr<OpenSubdiv::Far::TopologyRefiner> loop_refiner(const ControlMesh& control, const SmoothOptions& options,
                                                               const std::vector<std::pair<uint32_t, uint32_t>>& crease_pairs,
                                                               const std::vector<float>& crease_sharpness,
                                                               bool full_last_level);

/// Whether the limit is taken by loop_limit.h (a closed surface without creases) rather than
/// by OpenSubdiv's PrimvarRefiner::Limit.
inline bool own_loop_limit(const ControlMesh& control, const SmoothOptions& options, size_t creases) {
  return options.limit && control.boundary_edges == 0 && creases == 0;
}

}  // namespace particlemesh::detail
