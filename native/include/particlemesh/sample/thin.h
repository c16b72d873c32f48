// Thinning a particle set to a coarser, still even one (a preview of a big system).
#pragma once

#include "particlemesh/core/config.h"

#include <cstddef>
#include <cstdint>
#include <vector>

#include "particlemesh/core/export.h"
#include "particlemesh/core/vec3.h"
#include "particlemesh/mesh/point_cloud.h"

namespace PM_NAMESPACE {

/// Indices (ascending) of a subset of the points in which no two are closer than
/// `min_distance`, and every dropped point lies within `min_distance` of a kept one: a
/// maximal Poisson-disk subset, so evenly spaced particles stay evenly spaced, at a spacing
/// between min_distance and about twice it.
///
/// Points are taken greedily in input order (a point is kept unless a kept point of lower
/// index is too close): the result depends on the points alone, not on any thread count, and
/// a particle keeps its place from frame to frame when the particles move little.
/// @throws Error(InvalidArgument) if min_distance is not a positive finite number or points
///         is null with n > 0; Error(InvalidInput) on a non-finite coordinate;
///         Error(LimitExceeded) if min_distance is so small against the extent that the grid
///         would span more than 2^21 cells along an axis.
PM_EXPORT std::vector<uint32_t> thin_points(const Vec3* points, size_t n, double min_distance);

/// The same with a distance per point: point i is kept unless a kept point of lower index lies
/// closer than min_distance[i] (an unevenly sampled cloud thinned by a factor of each point's
/// local spacing, estimate_local_spacing, stays as uneven as it was, only coarser).
/// @throws as above, and Error(InvalidArgument) if min_distance does not hold n values.
PM_EXPORT std::vector<uint32_t> thin_points(const Vec3* points, size_t n, const std::vector<double>& min_distance);

/// The cloud's points at thin_points' indices, with their normals and attributes.
PM_EXPORT PointCloud thin_cloud(const PointCloud& cloud, double min_distance);
PM_EXPORT PointCloud thin_cloud(const PointCloud& cloud, const std::vector<double>& min_distance);

}  // namespace particlemesh
