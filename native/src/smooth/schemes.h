// Internal: the two subdivision back ends behind smooth_mesh().
#pragma once

#include "particlemesh/core/config.h"

#include "core/progress_tracker.h"
#include "particlemesh/smooth/subdivide.h"
#include "smooth/control_mesh.h"

namespace PM_NAMESPACE::detail {

/// The option and size checks of smooth_mesh (Error InvalidArgument / LimitExceeded).
void check_smooth_options(const SmoothOptions& options, size_t triangles);

/// The options' creases in control indices; each must be an edge of the mesh (else
/// Error(InvalidArgument) naming it). Sharpness at least 10 is passed as 10 (infinite).
void resolve_creases(const ControlMesh& control, const SmoothOptions& options,
                     std::vector<std::pair<uint32_t, uint32_t>>* pairs, std::vector<float>* sharpness);

/// Every corner attribute of `mesh` one value per component and triangle corner, finite and
/// within kMaxSmoothAttribute; else Error(InvalidInput) naming it (and the triangle).
void check_corner_attributes(const TriMesh& mesh);

/// `mesh`'s corner attributes through `levels` splits (see TriMesh::corner_attributes),
/// following the control mesh's orientation repair.
std::vector<VertexAttribute> subdivide_corner_attributes(const TriMesh& mesh, const ControlMesh& control, int levels);

/// The last step of smooth_mesh: area-weighted normals where the mesh has none, or where a
/// limit normal vanished (degenerate geometry).
void finish_smooth_normals(TriMesh& mesh);

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
