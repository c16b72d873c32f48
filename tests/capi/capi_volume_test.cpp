// The C ABI of volume particles: the same meshes as the C++ API (with normals), per-particle
// radii and strengths, statistics, and statuses + messages for every kind of misuse, with
// outputs untouched on failure.
#include "particlemesh/particlemesh.h"

#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "particlemesh/volume/field.h"
#include "particlemesh/volume/polygonize.h"
#include "support/test_support.h"

using namespace particlemesh;

namespace {

std::vector<double> flat(const std::vector<Vec3>& v) {
  std::vector<double> out;
  for (const Vec3& p : v) out.insert(out.end(), {p.x, p.y, p.z});
  return out;
}
std::string last() { return pm_last_error_message(); }

struct Cloud {
  pm_cloud* handle = nullptr;
  explicit Cloud(const PointCloud& c) {
    const auto pos = flat(c.positions);
    EXPECT_EQ(pm_cloud_create(pos.data(), nullptr, c.size(), &handle), PM_OK);
  }
  ~Cloud() { pm_cloud_destroy(handle); }
};

// The mesh behind a handle, read back through the C ABI.
TriMesh read_back(const pm_mesh* m) {
  size_t nv = 0, nt = 0;
  EXPECT_EQ(pm_mesh_get_counts(m, &nv, &nt), PM_OK);
  std::vector<double> p(3 * nv);
  std::vector<float> n(3 * nv);
  std::vector<int32_t> t(3 * nt);
  int32_t has = 0;
  EXPECT_EQ(pm_mesh_has_normals(m, &has), PM_OK);
  EXPECT_EQ(has, nv > 0 ? 1 : 0);
  if (nv) {
    EXPECT_EQ(pm_mesh_copy_positions(m, p.data(), nv), PM_OK);
    EXPECT_EQ(pm_mesh_copy_normals_f32(m, n.data(), nv), PM_OK);
  }
  if (nt) EXPECT_EQ(pm_mesh_copy_triangles(m, t.data(), nt), PM_OK);
  TriMesh out;
  for (size_t i = 0; i < nv; ++i) {
    out.positions.push_back({p[3 * i], p[3 * i + 1], p[3 * i + 2]});
    out.normals.push_back({n[3 * i], n[3 * i + 1], n[3 * i + 2]});
  }
  for (size_t f = 0; f < nt; ++f) out.triangles.push_back({uint32_t(t[3 * f]), uint32_t(t[3 * f + 1]), uint32_t(t[3 * f + 2])});
  return out;
}

}  // namespace

TEST(CApiPolygonize, MatchesTheCppApi) {
  const PointCloud c = test::random_cloud(3000, 7, 1.4);
  Cloud cloud(c);
  pm_polygonize_options opt;
  pm_polygonize_options_init(&opt);
  EXPECT_EQ(opt.struct_size, sizeof(pm_polygonize_options));
  EXPECT_EQ(opt.kernel, PM_KERNEL_WYVILL);
  EXPECT_EQ(opt.radius, 0.0);
  EXPECT_EQ(opt.threshold, 0.0);
  EXPECT_EQ(opt.cell_size, 0.0);
  EXPECT_EQ(opt.max_grid_bytes, kDefaultMaxGridBytes);
  opt.kernel = PM_KERNEL_POLY6;
  opt.radius = 0.15;
  opt.threshold = 0.8;
  pm_mesh* mesh = nullptr;
  pm_polygonize_stats stats{};
  stats.struct_size = sizeof(stats);
  ASSERT_EQ(pm_polygonize_ex(cloud.handle, nullptr, nullptr, &opt, &mesh, &stats), PM_OK) << last();
  PolygonizeOptions o;
  o.kernel = Kernel::Poly6;
  o.radius = 0.15;
  o.threshold = 0.8;
  const PolygonizeResult ref = polygonize(c, o);
  const TriMesh got = read_back(mesh);
  ASSERT_EQ(got.positions.size(), ref.mesh.positions.size());
  EXPECT_TRUE(got.positions == ref.mesh.positions);
  EXPECT_TRUE(got.triangles == ref.mesh.triangles);
  for (size_t i = 0; i < got.normals.size(); ++i)
    ASSERT_NEAR(norm(got.normals[i] - ref.mesh.normals[i]), 0.0, 1e-6);
  EXPECT_EQ(stats.vertices, ref.stats.vertices);
  EXPECT_EQ(stats.triangles, ref.stats.triangles);
  EXPECT_EQ(stats.particles, c.size());
  EXPECT_EQ(stats.radius, 0.15);
  EXPECT_EQ(stats.threshold, 0.8);
  EXPECT_DOUBLE_EQ(stats.cell_size, 0.15 / 4);
  EXPECT_EQ(stats.sampled_blocks, ref.stats.sampled_blocks);
  EXPECT_EQ(stats.grid_bytes, ref.stats.grid_bytes);
  pm_topology_report rep{};
  rep.struct_size = sizeof(rep);
  ASSERT_EQ(pm_mesh_report(mesh, &rep), PM_OK);
  EXPECT_EQ(rep.closed, 1);
  EXPECT_EQ(rep.consistently_oriented, 1);
  pm_mesh_destroy(mesh);
}

