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
/// `positions` (the input particles; the field's centres when null).
void finish_polygonized(PolygonizeResult& r, const PolygonizeOptions& options, const ParticleField& field,
                        const Vec3* positions, size_t n, ProgressTracker& tracker);

}  // namespace particlemesh::detail
