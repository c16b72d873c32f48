// The C ABI under hostile calls: every pointer argument NULL in turn, bad values
// named with their index, counts that disagree with the arrays, the resource limits, and
// cancellation: a status and a message naming the argument, the outputs untouched, and no
// leak (LeakSanitizer in the sanitizer build, scripts/sanitize.sh).
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <cstddef>
#include <functional>
#include <string>
#include <vector>

#include "particlemesh/particlemesh.h"
#include "particlemesh/sample/shapes.h"
#include "support/test_support.h"

using namespace particlemesh;

namespace {

std::string last() { return pm_last_error_message(); }

std::vector<double> flat(const std::vector<Vec3>& v) {
  std::vector<double> out;
  for (const Vec3& p : v) out.insert(out.end(), {p.x, p.y, p.z});
  return out;
}

// Each call passes NULL for `argument`: INVALID_ARGUMENT, and the message names it.
struct NullCase {
  const char* argument;
  std::function<pm_status()> call;
};

void expect_each_null_named(const std::vector<NullCase>& cases) {
  for (const NullCase& k : cases) {
    SCOPED_TRACE(std::string("argument ") + k.argument);
    EXPECT_EQ(k.call(), PM_STATUS_INVALID_ARGUMENT) << last();
    EXPECT_EQ(last().rfind(std::string(k.argument) + " is NULL", 0), 0u) << last();
  }
}

struct Handles {
  pm_cloud* cloud = nullptr;
  pm_mesh* mesh = nullptr;
  Handles() {
    const PointCloud c = fibonacci_sphere(200);
    const auto pos = flat(c.positions), nrm = flat(c.normals);
    EXPECT_EQ(pm_cloud_create(pos.data(), nrm.data(), c.size(), &cloud), PM_OK);
    EXPECT_EQ(pm_triangulate(cloud, nullptr, &mesh, nullptr), PM_OK) << last();
  }
  ~Handles() {
    pm_mesh_destroy(mesh);
    pm_cloud_destroy(cloud);
  }
};

}  // namespace

