// Volume-keeping smoothing of a triangle mesh: Taubin's lambda|mu filter (Taubin, "A signal
// processing approach to fair surface design", SIGGRAPH 1995).
//
// Plain Laplacian smoothing moves every vertex toward the mean of its neighbours and so
// shrinks a closed surface a little more at every step. Taubin alternates a shrinking step
// (factor lambda > 0) with an inflating one (factor mu < -lambda): a low-pass filter that takes
// out the bumps a few edges across and keeps the shape and, for smooth closed surfaces, the
// enclosed volume (to a fraction of a percent over tens of iterations). One iteration is
//
//     x_i += lambda L(x_i);   then   x_i += mu L(x_i),     L(x_i) = mean of x_j over the
//                                                           edge neighbours j of i, minus x_i
//
// (the uniform "umbrella" weights; each step is a Jacobi step: every vertex moves from the
// previous positions). The pass band is k_PB = 1/lambda + 1/mu (0.11 at the defaults).
// Connectivity is untouched, so a closed manifold stays closed and manifold; vertices on a
// boundary are smoothed along their neighbours like the others. Afterwards every vertex used
// by a triangle gets the area-weighted mean of its triangles' unit normals.
//
// Written here because OpenMesh's smoothers (JacobiLaplaceSmootherT) take full Laplacian
// steps with no signed step size, which is exactly the shrinking filter Taubin's pair avoids.
// Deterministic: every sum runs over a vertex's neighbours in increasing index.
#pragma once

#include "particlemesh/core/config.h"

#include <cstdint>

#include "particlemesh/core/export.h"
#include "particlemesh/mesh/tri_mesh.h"

namespace PM_NAMESPACE {

struct TaubinOptions {
  /// lambda|mu pairs of steps; 0 leaves the mesh as it is. At most 10000.
  int32_t iterations = 10;
  /// The shrinking step, in (0, 1].
  double lambda = 0.5;
  /// The inflating step: mu < -lambda, at least -1.
  double mu = -0.53;
  /// Worker threads, 0 = all cores. The output does not depend on it.
  int32_t threads = 0;
};

/// @throws Error(InvalidArgument) naming the option out of range.
PM_EXPORT void validate_taubin(const TaubinOptions& options);

/// Smooth `mesh` in place (see the top of this file). Cost: O(iterations x edges).
/// @throws Error(InvalidArgument) an option out of range (validate_taubin), a triangle index
///         >= the vertex count or a triangle repeating a vertex (mesh_edges).
PM_EXPORT void taubin_smooth(TriMesh& mesh, const TaubinOptions& options = {});

}  // namespace particlemesh
