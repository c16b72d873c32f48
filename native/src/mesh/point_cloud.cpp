#include "particlemesh/mesh/point_cloud.h"

#include <cmath>
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
