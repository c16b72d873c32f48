// Internal: summing spherical kernels into a block of polygonization samples (the
// anisotropic counterpart is anisotropic_sampling.h).
#pragma once

#include "particlemesh/volume/field.h"

namespace PM_NAMESPACE::detail {

/// out[x + 8 (y + 8 z)] = F at first_node + h (x, y, z), x, y, z in [0, kSampleBlock), as
/// float, for a field with spherical kernels. The particles are summed in grid order (a fixed
/// order: the samples do not depend on the thread count).
void sample_block_spherical(const ParticleField& field, const Vec3& first_node, double h, float* out);

}  // namespace particlemesh::detail
