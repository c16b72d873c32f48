#include "particlemesh/mesh/point_cloud.h"

#include <cmath>
#include <cstddef>
#include <string>

#include "particlemesh/core/error.h"

namespace PM_NAMESPACE {

namespace {
const char* bad_value_name(double v) { return std::isnan(v) ? "NaN" : "infinite"; }

void check_vectors(const std::vector<Vec3>& values, const char* what) {
  for (size_t i = 0; i < values.size(); ++i) {
    const Vec3& p = values[i];
    for (int a = 0; a < 3; ++a) {
      if (!std::isfinite(p[a]))
        throw Error(Status::InvalidInput, std::string(what) + "[" + std::to_string(i) + "]." +
                                              "xyz"[a] + " is " + bad_value_name(p[a]));
    }
  }
}
}  // namespace

PointCloud select_points(const PointCloud& cloud, const std::vector<uint32_t>& indices) {
  PointCloud out;
  out.positions.reserve(indices.size());
  for (uint32_t i : indices) out.positions.push_back(cloud.positions[i]);
  if (cloud.has_normals())
    for (uint32_t i : indices) out.normals.push_back(cloud.normals[i]);
  for (const VertexAttribute& a : cloud.attributes) {
    VertexAttribute& b = out.attributes.emplace_back(VertexAttribute{a.name, a.components, {}});
    b.values.reserve(indices.size() * size_t(a.components));
    for (uint32_t i : indices)
      b.values.insert(b.values.end(), a.values.begin() + ptrdiff_t(i) * a.components,
                      a.values.begin() + ptrdiff_t(i + 1) * a.components);
  }
  out.not_read = cloud.not_read;
  return out;
}

void validate_point_cloud(const PointCloud& cloud) {
  if (!cloud.normals.empty() && cloud.normals.size() != cloud.positions.size())
    throw Error(Status::InvalidInput, "the cloud has " + std::to_string(cloud.positions.size()) +
                                          " positions but " + std::to_string(cloud.normals.size()) +
                                          " normals");
  check_vectors(cloud.positions, "positions");
  check_vectors(cloud.normals, "normals");
  for (const auto& a : cloud.attributes) {
    if (a.components < 1 || a.values.size() != cloud.positions.size() * size_t(a.components))
      throw Error(Status::InvalidInput, "attribute '" + a.name + "' has " +
                                            std::to_string(a.values.size()) + " values, expected " +
                                            std::to_string(cloud.positions.size()) + " x " +
                                            std::to_string(a.components));
  }
}

}  // namespace particlemesh
