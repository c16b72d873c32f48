// The OpenVDB peer of the polygonize benchmark, behind a plain interface so that only its
// own translation unit includes (and compiles) OpenVDB.
#pragma once

#include <cstdint>
#include <vector>

#include "particlemesh/core/vec3.h"

namespace peer {

struct VdbResult {
  double seconds = 0;  ///< ParticlesToLevelSet (rasterize + finalize) + volumeToMesh
  uint64_t vertices = 0;
  uint64_t triangles = 0;  ///< triangles + 2 x quads
};

/// The same pipeline's mesh: vertices (x y z floats) and triangles (quads split in two).
struct VdbMesh {
  double seconds = 0;  ///< ParticlesToLevelSet + volumeToMesh
  std::vector<float> points;
  std::vector<uint32_t> triangles;
};

/// Whether the benchmark was built with OpenVDB.
bool openvdb_available();

/// Every particle a sphere of `sphere_radius` rasterised into a narrow-band level set of
/// voxel size `voxel` (half width 3 voxels), then meshed at iso-value 0 with adaptivity 0.
VdbResult openvdb_particles_to_mesh(const std::vector<particlemesh::Vec3>& positions, double sphere_radius,
                                    double voxel);
VdbMesh openvdb_particles_mesh(const std::vector<particlemesh::Vec3>& positions, double sphere_radius, double voxel);

}  // namespace peer