// Every pointer argument of every entry point, NULL in turn: INVALID_ARGUMENT naming it.
TEST(CApiHostile, EveryNullPointerIsNamed) {
  Handles h;
  const double pts[] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
  const float ptsf[] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
  const int32_t tri[] = {0, 1, 2};
  const float values[] = {1, 2, 3};
  pm_cloud* c = reinterpret_cast<pm_cloud*>(0x1);
  pm_mesh* m = reinterpret_cast<pm_mesh*>(0x1);
  size_t n = 7;
  int32_t i32 = 7;
  double d = 7;
  float buf[3 * 256];
  double dbuf[3 * 256];
  int32_t ibuf[3 * 512];
  const char* name = nullptr;
  double* const kUntouched = reinterpret_cast<double*>(0x7);
  double* dptr = kUntouched;
  uint32_t* uptr = reinterpret_cast<uint32_t*>(0x7);
  float* fptr = reinterpret_cast<float*>(0x7);
  pm_topology_report report{};
  report.struct_size = sizeof report;
  // An attribute "a", so that the attribute calls get as far as their output pointers.
  const std::vector<float> a200(200, 1.0f);
  ASSERT_EQ(pm_mesh_set_attribute(h.mesh, "a", 1, a200.data(), 200), PM_OK) << last();
  const std::vector<NullCase> cases = {
      {"positions", [&] { return pm_cloud_create(nullptr, nullptr, 3, &c); }},
      {"out_cloud", [&] { return pm_cloud_create(pts, nullptr, 3, nullptr); }},
      {"positions", [&] { return pm_cloud_create_f32(nullptr, nullptr, 3, &c); }},
      {"out_cloud", [&] { return pm_cloud_create_f32(ptsf, nullptr, 3, nullptr); }},
      {"path", [&] { return pm_cloud_read(nullptr, &c); }},
      {"out_cloud", [&] { return pm_cloud_read("x.ply", nullptr); }},
      {"cloud", [&] { return pm_cloud_get_count(nullptr, &n); }},
      {"out_count", [&] { return pm_cloud_get_count(h.cloud, nullptr); }},
      {"cloud", [&] { return pm_cloud_has_normals(nullptr, &i32); }},
      {"out_has_normals", [&] { return pm_cloud_has_normals(h.cloud, nullptr); }},
      {"cloud", [&] { return pm_cloud_copy_positions_f32(nullptr, buf, 256); }},
      {"out", [&] { return pm_cloud_copy_positions_f32(h.cloud, nullptr, 256); }},
      {"cloud", [&] { return pm_cloud_copy_normals_f32(nullptr, buf, 256); }},
      {"out", [&] { return pm_cloud_copy_normals_f32(h.cloud, nullptr, 256); }},
      {"cloud", [&] { return pm_cloud_copy_positions(nullptr, dbuf, 256); }},
      {"out", [&] { return pm_cloud_copy_positions(h.cloud, nullptr, 256); }},
      {"cloud", [&] { return pm_cloud_copy_normals(nullptr, dbuf, 256); }},
      {"out", [&] { return pm_cloud_copy_normals(h.cloud, nullptr, 256); }},
      {"cloud", [&] { return pm_estimate_spacing(nullptr, 0, &d); }},
      {"out_spacing", [&] { return pm_estimate_spacing(h.cloud, 0, nullptr); }},
      {"cloud", [&] { return pm_estimate_spacing_sampled(nullptr, 100, 0, &d); }},
      {"out_spacing", [&] { return pm_estimate_spacing_sampled(h.cloud, 100, 0, nullptr); }},
      {"cloud", [&] { return pm_cloud_thin(nullptr, 0.1, reinterpret_cast<uint32_t*>(ibuf), 512, &n); }},
      {"out_indices", [&] { return pm_cloud_thin(h.cloud, 0.1, nullptr, 512, &n); }},
      {"out_count", [&] { return pm_cloud_thin(h.cloud, 0.1, reinterpret_cast<uint32_t*>(ibuf), 512, nullptr); }},
      {"triangles", [&] { return pm_triangle_edges(nullptr, 1, 3, 0, reinterpret_cast<uint32_t*>(ibuf), 3, reinterpret_cast<uint32_t*>(ibuf) + 6, &n); }},
      {"out_edges", [&] { return pm_triangle_edges(reinterpret_cast<const uint32_t*>(tri), 1, 3, 0, nullptr, 3, reinterpret_cast<uint32_t*>(ibuf), &n); }},
      {"out_corner_edges", [&] { return pm_triangle_edges(reinterpret_cast<const uint32_t*>(tri), 1, 3, 0, reinterpret_cast<uint32_t*>(ibuf), 3, nullptr, &n); }},
      {"mesh", [&] { return pm_mesh_ray_crossings(nullptr, dbuf, 1, 0, reinterpret_cast<uint64_t*>(ibuf)); }},
      {"points", [&] { return pm_mesh_ray_crossings(h.mesh, nullptr, 1, 0, reinterpret_cast<uint64_t*>(ibuf)); }},
      {"out_crossings", [&] { return pm_mesh_ray_crossings(h.mesh, dbuf, 1, 0, nullptr); }},
      {"mesh", [&] { return pm_mesh_components(nullptr, &n, nullptr, nullptr, nullptr, nullptr, 0); }},
      {"out_component_count", [&] { return pm_mesh_components(h.mesh, nullptr, nullptr, nullptr, nullptr, nullptr, 0); }},
      {"mesh", [&] { return pm_mesh_get_not_read_count(nullptr, &n); }},
      {"out_count", [&] { return pm_mesh_get_not_read_count(h.mesh, nullptr); }},
      {"mesh", [&] { return pm_mesh_get_not_read(nullptr, 0, &name); }},
      {"out_text", [&] { return pm_mesh_get_not_read(h.mesh, 0, nullptr); }},
      {"out_edge_count", [&] { return pm_triangle_edges(reinterpret_cast<const uint32_t*>(tri), 1, 3, 0, reinterpret_cast<uint32_t*>(ibuf), 3, reinterpret_cast<uint32_t*>(ibuf) + 6, nullptr); }},
      {"path", [&] { return pm_frame_collection_read(nullptr, reinterpret_cast<pm_frame_collection**>(&m)); }},
      {"out_collection", [&] { return pm_frame_collection_read("x.pvd", nullptr); }},
      {"collection", [&] { return pm_frame_collection_get_count(nullptr, &n); }},
      {"collection", [&] { return pm_frame_collection_get_frame(nullptr, 0, &d, &name); }},
      {"cloud", [&] { return pm_triangulate(nullptr, nullptr, &m, nullptr); }},
      {"out_mesh", [&] { return pm_triangulate(h.cloud, nullptr, nullptr, nullptr); }},
      {"out_mesh", [&] { return pm_mesh_create(pts, 3, tri, 1, nullptr, nullptr); }},
      {"positions", [&] { return pm_mesh_create(nullptr, 3, tri, 1, nullptr, &m); }},
      {"triangles", [&] { return pm_mesh_create(pts, 3, nullptr, 1, nullptr, &m); }},
      {"path", [&] { return pm_mesh_read(nullptr, &m); }},
      {"out_mesh", [&] { return pm_mesh_read("x.ply", nullptr); }},
      {"mesh", [&] { return pm_mesh_write(nullptr, "x.ply"); }},
      {"path", [&] { return pm_mesh_write(h.mesh, nullptr); }},
      {"mesh", [&] { return pm_mesh_get_counts(nullptr, &n, &n); }},
      {"mesh", [&] { return pm_mesh_has_normals(nullptr, &i32); }},
      {"out_has_normals", [&] { return pm_mesh_has_normals(h.mesh, nullptr); }},
      {"mesh", [&] { return pm_mesh_copy_positions(nullptr, dbuf, 256); }},
      {"out", [&] { return pm_mesh_copy_positions(h.mesh, nullptr, 256); }},
      {"mesh", [&] { return pm_mesh_copy_positions_f32(nullptr, buf, 256); }},
      {"out", [&] { return pm_mesh_copy_positions_f32(h.mesh, nullptr, 256); }},
      {"mesh", [&] { return pm_mesh_copy_normals_f32(nullptr, buf, 256); }},
      {"out", [&] { return pm_mesh_copy_normals_f32(h.mesh, nullptr, 256); }},
      {"mesh", [&] { return pm_mesh_copy_normals(nullptr, dbuf, 256); }},
      {"out", [&] { return pm_mesh_copy_normals(h.mesh, nullptr, 256); }},
      {"mesh", [&] { return pm_mesh_copy_triangles(nullptr, ibuf, 512); }},
      {"out", [&] { return pm_mesh_copy_triangles(h.mesh, nullptr, 512); }},
      {"mesh", [&] { return pm_mesh_lend_arrays(nullptr, &dptr, &dptr, &uptr); }},
      {"out_positions", [&] { return pm_mesh_lend_arrays(h.mesh, nullptr, &dptr, &uptr); }},
      {"out_normals", [&] { return pm_mesh_lend_arrays(h.mesh, &dptr, nullptr, &uptr); }},
      {"out_triangles", [&] { return pm_mesh_lend_arrays(h.mesh, &dptr, &dptr, nullptr); }},
      {"mesh", [&] { return pm_mesh_report(nullptr, &report); }},
      {"out_report", [&] { return pm_mesh_report(h.mesh, nullptr); }},
      {"mesh", [&] { return pm_mesh_set_attribute(nullptr, "a", 1, values, 3); }},
      {"name", [&] { return pm_mesh_set_attribute(h.mesh, nullptr, 1, values, 200); }},
      {"values", [&] { return pm_mesh_set_attribute(h.mesh, "a", 1, nullptr, 200); }},
      {"mesh", [&] { return pm_mesh_get_attribute_components(nullptr, "a", &i32); }},
      {"name", [&] { return pm_mesh_get_attribute_components(h.mesh, nullptr, &i32); }},
      {"out_components", [&] { return pm_mesh_get_attribute_components(h.mesh, "a", nullptr); }},
      {"mesh", [&] { return pm_mesh_copy_attribute(nullptr, "a", buf, 256); }},
      {"name", [&] { return pm_mesh_copy_attribute(h.mesh, nullptr, buf, 256); }},
      {"out", [&] { return pm_mesh_copy_attribute(h.mesh, "a", nullptr, 256); }},
      {"mesh", [&] { return pm_mesh_lend_attribute(nullptr, "a", &fptr); }},
      {"name", [&] { return pm_mesh_lend_attribute(h.mesh, nullptr, &fptr); }},
      {"out_values", [&] { return pm_mesh_lend_attribute(h.mesh, "a", nullptr); }},
      {"mesh", [&] { return pm_mesh_get_attribute_count(nullptr, &n); }},
      {"out_count", [&] { return pm_mesh_get_attribute_count(h.mesh, nullptr); }},
      {"mesh", [&] { return pm_mesh_get_attribute_name(nullptr, 0, &name); }},
      {"out_name", [&] { return pm_mesh_get_attribute_name(h.mesh, 0, nullptr); }},
      {"mesh", [&] { return pm_mesh_set_corner_attribute(nullptr, "uv", 1, values, 3); }},
      {"name", [&] { return pm_mesh_set_corner_attribute(h.mesh, nullptr, 1, values, 1); }},
      {"mesh", [&] { return pm_mesh_get_corner_attribute_count(nullptr, &n); }},
      {"out_count", [&] { return pm_mesh_get_corner_attribute_count(h.mesh, nullptr); }},
      {"mesh", [&] { return pm_mesh_get_corner_attribute_name(nullptr, 0, &name); }},
      {"out_name", [&] { return pm_mesh_get_corner_attribute_name(h.mesh, 0, nullptr); }},
      {"mesh", [&] { return pm_mesh_get_corner_attribute_components(nullptr, "uv", &i32); }},
      {"name", [&] { return pm_mesh_get_corner_attribute_components(h.mesh, nullptr, &i32); }},
      {"mesh", [&] { return pm_mesh_copy_corner_attribute(nullptr, "uv", buf, 256); }},
      {"name", [&] { return pm_mesh_copy_corner_attribute(h.mesh, nullptr, buf, 256); }},
      {"cloud", [&] { return pm_cloud_set_attribute(nullptr, "a", 1, values, 3); }},
      {"name", [&] { return pm_cloud_set_attribute(h.cloud, nullptr, 1, values, 200); }},
      {"values", [&] { return pm_cloud_set_attribute(h.cloud, "a", 1, nullptr, 200); }},
      {"mesh", [&] { return pm_smooth(nullptr, nullptr, &m); }},
      {"out_mesh", [&] { return pm_smooth(h.mesh, nullptr, nullptr); }},
  };
  expect_each_null_named(cases);
  EXPECT_EQ(c, reinterpret_cast<pm_cloud*>(0x1));
  EXPECT_EQ(m, reinterpret_cast<pm_mesh*>(0x1));
  EXPECT_EQ(n, 7u);
  EXPECT_EQ(i32, 7);
  EXPECT_EQ(d, 7);
  EXPECT_EQ(name, nullptr);
  EXPECT_EQ(dptr, kUntouched);
  EXPECT_EQ(uptr, reinterpret_cast<uint32_t*>(0x7));
  EXPECT_EQ(fptr, reinterpret_cast<float*>(0x7));
  // Destroying NULL is a no-op.
  pm_cloud_destroy(nullptr);
  pm_mesh_destroy(nullptr);
}

