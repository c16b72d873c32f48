// C ABI: per-vertex attributes and smoothing (Loop / butterfly).
#include <cmath>
#include <memory>
#include <string>

#include "capi/conversions.h"
#include "capi/firewall.h"
#include "capi/handles.h"
#include "particlemesh/smooth/smoother.h"
#include "particlemesh/smooth/subdivide.h"

using namespace particlemesh;
using particlemesh::capi::guarded;
using particlemesh::capi::wrap_progress;
using particlemesh::capi::require;

namespace {

constexpr int32_t kMaxComponents = 4096;

VertexAttribute make_attribute(const char* name, int32_t components, const float* values, size_t vertex_count,
                               size_t expected_vertices, const char* owner) {
  require(name, "name");
  if (name[0] == '\0') throw Error(Status::InvalidArgument, "name is empty");
  if (components < 1 || components > kMaxComponents)
    throw Error(Status::InvalidArgument, "components must be in [1, 4096], got " + std::to_string(components));
  if (vertex_count != expected_vertices)
    throw Error(Status::InvalidArgument, "vertex_count is " + std::to_string(vertex_count) + " but the " + owner +
                                             " has " + std::to_string(expected_vertices));
  const size_t n = vertex_count * size_t(components);
  if (n > 0) require(values, "values");
  VertexAttribute a{name, components, std::vector<float>(values, values + n)};
  for (size_t i = 0; i < n; ++i)
    if (!std::isfinite(a.values[i]))
      throw Error(Status::InvalidInput, "values[" + std::to_string(i) + "] (vertex " +
                                            std::to_string(i / size_t(components)) + ", component " +
                                            std::to_string(i % size_t(components)) + ") of attribute '" + name +
                                            "' is not finite");
  return a;
}

/// Sets (adds or replaces, by name) an attribute of a TriMesh or a PointCloud, `owner` naming
/// it in errors.
template <class Vertices>
void set_attribute(Vertices& v, const char* owner, const char* name, int32_t components, const float* values,
                   size_t vertex_count) {
  VertexAttribute a = make_attribute(name, components, values, vertex_count, v.positions.size(), owner);
  for (auto& x : v.attributes)
    if (x.name == a.name) {
      x = std::move(a);
      return;
    }
  v.attributes.push_back(std::move(a));
}

/// The corner attribute `name` of a pm_mesh, checked: a count of triangles and components as
/// the C header says, finite values. Added, or replacing one of the same name.
void set_corner_attribute(TriMesh& mesh, const char* name, int32_t components, const float* values,
                          size_t triangle_count) {
  require(name, "name");
  if (name[0] == '\0') throw Error(Status::InvalidArgument, "name is empty");
  if (components < 1 || components > 64)
    throw Error(Status::InvalidArgument, "components must be in [1, 64], got " + std::to_string(components));
  if (triangle_count != mesh.triangles.size())
    throw Error(Status::InvalidArgument, "triangle_count is " + std::to_string(triangle_count) + " but the mesh has " +
                                             std::to_string(mesh.triangles.size()));
  const size_t k = size_t(components), n = 3 * triangle_count * k;
  if (n > 0) require(values, "values");
  VertexAttribute a{name, components, std::vector<float>(values, values + n)};
  for (size_t i = 0; i < n; ++i)
    if (!std::isfinite(a.values[i]))
      throw Error(Status::InvalidInput, "values[" + std::to_string(i) + "] (triangle " + std::to_string(i / k / 3) +
                                            ", corner " + std::to_string(i / k % 3) + ", component " +
                                            std::to_string(i % k) + ") of corner attribute '" + name + "' is not finite");
  for (auto& x : mesh.corner_attributes)
    if (x.name == a.name) {
      x = std::move(a);
      return;
    }
  mesh.corner_attributes.push_back(std::move(a));
}

/// A mesh's attribute (`corner`: its corner attribute) named `name`, else InvalidArgument.
const VertexAttribute& find(const pm_mesh* mesh, const char* name, bool corner = false) {
  require(mesh, "mesh");
  require(name, "name");
  for (const auto& a : corner ? mesh->mesh.corner_attributes : mesh->mesh.attributes)
    if (a.name == name) return a;
  throw Error(Status::InvalidArgument, std::string("the mesh has no ") + (corner ? "corner " : "") + "attribute '" +
                                           name + "'");
}

/// The count (out_count) or the index-th name (out_name) of a mesh's attributes or corner
/// attributes.
void list_attributes(const pm_mesh* mesh, bool corner, size_t* out_count, size_t index, const char** out_name) {
  require(mesh, "mesh");
  const auto& attrs = corner ? mesh->mesh.corner_attributes : mesh->mesh.attributes;
  if (out_name == nullptr) {
    require(out_count, "out_count");
    *out_count = attrs.size();
    return;
  }
  if (index >= attrs.size())
    throw Error(Status::InvalidArgument, "index " + std::to_string(index) + " is out of range: the mesh has " +
                                             std::to_string(attrs.size()) + (corner ? " corner" : "") + " attributes");
  *out_name = attrs[index].name.c_str();
}

/// The C++ options of a pm_smooth_options (NULL: the defaults), creases checked against `mesh`.
SmoothOptions smooth_options(const pm_mesh* mesh, const pm_smooth_options* options) {
  const pm_smooth_options o =
      capi::read_options(options, pm_smooth_options_init,
                         {offsetof(pm_smooth_options, crease_edges), offsetof(pm_smooth_options, crease_sharpness)});
  SmoothOptions opt;
  opt.scheme = static_cast<SmoothScheme>(o.scheme);
  opt.levels = o.levels;
  opt.limit = o.limit != 0;
  opt.boundary = static_cast<BoundaryRule>(o.boundary);
  opt.crease_method = static_cast<CreaseMethod>(o.crease_method);
  opt.threads = o.threads;
  opt.max_triangles = o.max_triangles;
  if (o.crease_count > 0) {
    require(o.crease_edges, "options->crease_edges");
    if (o.crease_count > mesh->mesh.triangles.size() * 3)
      throw Error(Status::InvalidArgument, "options->crease_count " + std::to_string(o.crease_count) +
                                               " exceeds the mesh's edge count");
    opt.creases.resize(o.crease_count);
    for (size_t i = 0; i < o.crease_count; ++i) {
      const int32_t a = o.crease_edges[2 * i], b = o.crease_edges[2 * i + 1];
      if (a < 0 || b < 0)
        throw Error(Status::InvalidArgument, "options->crease_edges[" + std::to_string(i) + "] = (" +
                                                 std::to_string(a) + ", " + std::to_string(b) +
                                                 ") has a negative vertex index");
      opt.creases[i].a = uint32_t(a);
      opt.creases[i].b = uint32_t(b);
      if (o.crease_sharpness) opt.creases[i].sharpness = o.crease_sharpness[i];
    }
  }
  opt.progress = wrap_progress(o.progress, o.progress_user_data);
  return opt;
}

}  // namespace