TEST(CApiPolygonize, DefaultsRadiiAndStrengths) {
  const PointCloud c = test::random_cloud(2000, 3, 1.26);
  Cloud cloud(c);
  // NULL options: every default.
  pm_mesh* mesh = nullptr;
  ASSERT_EQ(pm_polygonize(cloud.handle, nullptr, nullptr, nullptr, &mesh), PM_OK) << last();
  const PolygonizeResult ref = polygonize(c);
  EXPECT_TRUE(read_back(mesh).triangles == ref.mesh.triangles);
  pm_mesh_destroy(mesh);
  // Per-particle radii and strengths.
  std::vector<double> radii(c.size()), strengths(c.size());
  for (size_t i = 0; i < c.size(); ++i) {
    radii[i] = 0.08 + 0.04 * double(i % 5) / 5;
    strengths[i] = 0.5 + double(i % 3);
  }
  pm_polygonize_options opt;
  pm_polygonize_options_init(&opt);
  opt.threshold = 1.2;
  ASSERT_EQ(pm_polygonize(cloud.handle, radii.data(), strengths.data(), &opt, &mesh), PM_OK) << last();
  PolygonizeOptions o;
  o.threshold = 1.2;
  o.radii = radii;
  o.strengths = strengths;
  const PolygonizeResult ref2 = polygonize(c, o);
  const TriMesh got = read_back(mesh);
  EXPECT_TRUE(got.triangles == ref2.mesh.triangles);
  EXPECT_TRUE(got.positions == ref2.mesh.positions);
  EXPECT_FALSE(ref2.mesh.triangles == ref.mesh.triangles);
  pm_mesh_destroy(mesh);
}

