// The body shared by the file-reader fuzz targets: the bytes become a file with the given
// extension, read through the C++ API and the C ABI, and what comes back is checked against
// what the API promises.
#pragma once

#include <cmath>
#include <vector>

#include "fuzz_support.h"
#include "particlemesh/core/error.h"
#include "particlemesh/io/mesh_io.h"

namespace particlemesh::fuzz {

inline void check_cloud(const PointCloud& c) {
  PM_FUZZ_CHECK(!c.positions.empty());
  PM_FUZZ_CHECK(c.normals.empty() || c.normals.size() == c.positions.size());
  for (const Vec3& p : c.positions) PM_FUZZ_CHECK(is_finite(p));
  for (const Vec3& n : c.normals) PM_FUZZ_CHECK(is_finite(n));
}

inline void check_mesh(const TriMesh& m) {
  PM_FUZZ_CHECK(m.normals.empty() || m.normals.size() == m.positions.size());
  for (const Vec3& p : m.positions) PM_FUZZ_CHECK(is_finite(p));
  for (const Triangle& t : m.triangles)
    for (uint32_t v : t) PM_FUZZ_CHECK(v < m.positions.size());
  for (const VertexAttribute& a : m.corner_attributes) {
    PM_FUZZ_CHECK(a.values.size() == 3 * m.triangles.size() * size_t(a.components));
    for (float x : a.values) PM_FUZZ_CHECK(std::isfinite(x));
  }
}

/// read_point_cloud and/or read_mesh on the bytes (as a file named *extension), then the
/// same through pm_cloud_read / pm_mesh_read. Only particlemesh::Error may escape the C++
/// API; anything else propagates and is a finding.
inline void read_both(const uint8_t* data, size_t size, const char* extension, bool as_cloud, bool as_mesh) {
  static TempFileCleanup cleanup{extension};
  const std::string path = temp_file(extension, data, size);
  if (as_cloud) {
    try {
      check_cloud(read_point_cloud(path));
    } catch (const Error& e) {
      PM_FUZZ_CHECK(e.status() != Status::Internal);
      PM_FUZZ_CHECK(e.what()[0] != '\0');
    }
    pm_cloud* cloud = reinterpret_cast<pm_cloud*>(0x1);
    const pm_status s = pm_cloud_read(path.c_str(), &cloud);
    check_status(s);
    if (s == PM_OK) {
      size_t n = 0;
      check_status(pm_cloud_get_count(cloud, &n));
      PM_FUZZ_CHECK(n > 0);
      pm_cloud_destroy(cloud);
    } else {
      PM_FUZZ_CHECK(cloud == reinterpret_cast<pm_cloud*>(0x1));  // outputs untouched on failure
    }
  }
  if (as_mesh) {
    try {
      const TriMesh m = read_mesh(path);
      check_mesh(m);
      // What was read is written and read again: same vertices, triangles and attributes.
      static TempFileCleanup written{".out.ply"};
      const std::string out = temp_file(".out.ply", nullptr, 0);
      write_mesh(m, out);
      const TriMesh back = read_mesh(out);
      PM_FUZZ_CHECK(back.positions.size() == m.positions.size());
      PM_FUZZ_CHECK(back.triangles == m.triangles);
      // Every channel comes back; a k-component one other than "color" as k one-component
      // PLY properties (name_0 .. name_k), so the components are counted.
      auto components = [](const TriMesh& t) {
        size_t n = 0;
        for (const VertexAttribute& a : t.attributes) n += size_t(a.components);
        return n;
      };
      PM_FUZZ_CHECK(components(back) == components(m));
      for (const Vec3& p : back.positions) PM_FUZZ_CHECK(is_finite(p));
    } catch (const Error& e) {
      PM_FUZZ_CHECK(e.status() != Status::Internal);
      PM_FUZZ_CHECK(e.what()[0] != '\0');
    }
    pm_mesh* mesh = reinterpret_cast<pm_mesh*>(0x1);
    const pm_status s = pm_mesh_read(path.c_str(), &mesh);
    check_status(s);
    if (s == PM_OK) {
      pm_topology_report r{};
      r.struct_size = sizeof(r);
      check_status(pm_mesh_report(mesh, &r));
      // Values per corner (an OBJ's texture coordinates) copied out in full.
      size_t corners = 0, nv = 0, nt = 0;
      check_status(pm_mesh_get_corner_attribute_count(mesh, &corners));
      check_status(pm_mesh_get_counts(mesh, &nv, &nt));
      for (size_t i = 0; i < corners; ++i) {
        const char* name = nullptr;
        int32_t k = 0;
        check_status(pm_mesh_get_corner_attribute_name(mesh, i, &name));
        check_status(pm_mesh_get_corner_attribute_components(mesh, name, &k));
        std::vector<float> values(3 * nt * size_t(k));
        check_status(pm_mesh_copy_corner_attribute(mesh, name, values.data(), nt));
      }
      pm_mesh_destroy(mesh);
    } else {
      PM_FUZZ_CHECK(mesh == reinterpret_cast<pm_mesh*>(0x1));
    }
  }
}

}  // namespace particlemesh::fuzz