extern "C" {

pm_status pm_mesh_set_attribute(pm_mesh* mesh, const char* name, int32_t components, const float* values,
                                size_t vertex_count) {
  return guarded([&] { set_attribute(capi::deref(mesh, "mesh").mesh, "mesh", name, components, values, vertex_count); });
}

pm_status pm_cloud_set_attribute(pm_cloud* cloud, const char* name, int32_t components, const float* values,
                                 size_t vertex_count) {
  return guarded([&] { set_attribute(capi::deref(cloud, "cloud").cloud, "cloud", name, components, values, vertex_count); });
}

pm_status pm_mesh_get_attribute_components(const pm_mesh* mesh, const char* name, int32_t* out_components) {
  return guarded([&] {
    const VertexAttribute& a = find(mesh, name);
    require(out_components, "out_components");
    *out_components = a.components;
  });
}

pm_status pm_mesh_copy_attribute(const pm_mesh* mesh, const char* name, float* out, size_t capacity_vertices) {
  return guarded([&] {
    const VertexAttribute& a = find(mesh, name);
    require(out, "out");
    const size_t nv = mesh->mesh.positions.size();
    if (capacity_vertices < nv)
      throw Error(Status::InvalidArgument, "capacity_vertices " + std::to_string(capacity_vertices) +
                                               " is less than the " + std::to_string(nv) + " vertices");
    std::copy(a.values.begin(), a.values.end(), out);
  });
}

pm_status pm_mesh_lend_attribute(pm_mesh* mesh, const char* name, float** out_values) {
  return guarded([&] {
    const VertexAttribute& a = find(mesh, name);
    require(out_values, "out_values");
    // find() gives const access for the copying functions; the mesh itself is not const here.
    std::vector<float>& values = const_cast<VertexAttribute&>(a).values;
    *out_values = values.empty() ? nullptr : values.data();
  });
}

pm_status pm_mesh_get_attribute_count(const pm_mesh* mesh, size_t* out_count) {
  return guarded([&] { list_attributes(mesh, false, out_count, 0, nullptr); });
}

pm_status pm_mesh_get_attribute_name(const pm_mesh* mesh, size_t index, const char** out_name) {
  return guarded([&] {
    require(mesh, "mesh");
    require(out_name, "out_name");
    list_attributes(mesh, false, nullptr, index, out_name);
  });
}

pm_status pm_mesh_set_corner_attribute(pm_mesh* mesh, const char* name, int32_t components, const float* values,
                                       size_t triangle_count) {
  return guarded([&] { set_corner_attribute(capi::deref(mesh, "mesh").mesh, name, components, values, triangle_count); });
}

pm_status pm_mesh_get_corner_attribute_count(const pm_mesh* mesh, size_t* out_count) {
  return guarded([&] { list_attributes(mesh, true, out_count, 0, nullptr); });
}

pm_status pm_mesh_get_corner_attribute_name(const pm_mesh* mesh, size_t index, const char** out_name) {
  return guarded([&] {
    require(mesh, "mesh");
    require(out_name, "out_name");
    list_attributes(mesh, true, nullptr, index, out_name);
  });
}

pm_status pm_mesh_get_corner_attribute_components(const pm_mesh* mesh, const char* name, int32_t* out_components) {
  return guarded([&] {
    const VertexAttribute& a = find(mesh, name, true);
    require(out_components, "out_components");
    *out_components = a.components;
  });
}

pm_status pm_mesh_copy_corner_attribute(const pm_mesh* mesh, const char* name, float* out, size_t capacity_triangles) {
  return guarded([&] {
    const VertexAttribute& a = find(mesh, name, true);
    require(out, "out");
    const size_t nt = mesh->mesh.triangles.size();
    if (capacity_triangles < nt)
      throw Error(Status::InvalidArgument, "capacity_triangles " + std::to_string(capacity_triangles) +
                                               " is less than the " + std::to_string(nt) + " triangles");
    std::copy(a.values.begin(), a.values.end(), out);
  });
}

void pm_smooth_options_init(pm_smooth_options* options) {
  if (!capi::reset_versioned(options)) return;
  const SmoothOptions d;
  options->scheme = int32_t(d.scheme);
  options->levels = d.levels;
  options->limit = d.limit ? 1 : 0;
  options->boundary = int32_t(d.boundary);
  options->crease_method = int32_t(d.crease_method);
  options->threads = d.threads;
  options->max_triangles = d.max_triangles;
  options->crease_count = 0;
  options->crease_edges = nullptr;
  options->crease_sharpness = nullptr;
}

pm_status pm_smooth(const pm_mesh* mesh, const pm_smooth_options* options, pm_mesh** out_mesh) {
  return guarded([&] {
    require(mesh, "mesh");
    require(out_mesh, "out_mesh");
    // The options first: a bad struct_size is refused before the mesh is touched.
    const SmoothOptions o = smooth_options(mesh, options);
    SmoothResult r = smooth_mesh(mesh->mesh, o);
    auto handle = std::make_unique<pm_mesh>();
    handle->mesh = std::move(r.mesh);
    *out_mesh = handle.release();
  });
}

pm_status pm_smoother_create(const pm_mesh* mesh, const pm_smooth_options* options, pm_smoother** out_smoother) {
  return guarded([&] {
    require(mesh, "mesh");
    require(out_smoother, "out_smoother");
    const SmoothOptions o = smooth_options(mesh, options);  // before the mesh is touched
    auto handle = std::make_unique<pm_smoother>(pm_smoother{Smoother(mesh->mesh, o)});
    *out_smoother = handle.release();
  });
}

pm_status pm_smoother_matches(const pm_smoother* smoother, const pm_mesh* mesh, int32_t* out_matches) {
  return guarded([&] {
    require(smoother, "smoother");
    require(mesh, "mesh");
    require(out_matches, "out_matches");
    *out_matches = smoother->smoother.matches(mesh->mesh.triangles, mesh->mesh.positions.size()) ? 1 : 0;
  });
}

pm_status pm_smoother_evaluate(const pm_smoother* smoother, const pm_mesh* mesh, pm_mesh** out_mesh) {
  return guarded([&] {
    require(smoother, "smoother");
    require(mesh, "mesh");
    require(out_mesh, "out_mesh");
    const Smoother& s = smoother->smoother;
    if (!s.matches(mesh->mesh.triangles, mesh->mesh.positions.size()))
      throw Error(Status::InvalidArgument,
                  "the mesh (" + std::to_string(mesh->mesh.positions.size()) + " vertices, " +
                      std::to_string(mesh->mesh.triangles.size()) + " triangles) does not have the triangles the smoother "
                      "was made for (" + std::to_string(s.vertex_count()) + " vertices, " +
                      std::to_string(s.triangle_count()) + " triangles)");
    SmoothResult r = s.evaluate(mesh->mesh.positions, mesh->mesh.attributes);
    auto handle = std::make_unique<pm_mesh>();
    handle->mesh = std::move(r.mesh);
    *out_mesh = handle.release();
  });
}

void pm_smoother_destroy(pm_smoother* smoother) { delete smoother; }

}  // extern "C"