TEST(CApiPolygonize, MisuseGivesAStatusAMessageAndNoOutput) {
  const PointCloud c = test::random_cloud(500, 1);
  Cloud cloud(c);
  pm_mesh* const sentinel = reinterpret_cast<pm_mesh*>(0x1);
  pm_mesh* mesh = sentinel;
  pm_polygonize_options opt;
  pm_polygonize_options_init(&opt);

  EXPECT_EQ(pm_polygonize(nullptr, nullptr, nullptr, &opt, &mesh), PM_STATUS_INVALID_ARGUMENT);
  EXPECT_EQ(last(), "cloud is NULL");
  EXPECT_EQ(pm_polygonize(cloud.handle, nullptr, nullptr, &opt, nullptr), PM_STATUS_INVALID_ARGUMENT);
  EXPECT_EQ(last(), "out_mesh is NULL");

  opt.kernel = 7;
  EXPECT_EQ(pm_polygonize(cloud.handle, nullptr, nullptr, &opt, &mesh), PM_STATUS_INVALID_ARGUMENT);
  EXPECT_NE(last().find("kernel is 7"), std::string::npos) << last();
  pm_polygonize_options_init(&opt);

  std::vector<double> radii(c.size(), 0.1);
  radii[5] = std::nan("");
  EXPECT_EQ(pm_polygonize(cloud.handle, radii.data(), nullptr, &opt, &mesh), PM_STATUS_INVALID_ARGUMENT);
  EXPECT_NE(last().find("radii[5] is NaN"), std::string::npos) << last();
  std::vector<double> strengths(c.size(), 1.0);
  strengths[499] = INFINITY;
  EXPECT_EQ(pm_polygonize(cloud.handle, nullptr, strengths.data(), &opt, &mesh), PM_STATUS_INVALID_ARGUMENT);
  EXPECT_NE(last().find("strengths[499] is inf"), std::string::npos) << last();

  opt.radius = -3;
  EXPECT_EQ(pm_polygonize(cloud.handle, nullptr, nullptr, &opt, &mesh), PM_STATUS_INVALID_ARGUMENT);
  EXPECT_NE(last().find("radius is -3"), std::string::npos) << last();
  pm_polygonize_options_init(&opt);
  opt.cell_size = NAN;
  EXPECT_EQ(pm_polygonize(cloud.handle, nullptr, nullptr, &opt, &mesh), PM_STATUS_INVALID_ARGUMENT);
  EXPECT_NE(last().find("cell_size"), std::string::npos) << last();
  pm_polygonize_options_init(&opt);
  opt.threshold = -1;
  EXPECT_EQ(pm_polygonize(cloud.handle, nullptr, nullptr, &opt, &mesh), PM_STATUS_INVALID_ARGUMENT);
  pm_polygonize_options_init(&opt);
  opt.threads = -2;
  EXPECT_EQ(pm_polygonize(cloud.handle, nullptr, nullptr, &opt, &mesh), PM_STATUS_INVALID_ARGUMENT);

  pm_polygonize_options_init(&opt);
  opt.struct_size = 0;
  EXPECT_EQ(pm_polygonize(cloud.handle, nullptr, nullptr, &opt, &mesh), PM_STATUS_INVALID_ARGUMENT);
  EXPECT_NE(last().find("struct_size"), std::string::npos);

  pm_polygonize_options_init(&opt);
  opt.radius = 0.1;
  opt.threshold = 1;
  opt.cell_size = 1e-6;
  EXPECT_EQ(pm_polygonize(cloud.handle, nullptr, nullptr, &opt, &mesh), PM_STATUS_LIMIT_EXCEEDED);
  EXPECT_NE(last().find("max_grid_bytes"), std::string::npos) << last();
  opt.cell_size = 0.01;
  opt.max_grid_bytes = 4096;
  EXPECT_EQ(pm_polygonize(cloud.handle, nullptr, nullptr, &opt, &mesh), PM_STATUS_LIMIT_EXCEEDED);

  pm_polygonize_options_init(&opt);
  opt.progress = [](void*, const char*, double) { return 1; };
  EXPECT_EQ(pm_polygonize(cloud.handle, nullptr, nullptr, &opt, &mesh), PM_STATUS_CANCELLED);

  pm_polygonize_stats bad_stats{};
  pm_polygonize_options_init(&opt);
  EXPECT_EQ(pm_polygonize_ex(cloud.handle, nullptr, nullptr, &opt, &mesh, &bad_stats), PM_STATUS_INVALID_ARGUMENT);
  EXPECT_NE(last().find("out_stats"), std::string::npos);

  EXPECT_EQ(mesh, sentinel);  // never written on failure

  // An older caller's smaller options struct still works (fields after threads defaulted).
  pm_polygonize_options_init(&opt);
  opt.radius = 0.2;
  opt.threshold = 1;
  opt.struct_size = uint32_t(offsetof(pm_polygonize_options, max_grid_bytes));
  mesh = nullptr;
  EXPECT_EQ(pm_polygonize(cloud.handle, nullptr, nullptr, &opt, &mesh), PM_OK) << last();
  pm_mesh_destroy(mesh);
}

TEST(CApiPolygonize, LatticeField) {
  double v = 0;
  ASSERT_EQ(pm_lattice_field(PM_KERNEL_POLY6, 0.1, 0.05, &v), PM_OK);
  EXPECT_DOUBLE_EQ(v, lattice_field(Kernel::Poly6, 0.1, 0.05));
  EXPECT_EQ(pm_lattice_field(9, 0.1, 0.05, &v), PM_STATUS_INVALID_ARGUMENT);
  EXPECT_EQ(pm_lattice_field(PM_KERNEL_POLY6, -1, 0.05, &v), PM_STATUS_INVALID_ARGUMENT);
  EXPECT_EQ(pm_lattice_field(PM_KERNEL_POLY6, 0.1, 0.05, nullptr), PM_STATUS_INVALID_ARGUMENT);
}