// The same for the volume, ray-casting and cloud-attribute entry points.
TEST(CApiHostile, EveryNullPointerIsNamedVolumeRaysAndAttributes) {
  Handles h;
  const std::vector<float> a200(200, 1.0f);
  ASSERT_EQ(pm_cloud_set_attribute(h.cloud, "a", 1, a200.data(), 200), PM_OK) << last();
  pm_field* field = nullptr;
  ASSERT_EQ(pm_field_create(h.cloud, nullptr, nullptr, nullptr, &field), PM_OK) << last();
  const double origin[] = {0, 0, -5}, direction[] = {0, 0, 1};
  pm_ray_hits* hits = nullptr;
  ASSERT_EQ(pm_raycast_all(field, origin, direction, 1, nullptr, &hits), PM_OK) << last();
  pm_mesh* m = reinterpret_cast<pm_mesh*>(0x1);
  pm_field* f = reinterpret_cast<pm_field*>(0x1);
  pm_ray_hits* rh = reinterpret_cast<pm_ray_hits*>(0x1);
  size_t n = 7;
  int32_t i32 = 7;
  double d = 7, dbuf[3 * 256];
  float buf[256];
  uint64_t offsets[8];
  const char* name = nullptr;
  const std::vector<NullCase> cases = {
      {"cloud", [&] { return pm_polygonize(nullptr, nullptr, nullptr, nullptr, &m); }},
      {"out_mesh", [&] { return pm_polygonize(h.cloud, nullptr, nullptr, nullptr, nullptr); }},
      {"out_value", [&] { return pm_lattice_field(PM_KERNEL_WYVILL, 1.0, 0.5, nullptr); }},
      {"cloud", [&] { return pm_default_radius(nullptr, nullptr, PM_KERNEL_WYVILL, 0, &d); }},
      {"out_radius", [&] { return pm_default_radius(h.cloud, nullptr, PM_KERNEL_WYVILL, 0, nullptr); }},
      {"cloud", [&] { return pm_field_create(nullptr, nullptr, nullptr, nullptr, &f); }},
      {"out_field", [&] { return pm_field_create(h.cloud, nullptr, nullptr, nullptr, nullptr); }},
      {"field", [&] { return pm_field_get_params(nullptr, &d, &d); }},
      {"field", [&] { return pm_field_values(nullptr, origin, 1, dbuf); }},
      {"points", [&] { return pm_field_values(field, nullptr, 1, dbuf); }},
      {"out_values", [&] { return pm_field_values(field, origin, 1, nullptr); }},
      {"field", [&] { return pm_raycast_first(nullptr, origin, direction, 1, nullptr, dbuf, nullptr, nullptr, nullptr, &n); }},
      {"origins", [&] { return pm_raycast_first(field, nullptr, direction, 1, nullptr, dbuf, nullptr, nullptr, nullptr, &n); }},
      {"directions", [&] { return pm_raycast_first(field, origin, nullptr, 1, nullptr, dbuf, nullptr, nullptr, nullptr, &n); }},
      {"field", [&] { return pm_raycast_all(nullptr, origin, direction, 1, nullptr, &rh); }},
      {"origins", [&] { return pm_raycast_all(field, nullptr, direction, 1, nullptr, &rh); }},
      {"directions", [&] { return pm_raycast_all(field, origin, nullptr, 1, nullptr, &rh); }},
      {"out_hits", [&] { return pm_raycast_all(field, origin, direction, 1, nullptr, nullptr); }},
      {"a", [&] { return pm_raycast_csg(nullptr, field, PM_CSG_UNION, origin, direction, 1, nullptr, &rh); }},
      {"b", [&] { return pm_raycast_csg(field, nullptr, PM_CSG_UNION, origin, direction, 1, nullptr, &rh); }},
      {"out_hits", [&] { return pm_raycast_csg(field, field, PM_CSG_UNION, origin, direction, 1, nullptr, nullptr); }},
      {"hits", [&] { return pm_ray_hits_get_counts(nullptr, &n, &n); }},
      {"hits", [&] { return pm_ray_hits_copy_offsets(nullptr, offsets, 8); }},
      {"out_offsets", [&] { return pm_ray_hits_copy_offsets(hits, nullptr, 8); }},
      {"hits", [&] { return pm_ray_hits_copy_starts_inside(nullptr, &i32, 1); }},
      {"out", [&] { return pm_ray_hits_copy_starts_inside(hits, nullptr, 1); }},
      {"hits", [&] { return pm_ray_hits_copy(nullptr, dbuf, nullptr, nullptr, nullptr, 8); }},
      {"cloud", [&] { return pm_cloud_get_attribute_count(nullptr, &n); }},
      {"out_count", [&] { return pm_cloud_get_attribute_count(h.cloud, nullptr); }},
      {"cloud", [&] { return pm_cloud_get_attribute_name(nullptr, 0, &name); }},
      {"out_name", [&] { return pm_cloud_get_attribute_name(h.cloud, 0, nullptr); }},
      {"cloud", [&] { return pm_cloud_get_attribute_components(nullptr, "a", &i32); }},
      {"name", [&] { return pm_cloud_get_attribute_components(h.cloud, nullptr, &i32); }},
      {"out_components", [&] { return pm_cloud_get_attribute_components(h.cloud, "a", nullptr); }},
      {"cloud", [&] { return pm_cloud_copy_attribute(nullptr, "a", buf, 256); }},
      {"name", [&] { return pm_cloud_copy_attribute(h.cloud, nullptr, buf, 256); }},
      {"out", [&] { return pm_cloud_copy_attribute(h.cloud, "a", nullptr, 256); }},
      {"cloud", [&] { return pm_cloud_get_not_read_count(nullptr, &n); }},
      {"out_count", [&] { return pm_cloud_get_not_read_count(h.cloud, nullptr); }},
      {"cloud", [&] { return pm_cloud_get_not_read(nullptr, 0, &name); }},
      {"out_text", [&] { return pm_cloud_get_not_read(h.cloud, 0, nullptr); }},
  };
  expect_each_null_named(cases);
  EXPECT_EQ(m, reinterpret_cast<pm_mesh*>(0x1));
  EXPECT_EQ(f, reinterpret_cast<pm_field*>(0x1));
  EXPECT_EQ(rh, reinterpret_cast<pm_ray_hits*>(0x1));
  EXPECT_EQ(n, 7u);
  EXPECT_EQ(i32, 7);
  EXPECT_EQ(d, 7);
  EXPECT_EQ(name, nullptr);
  pm_ray_hits_destroy(hits);
  pm_field_destroy(field);
  pm_field_destroy(nullptr);
  pm_ray_hits_destroy(nullptr);
}

