// Internal: summing anisotropic kernels into a block of polygonization samples.
#pragma once

#include "particlemesh/core/config.h"

#include "particlemesh/volume/field.h"

namespace PM_NAMESPACE::detail {

/// Nodes per block edge of the polygonizer's sparse grid.
inline constexpr int kSampleBlock = 8;

/// out[x + 8 (y + 8 z)] = F at first_node + h (x, y, z), x, y, z in [0, 8), as float, for a
/// field with anisotropic kernels. The particles are summed in grid order (a fixed order:
/// the samples do not depend on the thread count).
void sample_block_anisotropic(const ParticleField& field, const Vec3& first_node, double h, float* out);

/// Does the bounding box of some kernel's ellipsoid meet the box [lo, hi]? (A superset of
/// "some support reaches a point of the box".)
bool anisotropic_support_meets_box(const ParticleField& field, const Vec3& lo, const Vec3& hi);

}  // namespace particlemesh::detail
