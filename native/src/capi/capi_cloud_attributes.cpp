// C ABI: a cloud's per-point attributes read back (query, then copy), as the mesh's are in
// capi_smooth.cpp.
#include <algorithm>
#include <string>

#include "capi/conversions.h"
#include "capi/firewall.h"
#include "capi/handles.h"

using namespace particlemesh;
using particlemesh::capi::guarded;
using particlemesh::capi::require;

namespace {

const VertexAttribute& find(const pm_cloud* cloud, const char* name) {
  require(cloud, "cloud");
  require(name, "name");
  for (const auto& a : cloud->cloud.attributes)
    if (a.name == name) return a;
  throw Error(Status::InvalidArgument, std::string("the cloud has no attribute '") + name + "'");
}

}  // namespace

extern "C" {

pm_status pm_cloud_get_attribute_count(const pm_cloud* cloud, size_t* out_count) {
  return guarded([&] {
    require(cloud, "cloud");
    require(out_count, "out_count");
    *out_count = cloud->cloud.attributes.size();
  });
}

pm_status pm_cloud_get_attribute_name(const pm_cloud* cloud, size_t index, const char** out_name) {
  return guarded([&] {
    require(cloud, "cloud");
    require(out_name, "out_name");
    const auto& attrs = cloud->cloud.attributes;
    if (index >= attrs.size())
      throw Error(Status::InvalidArgument, "index " + std::to_string(index) + " is out of range: the cloud has " +
                                               std::to_string(attrs.size()) + " attributes");
    *out_name = attrs[index].name.c_str();
  });
}

pm_status pm_cloud_get_not_read_count(const pm_cloud* cloud, size_t* out_count) {
  return guarded([&] {
    require(cloud, "cloud");
    require(out_count, "out_count");
    *out_count = cloud->cloud.not_read.size();
  });
}

pm_status pm_cloud_get_not_read(const pm_cloud* cloud, size_t index, const char** out_text) {
  return guarded([&] {
    require(cloud, "cloud");
    require(out_text, "out_text");
    *out_text = capi::not_read_line(cloud->cloud.not_read, index);
  });
}

pm_status pm_cloud_get_attribute_components(const pm_cloud* cloud, const char* name, int32_t* out_components) {
  return guarded([&] {
    const VertexAttribute& a = find(cloud, name);
    require(out_components, "out_components");
    *out_components = a.components;
  });
}

pm_status pm_cloud_copy_attribute(const pm_cloud* cloud, const char* name, float* out, size_t capacity_points) {
  return guarded([&] {
    const VertexAttribute& a = find(cloud, name);
    require(out, "out");
    const size_t n = cloud->cloud.positions.size();
    if (capacity_points < n)
      throw Error(Status::InvalidArgument, "capacity_points " + std::to_string(capacity_points) +
                                               " is less than the " + std::to_string(n) + " points");
    if (a.values.size() != n * size_t(a.components))
      throw Error(Status::Internal, "attribute '" + a.name + "' holds " + std::to_string(a.values.size()) +
                                        " values for " + std::to_string(n) + " points");
    std::copy(a.values.begin(), a.values.end(), out);
  });
}

}  // extern "C"
