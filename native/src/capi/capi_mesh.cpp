// C ABI: meshes and topology reports.
#include <algorithm>
#include <climits>
#include <memory>
#include <string>
#include <type_traits>
#include <vector>

#include "capi/conversions.h"
#include "capi/firewall.h"
#include "capi/handles.h"
#include "mesh/edges_impl.h"
#include "particlemesh/io/mesh_io.h"
#include "particlemesh/mesh/components.h"
#include "particlemesh/mesh/edges.h"
#include "particlemesh/mesh/ray_crossings.h"
#include "particlemesh/mesh/topology_report.h"

using namespace particlemesh;
using particlemesh::capi::check_capacity;
using particlemesh::capi::copy_vec3s;
using particlemesh::capi::guarded;
using particlemesh::capi::require;

namespace {

// A vector whose capacity exceeds its size by more than a quarter (one grown by doubling)
// shrunk to its size, so that a lent array is all the memory its mesh keeps for it.
template <class T>
void trim_room(std::vector<T>& v) {
  if (v.capacity() - v.size() > v.size() / 4) v.shrink_to_fit();
}

}  // namespace

extern "C" {

pm_status pm_mesh_create(const double* positions, size_t vertex_count, const int32_t* triangles,
                         size_t triangle_count, const double* normals, pm_mesh** out_mesh) {
  return guarded([&] {
    require(out_mesh, "out_mesh");
    if (vertex_count > 0) require(positions, "positions");
    if (triangle_count > 0) require(triangles, "triangles");
    if (vertex_count > size_t(INT32_MAX)) throw Error(Status::LimitExceeded, "more than 2^31 - 1 vertices");
    auto handle = std::make_unique<pm_mesh>();
    TriMesh& m = handle->mesh;
    m.positions.resize(vertex_count);
    for (size_t i = 0; i < vertex_count; ++i) {
      m.positions[i] = {positions[3 * i], positions[3 * i + 1], positions[3 * i + 2]};
      if (!is_finite(m.positions[i]))
        throw Error(Status::InvalidInput, "positions[" + std::to_string(i) + "] is not finite");
    }
    if (normals) {
      m.normals.resize(vertex_count);
      for (size_t i = 0; i < vertex_count; ++i) {
        m.normals[i] = {normals[3 * i], normals[3 * i + 1], normals[3 * i + 2]};
        if (!is_finite(m.normals[i]))
          throw Error(Status::InvalidInput, "normals[" + std::to_string(i) + "] is not finite");
      }
    }
    m.triangles.resize(triangle_count);
    for (size_t f = 0; f < triangle_count; ++f)
      for (int c = 0; c < 3; ++c) {
        const int32_t v = triangles[3 * f + size_t(c)];
        if (v < 0 || size_t(v) >= vertex_count)
          throw Error(Status::InvalidInput, "triangles[" + std::to_string(f) + "] refers to vertex " +
                                                std::to_string(v) + " of " + std::to_string(vertex_count));
        m.triangles[f][size_t(c)] = uint32_t(v);
      }
    *out_mesh = handle.release();
  });
}

pm_status pm_mesh_read(const char* path, pm_mesh** out_mesh) {
  return guarded([&] {
    require(path, "path");
    require(out_mesh, "out_mesh");
    auto handle = std::make_unique<pm_mesh>();
    handle->mesh = read_mesh(path);
    *out_mesh = handle.release();
  });
}

pm_status pm_mesh_write(const pm_mesh* mesh, const char* path) {
  return guarded([&] {
    require(mesh, "mesh");
    require(path, "path");
    write_mesh(mesh->mesh, path);
  });
}

pm_status pm_mesh_get_counts(const pm_mesh* mesh, size_t* out_vertex_count, size_t* out_triangle_count) {
  return guarded([&] {
    require(mesh, "mesh");
    if (out_vertex_count) *out_vertex_count = mesh->mesh.positions.size();
    if (out_triangle_count) *out_triangle_count = mesh->mesh.triangles.size();
  });
}

pm_status pm_mesh_has_normals(const pm_mesh* mesh, int32_t* out_has_normals) {
  return guarded([&] {
    require(mesh, "mesh");
    require(out_has_normals, "out_has_normals");
    *out_has_normals = mesh->mesh.normals.empty() ? 0 : 1;
  });
}

pm_status pm_mesh_copy_positions(const pm_mesh* mesh, double* out, size_t capacity) {
  return guarded([&] {
    require(mesh, "mesh");
    require(out, "out");
    copy_vec3s(mesh->mesh.positions, out, capacity, "vertices");
  });
}

pm_status pm_mesh_copy_positions_f32(const pm_mesh* mesh, float* out, size_t capacity) {
  return guarded([&] {
    require(mesh, "mesh");
    require(out, "out");
    copy_vec3s(mesh->mesh.positions, out, capacity, "vertices");
  });
}

pm_status pm_mesh_copy_normals_f32(const pm_mesh* mesh, float* out, size_t capacity) {
  return guarded([&] {
    require(mesh, "mesh");
    require(out, "out");
    if (mesh->mesh.normals.empty()) throw Error(Status::InvalidArgument, "the mesh has no normals");
    copy_vec3s(mesh->mesh.normals, out, capacity, "vertices");
  });
}

pm_status pm_mesh_copy_normals(const pm_mesh* mesh, double* out, size_t capacity) {
  return guarded([&] {
    require(mesh, "mesh");
    require(out, "out");
    if (mesh->mesh.normals.empty()) throw Error(Status::InvalidArgument, "the mesh has no normals");
    copy_vec3s(mesh->mesh.normals, out, capacity, "vertices");
  });
}

pm_status pm_mesh_copy_triangles(const pm_mesh* mesh, int32_t* out, size_t capacity) {
  return guarded([&] {
    require(mesh, "mesh");
    require(out, "out");
    const auto& t = mesh->mesh.triangles;
    check_capacity(capacity, t.size(), "triangles");
    if (mesh->mesh.positions.size() > size_t(INT32_MAX))
      throw Error(Status::LimitExceeded, "vertex indices do not fit int32");
    for (size_t f = 0; f < t.size(); ++f)
      for (int c = 0; c < 3; ++c) out[3 * f + size_t(c)] = int32_t(t[f][size_t(c)]);
  });
}

pm_status pm_mesh_lend_arrays(pm_mesh* mesh, double** out_positions, double** out_normals, uint32_t** out_triangles) {
  static_assert(sizeof(Vec3) == 3 * sizeof(double) && std::is_standard_layout_v<Vec3>);
  static_assert(sizeof(Triangle) == 3 * sizeof(uint32_t));
  return guarded([&] {
    require(mesh, "mesh");
    require(out_positions, "out_positions");
    require(out_normals, "out_normals");
    require(out_triangles, "out_triangles");
    TriMesh& m = mesh->mesh;
    trim_room(m.positions);
    trim_room(m.normals);
    trim_room(m.triangles);
    *out_positions = m.positions.empty() ? nullptr : &m.positions.front().x;
    *out_normals = m.normals.empty() ? nullptr : &m.normals.front().x;
    *out_triangles = m.triangles.empty() ? nullptr : m.triangles.front().data();
  });
}

void pm_mesh_destroy(pm_mesh* mesh) { delete mesh; }

pm_status pm_triangle_edges(const uint32_t* triangles, size_t triangle_count, size_t vertex_count, int32_t threads,
                            uint32_t* out_edges, size_t edge_capacity, uint32_t* out_corner_edges,
                            size_t* out_edge_count) {
  return guarded([&] {
    require(out_edge_count, "out_edge_count");
    if (triangle_count > 0) {
      require(triangles, "triangles");
      require(out_edges, "out_edges");
      require(out_corner_edges, "out_corner_edges");
    }
    *out_edge_count = detail::number_edges(triangles, triangle_count, vertex_count, threads, out_corner_edges,
                                           [&](size_t count) {
                                             *out_edge_count = count;
                                             if (edge_capacity < count)
                                               throw Error(Status::InvalidArgument,
                                                           "edge_capacity " + std::to_string(edge_capacity) +
                                                               " is less than the " + std::to_string(count) + " edges");
                                             return out_edges;
                                           });
  });
}

pm_status pm_mesh_ray_crossings(const pm_mesh* mesh, const double* points, size_t point_count, int32_t threads,
                                uint64_t* out_crossings) {
  return guarded([&] {
    require(mesh, "mesh");
    if (point_count > 0) {
      require(points, "points");
      require(out_crossings, "out_crossings");
    }
    std::vector<Vec3> q(point_count);
    for (size_t i = 0; i < point_count; ++i) q[i] = {points[3 * i], points[3 * i + 1], points[3 * i + 2]};
    const std::vector<uint64_t> counts = ray_crossings(mesh->mesh, q, threads);
    std::copy(counts.begin(), counts.end(), out_crossings);
  });
}

pm_status pm_mesh_get_not_read_count(const pm_mesh* mesh, size_t* out_count) {
  return guarded([&] {
    require(mesh, "mesh");
    require(out_count, "out_count");
    *out_count = mesh->mesh.not_read.size();
  });
}

pm_status pm_mesh_get_not_read(const pm_mesh* mesh, size_t index, const char** out_text) {
  return guarded([&] {
    require(mesh, "mesh");
    require(out_text, "out_text");
    *out_text = capi::not_read_line(mesh->mesh.not_read, index);
  });
}

pm_status pm_mesh_components(const pm_mesh* mesh, size_t* out_component_count, uint32_t* out_vertex_component,
                             uint64_t* out_triangles, double* out_area, double* out_volume, size_t capacity) {
  return guarded([&] {
    require(mesh, "mesh");
    require(out_component_count, "out_component_count");
    const MeshComponents c = mesh_components(mesh->mesh);
    const size_t count = c.triangles.size();
    *out_component_count = count;
    if ((out_triangles || out_area || out_volume) && capacity < count)
      throw Error(Status::InvalidArgument, "capacity " + std::to_string(capacity) + " is below the mesh's " +
                                               std::to_string(count) + " components");
    if (out_vertex_component) std::copy(c.vertex_component.begin(), c.vertex_component.end(), out_vertex_component);
    if (out_triangles) std::copy(c.triangles.begin(), c.triangles.end(), out_triangles);
    if (out_area) std::copy(c.area.begin(), c.area.end(), out_area);
    if (out_volume) std::copy(c.volume.begin(), c.volume.end(), out_volume);
  });
}

pm_status pm_mesh_report(const pm_mesh* mesh, pm_topology_report* out_report) {
  return guarded([&] {
    require(mesh, "mesh");
    require(out_report, "out_report");
    const TopologyReport r = topology_report(mesh->mesh);
    pm_topology_report c{};
    c.struct_size = sizeof(c);
    c.vertices = r.vertices;
    c.triangles = r.triangles;
    c.vertices_used = r.vertices_used;
    c.edges = r.edges;
    c.boundary_edges = r.boundary_edges;
    c.manifold_edges = r.manifold_edges;
    c.nonmanifold_edges = r.nonmanifold_edges;
    c.nonmanifold_vertices = r.nonmanifold_vertices;
    c.degenerate_triangles = r.degenerate_triangles;
    c.duplicate_triangles = r.duplicate_triangles;
    c.orientation_conflicts = r.orientation_conflicts;
    c.boundary_loops = r.boundary_loops;
    c.components = r.components;
    c.closed_components = r.closed_components;
    c.euler_characteristic = r.euler_characteristic;
    c.manifold = r.manifold;
    c.closed = r.closed;
    c.consistently_oriented = r.consistently_oriented;
    c.outward = r.outward;
    capi::write_versioned(out_report, c, "out_report");
  });
}

}  // extern "C"
