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
  /// What read_point_cloud found in the file for each particle but does not carry, one line
  /// each naming it and why: "point attribute 'name' (strings)", "PointData array 'label'
  /// (strings)", "vertex list property 'ids' (lists)", "extra bytes (4 per point)"; past 32
  /// names, a last line "and N more". Empty for a cloud that was not read from a file, and
  /// when everything per particle was read.
  std::vector<std::string> not_read;

  size_t size() const { return positions.size(); }
  bool has_normals() const { return !normals.empty(); }
};

/// Check that the cloud is usable: normals (if any) match the positions in number, every
/// coordinate and normal component is finite, attribute sizes match.
/// @throws Error(InvalidInput) naming the first offending element, e.g. "positions[12].y is NaN".
PM_EXPORT void validate_point_cloud(const PointCloud& cloud);

/// The points `indices` of the cloud (in that order), each with its normal and attribute values
/// (and the cloud's not_read). Every index must be below cloud.size().
PM_EXPORT PointCloud select_points(const PointCloud& cloud, const std::vector<uint32_t>& indices);

}  // namespace particlemesh