// Bad values name the argument and the index; nothing is created.
TEST(CApiHostile, BadValuesNameArgumentAndIndex) {
  const double inf = INFINITY;
  pm_cloud* c = reinterpret_cast<pm_cloud*>(0x1);
  std::vector<double> p(30, 0.5);
  p[3 * 7 + 2] = inf;
  EXPECT_EQ(pm_cloud_create(p.data(), nullptr, 10, &c), PM_STATUS_INVALID_INPUT);
  EXPECT_NE(last().find("positions[7].z"), std::string::npos) << last();
  std::vector<float> pf(30, 0.5f);
  pf[3 * 4] = NAN;
  EXPECT_EQ(pm_cloud_create_f32(pf.data(), nullptr, 10, &c), PM_STATUS_INVALID_INPUT);
  EXPECT_NE(last().find("positions[4].x"), std::string::npos) << last();
  std::vector<double> n(30, 0.0);
  n[3 * 9 + 1] = NAN;
  p[3 * 7 + 2] = 0.25;
  EXPECT_EQ(pm_cloud_create(p.data(), n.data(), 10, &c), PM_STATUS_INVALID_INPUT);
  EXPECT_NE(last().find("normals[9]"), std::string::npos) << last();
  EXPECT_EQ(c, reinterpret_cast<pm_cloud*>(0x1));

  pm_mesh* m = reinterpret_cast<pm_mesh*>(0x1);
  const double tri_pts[] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
  const double bad_normals[] = {0, 0, 1, 0, 0, 1, 0, NAN, 1};
  const int32_t tri[] = {0, 1, 2};
  EXPECT_EQ(pm_mesh_create(tri_pts, 3, tri, 1, bad_normals, &m), PM_STATUS_INVALID_INPUT);
  EXPECT_NE(last().find("normals[2]"), std::string::npos) << last();
  const int32_t negative[] = {0, -1, 2};
  EXPECT_EQ(pm_mesh_create(tri_pts, 3, negative, 1, nullptr, &m), PM_STATUS_INVALID_INPUT);
  EXPECT_NE(last().find("triangles[0]"), std::string::npos) << last();
  EXPECT_EQ(m, reinterpret_cast<pm_mesh*>(0x1));

  // Options: radii and factors <= 0, NaN, unknown enum values.
  Handles h;
  pm_triangulate_options o;
  auto expect_bad = [&](const char* field) {
    pm_mesh* out = reinterpret_cast<pm_mesh*>(0x2);
    EXPECT_EQ(pm_triangulate(h.cloud, &o, &out, nullptr), PM_STATUS_INVALID_ARGUMENT) << field;
    EXPECT_NE(last().find(field), std::string::npos) << last();
    EXPECT_EQ(out, reinterpret_cast<pm_mesh*>(0x2));
    pm_triangulate_options_init(&o);
  };
  pm_triangulate_options_init(&o);
  o.spacing = -0.1;
  expect_bad("spacing");
  o.spacing = NAN;
  expect_bad("spacing");
  o.max_edge_factor = 0;
  expect_bad("edge");
  o.max_edge_factor = INFINITY;
  expect_bad("edge");
  o.normals = 17;
  expect_bad("normals");
  o.flags = 0x80000000u;
  expect_bad("flags");
}

