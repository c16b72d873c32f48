// The particles' attributes at given points, interpolated exactly as polygonize interpolates
// them at its vertices: for a caller that meshes first and asks for the attributes later
// (a viewport that shows a new frame's geometry at once and its channels once it rests).
#pragma once

#include "particlemesh/core/config.h"

#include <cstddef>
#include <vector>

#include "particlemesh/core/export.h"
#include "particlemesh/core/vec3.h"
#include "particlemesh/mesh/point_cloud.h"
#include "particlemesh/volume/field.h"
#include "particlemesh/volume/polygonize.h"

namespace PM_NAMESPACE {

/// The cloud's attributes at `points`: one VertexAttribute per cloud attribute (same name,
/// components and order), `count` values each, a(x) = sum_i w_i a_i / sum_i w_i with
/// w_i = |strength_i| g(s_i(x)) summed in the field's particle order (0 where no kernel
/// reaches x). The field is built from `cloud` and the field options of `options` (kernel,
/// radius, threshold, radii, strengths, anisotropy, domain_min, domain_max_radius) as
/// polygonize(cloud, options) builds it, and the sums are polygonize's own: given the
/// vertices polygonize placed, the values are bit for bit those it gave them. (Its vertices
/// before surface_smoothing: the attributes are taken where a vertex is placed, a vertex
/// collapse_edges merged where it ends up; dropping small pieces moves no vertex.) The other options but `threads` and `progress` are not
/// used. The result does not depend on the thread count. Cost: building the field (a
/// spacing estimate when the radius is the default) and one neighbour query per point.
/// @throws Error(InvalidInput) a non-finite point coordinate (naming the point), an
///         attribute whose values do not match the particles, and as polygonize: an empty
///         cloud, a non-finite particle;
///         Error(InvalidArgument) the field options out of range, as polygonize;
///         Error(Cancelled) when the progress callback returns false.
PM_EXPORT std::vector<VertexAttribute> polygonize_attributes(const PointCloud& cloud, const PolygonizeOptions& options,
                                                             const Vec3* points, size_t count);

/// The same on a field built beforehand, for the particles' `attributes` (one value per
/// field particle and component, in the field's input order).
PM_EXPORT std::vector<VertexAttribute> polygonize_attributes(const ParticleField& field,
                                                             const std::vector<VertexAttribute>& attributes,
                                                             const Vec3* points, size_t count, int threads = 0,
                                                             const ProgressCallback& progress = {});

}  // namespace particlemesh
