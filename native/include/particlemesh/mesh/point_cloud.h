// Particles: positions, optional normals, optional per-point attribute channels.
#pragma once

#include "particlemesh/core/config.h"

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "particlemesh/core/export.h"
#include "particlemesh/core/vec3.h"

namespace PM_NAMESPACE {

/// A named per-vertex float channel (colour, velocity, radius, ...), `components` floats per
/// vertex, stored vertex-major: values[v * components + c].
struct VertexAttribute {
  std::string name;
  int components = 1;
  std::vector<float> values;
};

/// N particles. `normals` is either empty or has one entry per position.
struct PointCloud {
  std::vector<Vec3> positions;
  std::vector<Vec3> normals;
  std::vector<VertexAttribute> attributes;

  size_t size() const { return positions.size(); }
  bool has_normals() const { return !normals.empty(); }
};

/// Check that the cloud is usable: normals (if any) match the positions in number, every
/// coordinate and normal component is finite, attribute sizes match.
/// @throws Error(InvalidInput) naming the first offending element, e.g. "positions[12].y is NaN".
PM_EXPORT void validate_point_cloud(const PointCloud& cloud);

/// The points `indices` of the cloud (in that order), each with its normal and attribute values.
/// Every index must be below cloud.size().
PM_EXPORT PointCloud select_points(const PointCloud& cloud, const std::vector<uint32_t>& indices);

}  // namespace particlemesh