// Counts that disagree with the arrays they describe.
TEST(CApiHostile, CountsThatDisagree) {
  Handles h;
  size_t nv = 0;
  ASSERT_EQ(pm_mesh_get_counts(h.mesh, &nv, nullptr), PM_OK);
  std::vector<float> values(nv + 1, 1.0f);
  EXPECT_EQ(pm_mesh_set_attribute(h.mesh, "v", 1, values.data(), nv + 1), PM_STATUS_INVALID_ARGUMENT);
  EXPECT_NE(last().find("vertex_count is " + std::to_string(nv + 1)), std::string::npos) << last();
  EXPECT_EQ(pm_cloud_set_attribute(h.cloud, "v", 1, values.data(), 199), PM_STATUS_INVALID_ARGUMENT);
  EXPECT_NE(last().find("vertex_count is 199"), std::string::npos) << last();
  size_t count = 9;
  ASSERT_EQ(pm_mesh_get_attribute_count(h.mesh, &count), PM_OK);
  EXPECT_EQ(count, 0u);  // nothing half-set
  // A capacity short by one: refused, the buffer untouched.
  std::vector<float> out(3 * nv, -5.0f);
  EXPECT_EQ(pm_mesh_copy_positions_f32(h.mesh, out.data(), nv - 1), PM_STATUS_INVALID_ARGUMENT);
  EXPECT_NE(last().find("capacity " + std::to_string(nv - 1)), std::string::npos) << last();
  EXPECT_EQ(out[0], -5.0f);
  // An index past the end.
  const char* name = nullptr;
  EXPECT_EQ(pm_mesh_get_attribute_name(h.mesh, 0, &name), PM_STATUS_INVALID_ARGUMENT);
  EXPECT_NE(last().find("index 0 is out of range"), std::string::npos) << last();
  // A count beyond what the ABI can index.
  pm_cloud* c = reinterpret_cast<pm_cloud*>(0x1);
  const double one[] = {0, 0, 0};
  EXPECT_EQ(pm_cloud_create(one, nullptr, size_t(1) << 40, &c), PM_STATUS_LIMIT_EXCEEDED);
  EXPECT_EQ(c, reinterpret_cast<pm_cloud*>(0x1));
}

