// Internal: what polygonize does to its mesh after marching cubes, on request: drop the small
// pieces, then smooth (Taubin).
#pragma once

#include "particlemesh/core/config.h"

#include "core/progress_tracker.h"
#include "particlemesh/volume/polygonize.h"

namespace PM_NAMESPACE::detail {

/// Check min_component_volume, min_component_particles and surface_smoothing.
/// @throws Error(InvalidArgument) naming the option.
void validate_finishing(const PolygonizeOptions& options);

/// Apply the finishing options to r.mesh and fill their statistics. The particle spacing for
/// min_component_particles is the field's when it estimated one, else it is estimated from
/// `positions` (the input particles; the field's centres when null). `attributes` (the
/// particles' channels, in input order; may be null) are interpolated onto the vertices
/// first (interpolate_attributes), so that dropped pieces take theirs with them.
void finish_polygonized(PolygonizeResult& r, const PolygonizeOptions& options, const ParticleField& field,
                        const Vec3* positions, size_t n, ProgressTracker& tracker,
                        const std::vector<VertexAttribute>* attributes = nullptr);

/// Each vertex x of `mesh` gets, for each attribute, the particles' values weighted by their
/// normalised kernel weights at x: a(x) = sum_i w_i a_i / sum_i w_i with w_i = |strength_i|
/// g(s_i(x)), s_i the particle's scaled squared distance (its sphere's, or its ellipsoid's
/// with anisotropic kernels): the same weights that sum to F(x) = T there, so a particle
/// counts in proportion to its share of the surface at x (Shepard interpolation with the
/// field's kernel). Summed in the field's fixed particle order (for_each_contributor): the
/// values do not depend on the thread count, and the tiles of a cloud get the whole cloud's
/// values bit for bit. A vertex no kernel reaches (none on a polygonized surface) gets 0.
void interpolate_attributes(TriMesh& mesh, const ParticleField& field, const std::vector<VertexAttribute>& attributes);

}  // namespace particlemesh::detail
