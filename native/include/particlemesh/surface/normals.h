// Per-particle normals for clouds that come without them.
#pragma once

#include "particlemesh/core/config.h"

#include <vector>

#include "particlemesh/core/export.h"
#include "particlemesh/core/progress.h"
#include "particlemesh/mesh/point_cloud.h"

namespace PM_NAMESPACE {

struct NormalOptions {
  /// Neighbourhood radius in world units for the local plane fit; 0 = 2 x the estimated
  /// spacing (Tonnesen's default edge limit).
  double radius = 0;
  int threads = 0;
  ProgressCallback progress;
};

/// Unit normals by a robust local plane fit: among the planes of the raw triangles (edge
/// limit L = radius) at a point, the one with the most neighbours close to it, refined by a
/// PCA of those neighbours, so that a second sheet passing within the radius (a fold, a thin
/// part, a nearby surface) does not tilt the normal. A plane with neighbours well out on both
/// sides cuts across the surface (the plane of one ring of samples around a thin part): it
/// gives way to the best plane whose neighbours off it lie on one side, when that one is
/// nearer the neighbourhood's plain PCA normal. Oriented consistently as Hoppe et al.
/// (1992) do, along a minimum spanning tree of the neighbour graph, with signed edges: an edge
/// in the tangent planes keeps the orientation, an edge across a gap between two sheets
/// reverses it (outward normals of a closed surface face each other across any gap). Each
/// tree starts at its highest point, turned to +z, so closed surfaces face outward. Points with
/// fewer than two neighbours get (0,0,0). Deterministic; O(N log N).
PM_EXPORT std::vector<Vec3> estimate_normals(const PointCloud& cloud, const NormalOptions& options = {});

}  // namespace particlemesh