// The limits through the C ABI: the triplet cap and the smoothing triangle budget.
TEST(CApiHostile, LimitsAreSettableThroughTheAbi) {
  const PointCloud s = fibonacci_sphere(3000);
  const auto pos = flat(s.positions);
  pm_cloud* cloud = nullptr;
  ASSERT_EQ(pm_cloud_create(pos.data(), nullptr, s.size(), &cloud), PM_OK);
  pm_triangulate_options o;
  pm_triangulate_options_init(&o);
  EXPECT_EQ(o.max_triplets_per_point, 4096u);
  o.max_edge_factor = 12;
  o.max_neighbors = 100000;
  pm_mesh* mesh = reinterpret_cast<pm_mesh*>(0x2);
  pm_triangulate_stats stats{};
  stats.struct_size = sizeof stats;
  stats.triplets = 77;
  EXPECT_EQ(pm_triangulate(cloud, &o, &mesh, &stats), PM_STATUS_LIMIT_EXCEEDED);
  EXPECT_NE(last().find("max_triplets_per_point = 4096"), std::string::npos) << last();
  EXPECT_EQ(mesh, reinterpret_cast<pm_mesh*>(0x2));
  EXPECT_EQ(stats.triplets, 77u);  // untouched
  // The default factor: the count comes back in the stats; a limit just below it fails.
  pm_triangulate_options_init(&o);
  o.flags = PM_TRIANGULATE_RAW;
  ASSERT_EQ(pm_triangulate(cloud, &o, &mesh, &stats), PM_OK) << last();
  EXPECT_GT(stats.triplets, stats.candidates);
  pm_mesh_destroy(mesh);
  o.max_triplets_per_point = uint32_t(stats.triplets / s.size());
  mesh = reinterpret_cast<pm_mesh*>(0x2);
  EXPECT_EQ(pm_triangulate(cloud, &o, &mesh, nullptr), PM_STATUS_LIMIT_EXCEEDED);
  EXPECT_EQ(mesh, reinterpret_cast<pm_mesh*>(0x2));
  // The neighbour cap: a caller's spacing far below the truth.
  pm_triangulate_options_init(&o);
  o.spacing = 0.5;
  EXPECT_EQ(pm_triangulate(cloud, &o, &mesh, nullptr), PM_STATUS_LIMIT_EXCEEDED);
  EXPECT_NE(last().find("neighbours"), std::string::npos) << last();

  ASSERT_EQ(pm_triangulate(cloud, nullptr, &mesh, nullptr), PM_OK);
  size_t nt = 0;
  ASSERT_EQ(pm_mesh_get_counts(mesh, nullptr, &nt), PM_OK);
  pm_smooth_options so;
  pm_smooth_options_init(&so);
  so.levels = 10;
  pm_mesh* smooth = reinterpret_cast<pm_mesh*>(0x3);
  EXPECT_EQ(pm_smooth(mesh, &so, &smooth), PM_STATUS_LIMIT_EXCEEDED);
  EXPECT_NE(last().find("max_triangles"), std::string::npos) << last();
  so.levels = 11;
  EXPECT_EQ(pm_smooth(mesh, &so, &smooth), PM_STATUS_INVALID_ARGUMENT);
  so.levels = 1;
  so.max_triangles = 4 * nt - 1;
  EXPECT_EQ(pm_smooth(mesh, &so, &smooth), PM_STATUS_LIMIT_EXCEEDED);
  EXPECT_EQ(smooth, reinterpret_cast<pm_mesh*>(0x3));
  pm_mesh_destroy(mesh);
  pm_cloud_destroy(cloud);
}

