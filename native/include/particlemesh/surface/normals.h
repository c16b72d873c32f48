// Per-particle normals for clouds that come without them.
#pragma once

#include <vector>

#include "particlemesh/core/export.h"
#include "particlemesh/core/progress.h"
#include "particlemesh/mesh/point_cloud.h"

namespace particlemesh {

struct NormalOptions {
  /// Neighbourhood radius in world units for the local plane fit; 0 = 2 x the estimated
  /// spacing (the seed's default edge limit).
  double radius = 0;
  int threads = 0;
  ProgressCallback progress;
};

/// Unit normals by local PCA (the direction of least variance of the neighbours within
/// `radius`), oriented consistently as Hoppe et al. (1992) do: propagated along a minimum
/// spanning tree of the neighbour graph whose edge cost is 1 - |n_i . n_j| plus how far the
/// edge leaves the tangent planes (so the tree runs along a sheet rather than across a gap
/// to a nearby one). Each tree starts at its highest point, whose normal is turned to +z, so
/// closed surfaces come out facing outward. Points with fewer than two neighbours get (0,0,0).
/// Deterministic; O(N log N).
PM_EXPORT std::vector<Vec3> estimate_normals(const PointCloud& cloud, const NormalOptions& options = {});

}  // namespace particlemesh
