// C ABI: point clouds.
#include <algorithm>
#include <memory>
#include <string>

#include "capi/conversions.h"
#include "capi/firewall.h"
#include "capi/handles.h"
#include "particlemesh/io/mesh_io.h"
#include "particlemesh/sample/thin.h"
#include "particlemesh/spatial/spacing.h"

using namespace particlemesh;
using particlemesh::capi::guarded;
using particlemesh::capi::require;

namespace {

constexpr size_t kMaxCount = size_t(1) << 32;

template <class T>
pm_status create_cloud(const T* positions, const T* normals, size_t count, pm_cloud** out) {
  return guarded([&] {
    require(out, "out_cloud");
    if (count == 0) throw Error(Status::InvalidInput, "count is 0: the cloud is empty");
    require(positions, "positions");
    if (count >= kMaxCount) throw Error(Status::LimitExceeded, "count exceeds 2^32 - 1 points");
    auto handle = std::make_unique<pm_cloud>();
    PointCloud& c = handle->cloud;
    c.positions.resize(count);
    for (size_t i = 0; i < count; ++i)
      c.positions[i] = {double(positions[3 * i]), double(positions[3 * i + 1]), double(positions[3 * i + 2])};
    if (normals) {
      c.normals.resize(count);
      for (size_t i = 0; i < count; ++i)
        c.normals[i] = {double(normals[3 * i]), double(normals[3 * i + 1]), double(normals[3 * i + 2])};
    }
    validate_point_cloud(c);
    *out = handle.release();
  });
}

template <class T>
pm_status copy_vectors(const pm_cloud* cloud, T* out, size_t capacity, bool normals) {
  return guarded([&] {
    require(cloud, "cloud");
    require(out, "out");
    const auto& v = normals ? cloud->cloud.normals : cloud->cloud.positions;
    if (normals && v.empty()) throw Error(Status::InvalidArgument, "the cloud has no normals");
    capi::copy_vec3s(v, out, capacity, "points");
  });
}

}  // namespace

extern "C" {

pm_status pm_cloud_create(const double* positions, const double* normals, size_t count, pm_cloud** out_cloud) {
  return create_cloud(positions, normals, count, out_cloud);
}

pm_status pm_cloud_create_f32(const float* positions, const float* normals, size_t count, pm_cloud** out_cloud) {
  return create_cloud(positions, normals, count, out_cloud);
}

pm_status pm_cloud_read(const char* path, pm_cloud** out_cloud) {
  return guarded([&] {
    require(path, "path");
    require(out_cloud, "out_cloud");
    auto handle = std::make_unique<pm_cloud>();
    handle->cloud = read_point_cloud(path);
    *out_cloud = handle.release();
  });
}

pm_status pm_frame_collection_read(const char* path, pm_frame_collection** out_collection) {
  return guarded([&] {
    require(path, "path");
    require(out_collection, "out_collection");
    auto handle = std::make_unique<pm_frame_collection>();
    handle->frames = read_frame_collection(path);
    *out_collection = handle.release();
  });
}

pm_status pm_frame_collection_get_count(const pm_frame_collection* collection, size_t* out_count) {
  return guarded([&] {
    require(collection, "collection");
    require(out_count, "out_count");
    *out_count = collection->frames.size();
  });
}

pm_status pm_frame_collection_get_frame(const pm_frame_collection* collection, size_t index, double* out_time,
                                        const char** out_path) {
  return guarded([&] {
    require(collection, "collection");
    require(out_time, "out_time");
    require(out_path, "out_path");
    if (index >= collection->frames.size())
      throw Error(Status::InvalidArgument, "frame " + std::to_string(index) + " of a collection of " +
                                               std::to_string(collection->frames.size()));
    *out_time = collection->frames[index].time;
    *out_path = collection->frames[index].path.c_str();
  });
}

void pm_frame_collection_destroy(pm_frame_collection* collection) { delete collection; }

pm_status pm_cloud_get_count(const pm_cloud* cloud, size_t* out_count) {
  return guarded([&] {
    require(cloud, "cloud");
    require(out_count, "out_count");
    *out_count = cloud->cloud.size();
  });
}

pm_status pm_cloud_has_normals(const pm_cloud* cloud, int32_t* out_has_normals) {
  return guarded([&] {
    require(cloud, "cloud");
    require(out_has_normals, "out_has_normals");
    *out_has_normals = cloud->cloud.has_normals() ? 1 : 0;
  });
}

pm_status pm_cloud_copy_positions_f32(const pm_cloud* cloud, float* out, size_t capacity) {
  return copy_vectors(cloud, out, capacity, false);
}

pm_status pm_cloud_copy_normals_f32(const pm_cloud* cloud, float* out, size_t capacity) {
  return copy_vectors(cloud, out, capacity, true);
}

pm_status pm_cloud_copy_positions(const pm_cloud* cloud, double* out, size_t capacity) {
  return copy_vectors(cloud, out, capacity, false);
}

pm_status pm_cloud_copy_normals(const pm_cloud* cloud, double* out, size_t capacity) {
  return copy_vectors(cloud, out, capacity, true);
}

void pm_cloud_destroy(pm_cloud* cloud) { delete cloud; }

pm_status pm_estimate_spacing(const pm_cloud* cloud, int32_t threads, double* out_spacing) {
  return guarded([&] {
    require(cloud, "cloud");
    require(out_spacing, "out_spacing");
    const auto& p = cloud->cloud.positions;
    *out_spacing = estimate_spacing(p.data(), p.size(), threads).spacing;
  });
}

pm_status pm_estimate_spacing_sampled(const pm_cloud* cloud, size_t max_samples, int32_t threads,
                                      double* out_spacing) {
  return guarded([&] {
    require(cloud, "cloud");
    require(out_spacing, "out_spacing");
    const auto& p = cloud->cloud.positions;
    *out_spacing = estimate_spacing_sampled(p.data(), p.size(), max_samples, threads).spacing;
  });
}

pm_status pm_cloud_thin(const pm_cloud* cloud, double min_distance, uint32_t* out_indices,
                        size_t capacity, size_t* out_count) {
  return guarded([&] {
    require(cloud, "cloud");
    require(out_indices, "out_indices");
    require(out_count, "out_count");
    const auto& p = cloud->cloud.positions;
    if (capacity < p.size())
      throw Error(Status::InvalidArgument, "capacity " + std::to_string(capacity) +
                                               " is less than the cloud's " + std::to_string(p.size()) + " points");
    const std::vector<uint32_t> kept = thin_points(p.data(), p.size(), min_distance);
    std::copy(kept.begin(), kept.end(), out_indices);
    *out_count = kept.size();
  });
}

}  // extern "C"