namespace {

struct CancelAfter {
  std::chrono::steady_clock::time_point start = std::chrono::steady_clock::now();
  double after = 0;  ///< seconds
  std::chrono::steady_clock::time_point requested{};
  int calls_after = 0;
};

int cancel_after(void* user, const char*, double) {
  auto* c = static_cast<CancelAfter*>(user);
  const auto now = std::chrono::steady_clock::now();
  if (c->requested != std::chrono::steady_clock::time_point{}) {
    ++c->calls_after;
    return 1;
  }
  if (std::chrono::duration<double>(now - c->start).count() < c->after) return 0;
  c->requested = now;
  return 1;
}

double since(std::chrono::steady_clock::time_point t) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t).count();
}

}  // namespace

// Cancelling mid-way: PM_STATUS_CANCELLED promptly, outputs untouched, the callback not
// called again, nothing leaked (LeakSanitizer).
TEST(CApiHostile, CancelledCallsLeaveOutputsUntouched) {
  // Long enough for the latest request to come mid-call (100k under ASan: the same paths).
  const PointCloud s = fibonacci_sphere(test::kSanitized ? 100000 : 300000);
  const auto pos = flat(s.positions);
  pm_cloud* cloud = nullptr;
  ASSERT_EQ(pm_cloud_create(pos.data(), nullptr, s.size(), &cloud), PM_OK);
  for (double after : {0.05, 0.3, 0.8}) {
    for (uint32_t flags : {0u, uint32_t(PM_TRIANGULATE_RAW)}) {
      CancelAfter state;
      state.after = after;
      pm_triangulate_options o;
      pm_triangulate_options_init(&o);
      o.flags = flags;
      o.progress = cancel_after;
      o.progress_user_data = &state;
      pm_mesh* mesh = reinterpret_cast<pm_mesh*>(0x2);
      pm_triangulate_stats stats{};
      stats.struct_size = sizeof stats;
      stats.points = 12345;
      const pm_status st = pm_triangulate(cloud, &o, &mesh, &stats);
      if (st == PM_OK) {  // finished before the request (a fast machine)
        pm_mesh_destroy(mesh);
        continue;
      }
      EXPECT_EQ(st, PM_STATUS_CANCELLED) << last();
      EXPECT_LT(since(state.requested), 3.0);
      EXPECT_EQ(state.calls_after, 0);
      EXPECT_EQ(mesh, reinterpret_cast<pm_mesh*>(0x2));
      EXPECT_EQ(stats.points, 12345u);
    }
  }
  pm_mesh* mesh = nullptr;
  ASSERT_EQ(pm_triangulate(cloud, nullptr, &mesh, nullptr), PM_OK);
  for (double after : {0.05, 0.5}) {
    CancelAfter state;
    state.after = after;
    pm_smooth_options so;
    pm_smooth_options_init(&so);
    so.levels = 2;
    so.progress = cancel_after;
    so.progress_user_data = &state;
    pm_mesh* smooth = reinterpret_cast<pm_mesh*>(0x3);
    const pm_status st = pm_smooth(mesh, &so, &smooth);
    if (st == PM_OK) {
      pm_mesh_destroy(smooth);
      continue;
    }
    EXPECT_EQ(st, PM_STATUS_CANCELLED) << last();
    EXPECT_LT(since(state.requested), 3.0);
    EXPECT_EQ(smooth, reinterpret_cast<pm_mesh*>(0x3));
  }
  pm_mesh_destroy(mesh);
  pm_cloud_destroy(cloud);
}
