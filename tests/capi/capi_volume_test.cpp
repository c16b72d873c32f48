// The C ABI of volume particles: the same meshes as the C++ API (with normals), per-particle
// radii and strengths, statistics, and statuses + messages for every kind of misuse, with
// outputs untouched on failure.
#include "particlemesh/particlemesh.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
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

// The appended fields: anisotropic kernels, dropping small pieces, Taubin smoothing. Their
// defaults are the C++ defaults (all off); a caller with the struct as it was before them
// (struct_size up to progress_user_data) gets those defaults; a bad value is named.
TEST(CApiPolygonize, AnisotropicKernelsPiecesAndSmoothing) {
  const PointCloud c = test::random_cloud(3000, 7, 1.4);
  Cloud cloud(c);
  pm_polygonize_options opt;
  pm_polygonize_options_init(&opt);
  const PolygonizeOptions d;
  EXPECT_EQ(opt.anisotropic, 0);
  EXPECT_EQ(opt.aniso_neighbor_radius, d.anisotropy.neighbor_radius);
  EXPECT_EQ(opt.aniso_max_stretch, d.anisotropy.max_stretch);
  EXPECT_EQ(opt.aniso_min_neighbors, d.anisotropy.min_neighbors);
  EXPECT_EQ(opt.aniso_smoothing, d.anisotropy.smoothing);
  EXPECT_EQ(opt.min_component_volume, 0.0);
  EXPECT_EQ(opt.min_component_particles, 0.0);
  EXPECT_EQ(opt.taubin_iterations, 0);
  EXPECT_EQ(opt.taubin_lambda, d.surface_smoothing.lambda);
  EXPECT_EQ(opt.taubin_mu, d.surface_smoothing.mu);
  opt.anisotropic = 1;
  opt.aniso_max_stretch = 3;
  opt.aniso_min_neighbors = 20;
  opt.aniso_smoothing = 0.2;
  opt.min_component_particles = 5;
  opt.taubin_iterations = 3;
  pm_mesh* mesh = nullptr;
  pm_polygonize_stats stats{};
  stats.struct_size = sizeof(stats);
  ASSERT_EQ(pm_polygonize_ex(cloud.handle, nullptr, nullptr, &opt, &mesh, &stats), PM_OK) << last();
  PolygonizeOptions o;
  o.anisotropy.enabled = true;
  o.anisotropy.max_stretch = 3;
  o.anisotropy.min_neighbors = 20;
  o.anisotropy.smoothing = 0.2;
  o.min_component_particles = 5;
  o.surface_smoothing.iterations = 3;
  const PolygonizeResult ref = polygonize(c, o);
  const TriMesh got = read_back(mesh);
  EXPECT_TRUE(got.positions == ref.mesh.positions);
  EXPECT_TRUE(got.triangles == ref.mesh.triangles);
  EXPECT_EQ(stats.anisotropic, 1);
  EXPECT_EQ(stats.anisotropic_particles, ref.stats.anisotropic_particles);
  EXPECT_GT(stats.anisotropic_particles, c.size() / 2);
  EXPECT_EQ(stats.components_removed, ref.stats.components_removed);
  EXPECT_EQ(stats.threshold, ref.stats.threshold);
  pm_mesh_destroy(mesh);

  // The struct as callers built before these fields knew it: all of them at their defaults.
  opt.struct_size = uint32_t(offsetof(pm_polygonize_options, progress_user_data) + sizeof(void*));
  ASSERT_EQ(pm_polygonize_ex(cloud.handle, nullptr, nullptr, &opt, &mesh, &stats), PM_OK) << last();
  EXPECT_EQ(stats.anisotropic, 0);
  EXPECT_TRUE(read_back(mesh).triangles == polygonize(c).mesh.triangles);
  pm_mesh_destroy(mesh);
  // And an old stats struct: the appended statistics are left alone.
  pm_polygonize_stats old{};
  old.struct_size = uint32_t(offsetof(pm_polygonize_stats, anisotropic));
  old.anisotropic = 77;
  opt.struct_size = sizeof(opt);
  ASSERT_EQ(pm_polygonize_ex(cloud.handle, nullptr, nullptr, &opt, &mesh, &old), PM_OK) << last();
  EXPECT_EQ(old.anisotropic, 77);
  EXPECT_EQ(old.triangles, ref.stats.triangles);
  pm_mesh_destroy(mesh);

  struct Bad {
    void (*set)(pm_polygonize_options&);
    const char* named;
  };
  const Bad bad[] = {
      {[](pm_polygonize_options& x) { x.aniso_max_stretch = 0.5; }, "max_stretch"},
      {[](pm_polygonize_options& x) { x.aniso_neighbor_radius = -1; }, "neighbor_radius"},
      {[](pm_polygonize_options& x) { x.aniso_smoothing = NAN; }, "smoothing"},
      {[](pm_polygonize_options& x) { x.aniso_min_neighbors = -3; }, "min_neighbors"},
      {[](pm_polygonize_options& x) { x.min_component_volume = -1; }, "min_component_volume"},
      {[](pm_polygonize_options& x) { x.min_component_particles = INFINITY; }, "min_component_particles"},
      {[](pm_polygonize_options& x) { x.taubin_iterations = -1; }, "iterations"},
      {[](pm_polygonize_options& x) { x.taubin_mu = 0.2; }, "mu"},
  };
  for (const Bad& b : bad) {
    pm_polygonize_options x;
    pm_polygonize_options_init(&x);
    x.anisotropic = 1;
    b.set(x);
    pm_mesh* untouched = reinterpret_cast<pm_mesh*>(0x1);
    EXPECT_EQ(pm_polygonize(cloud.handle, nullptr, nullptr, &x, &untouched), PM_STATUS_INVALID_ARGUMENT) << b.named;
    EXPECT_NE(last().find(b.named), std::string::npos) << last();
    EXPECT_EQ(untouched, reinterpret_cast<pm_mesh*>(0x1));
  }
}

// collapse_edges, appended last: off by default and for a caller whose struct ends before it;
// the C++ result when set; the count in the stats (left alone in a stats struct without it);
// out of range named.
TEST(CApiPolygonize, CollapsesShortEdges) {
  const PointCloud c = test::random_cloud(3000, 7, 1.4);
  Cloud cloud(c);
  pm_polygonize_options opt;
  pm_polygonize_options_init(&opt);
  EXPECT_EQ(opt.collapse_edges, 0.0);
  opt.radius = 0.15;
  opt.collapse_edges = 0.3;
  pm_mesh* mesh = nullptr;
  pm_polygonize_stats stats{};
  stats.struct_size = sizeof(stats);
  ASSERT_EQ(pm_polygonize_ex(cloud.handle, nullptr, nullptr, &opt, &mesh, &stats), PM_OK) << last();
  PolygonizeOptions o;
  o.radius = 0.15;
  o.collapse_edges = 0.3;
  const PolygonizeResult ref = polygonize(c, o);
  EXPECT_GT(ref.stats.edges_collapsed, 0u);
  EXPECT_EQ(stats.edges_collapsed, ref.stats.edges_collapsed);
  EXPECT_EQ(stats.triangles, ref.stats.triangles);
  EXPECT_TRUE(read_back(mesh).positions == ref.mesh.positions);
  EXPECT_TRUE(read_back(mesh).triangles == ref.mesh.triangles);
  pm_mesh_destroy(mesh);
  // A struct that ends before the field: off.
  opt.struct_size = uint32_t(offsetof(pm_polygonize_options, collapse_edges));
  pm_polygonize_stats old{};
  old.struct_size = uint32_t(offsetof(pm_polygonize_stats, edges_collapsed));
  old.edges_collapsed = 77;
  ASSERT_EQ(pm_polygonize_ex(cloud.handle, nullptr, nullptr, &opt, &mesh, &old), PM_OK) << last();
  o.collapse_edges = 0;
  EXPECT_TRUE(read_back(mesh).triangles == polygonize(c, o).mesh.triangles);
  EXPECT_EQ(old.edges_collapsed, 77u);
  pm_mesh_destroy(mesh);
  opt.struct_size = sizeof(opt);
  for (double bad : {-0.1, 0.51, double(NAN)}) {
    opt.collapse_edges = bad;
    pm_mesh* untouched = reinterpret_cast<pm_mesh*>(0x1);
    EXPECT_EQ(pm_polygonize(cloud.handle, nullptr, nullptr, &opt, &untouched), PM_STATUS_INVALID_ARGUMENT) << bad;
    EXPECT_NE(last().find("collapse_edges"), std::string::npos) << last();
    EXPECT_EQ(untouched, reinterpret_cast<pm_mesh*>(0x1));
  }
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

// The radius pm_polygonize takes for radius 0: what a caller cutting a cloud into tiles passes
// to every tile. Irregular particles get more than 2 x their median spacing; a lattice 2 x.
TEST(CApiPolygonize, DefaultRadiusIsPolygonizes) {
  const PointCloud random = test::random_cloud(3000, 8, 1.0);
  std::vector<double> strengths(random.size(), 1.5);
  strengths[0] = 40;
  for (const double* w : {static_cast<const double*>(nullptr), static_cast<const double*>(strengths.data())}) {
    Cloud cloud(random);
    double r = 0;
    ASSERT_EQ(pm_default_radius(cloud.handle, w, PM_KERNEL_POLY4, 1, &r), PM_OK) << last();
    pm_polygonize_options opt;
    pm_polygonize_options_init(&opt);
    opt.kernel = PM_KERNEL_POLY4;
    pm_mesh* mesh = nullptr;
    pm_polygonize_stats stats{};
    stats.struct_size = sizeof(stats);
    ASSERT_EQ(pm_polygonize_ex(cloud.handle, nullptr, w, &opt, &mesh, &stats), PM_OK) << last();
    pm_mesh_destroy(mesh);
    EXPECT_EQ(r, stats.radius);
    EXPECT_GT(r, 1.25 * 2 * stats.spacing);
  }
  PointCloud block;
  for (int i = 0; i < 8; ++i)
    for (int j = 0; j < 8; ++j)
      for (int k = 0; k < 8; ++k) block.positions.push_back({0.5 * i, 0.5 * j, 0.5 * k});
  Cloud lattice(block);
  double r = 0;
  ASSERT_EQ(pm_default_radius(lattice.handle, nullptr, PM_KERNEL_WYVILL, 0, &r), PM_OK) << last();
  EXPECT_DOUBLE_EQ(r, 1.0);
  EXPECT_EQ(pm_default_radius(lattice.handle, nullptr, 9, 0, &r), PM_STATUS_INVALID_ARGUMENT);
  EXPECT_NE(last().find("kernel"), std::string::npos) << last();
  Cloud one(PointCloud{{{1.0, 2.0, 3.0}}, {}, {}});
  EXPECT_EQ(pm_default_radius(one.handle, nullptr, PM_KERNEL_WYVILL, 0, &r), PM_STATUS_INVALID_INPUT);
  EXPECT_NE(last().find("give a radius"), std::string::npos) << last();
}

// The particle grid's radius a caller cutting a cloud into tiles gives every tile with
// per-particle radii: the C++ value, and the usual statuses for misuse (the output untouched).
TEST(CApiPolygonize, ParticleGridRadius) {
  std::vector<double> radii(5000, 0.1);
  radii[42] = 2.0;
  double r = -1;
  ASSERT_EQ(pm_particle_grid_radius(radii.data(), radii.size(), &r), PM_OK) << last();
  EXPECT_EQ(r, 0.1);
  EXPECT_EQ(r, particle_grid_radius(radii.data(), radii.size()));
  ASSERT_EQ(pm_particle_grid_radius(nullptr, 0, &r), PM_OK) << last();
  EXPECT_EQ(r, 0.0);
  radii[7] = std::nan("");
  r = -1;
  EXPECT_EQ(pm_particle_grid_radius(radii.data(), radii.size(), &r), PM_STATUS_INVALID_ARGUMENT);
  EXPECT_NE(last().find("radii[7]"), std::string::npos) << last();
  EXPECT_EQ(r, -1);
  EXPECT_EQ(pm_particle_grid_radius(nullptr, 3, &r), PM_STATUS_INVALID_ARGUMENT);
  EXPECT_EQ(pm_particle_grid_radius(radii.data(), radii.size(), nullptr), PM_STATUS_INVALID_ARGUMENT);
}

// pm_polygonize_attributes at the vertices of a mesh made without attributes: the values
// pm_polygonize gives its vertices, bit for bit, laid out attribute after attribute; the usual
// statuses and messages for misuse, and the output untouched on failure.
TEST(CApiPolygonize, AttributesAtTheVerticesOfAMeshMadeWithout) {
  const PointCloud c = test::random_cloud(3000, 7, 1.4);
  Cloud bare(c), with(c);
  std::vector<float> velocity, heat;
  for (size_t i = 0; i < c.size(); ++i) {
    for (int k = 0; k < 3; ++k) velocity.push_back(float(std::sin(double(3 * i + size_t(k)))));
    heat.push_back(float(i % 11));
  }
  ASSERT_EQ(pm_cloud_set_attribute(with.handle, "velocity", 3, velocity.data(), c.size()), PM_OK);
  ASSERT_EQ(pm_cloud_set_attribute(with.handle, "heat", 1, heat.data(), c.size()), PM_OK);
  pm_polygonize_options opt;
  pm_polygonize_options_init(&opt);
  opt.kernel = PM_KERNEL_POLY6;
  opt.threads = 2;
  pm_mesh *plain = nullptr, *full = nullptr;
  ASSERT_EQ(pm_polygonize(bare.handle, nullptr, nullptr, &opt, &plain), PM_OK) << last();
  ASSERT_EQ(pm_polygonize(with.handle, nullptr, nullptr, &opt, &full), PM_OK) << last();
  size_t nv = 0, nt = 0;
  ASSERT_EQ(pm_mesh_get_counts(plain, &nv, &nt), PM_OK);
  ASSERT_GT(nv, 500u);
  std::vector<double> points(3 * nv);
  ASSERT_EQ(pm_mesh_copy_positions(plain, points.data(), nv), PM_OK);
  std::vector<float> want(4 * nv);
  ASSERT_EQ(pm_mesh_copy_attribute(full, "velocity", want.data(), nv), PM_OK);
  ASSERT_EQ(pm_mesh_copy_attribute(full, "heat", want.data() + 3 * nv, nv), PM_OK);
  std::vector<float> got(4 * nv, -1.0f);
  ASSERT_EQ(pm_polygonize_attributes(with.handle, nullptr, nullptr, &opt, points.data(), nv, got.data(), got.size()),
            PM_OK)
      << last();
  EXPECT_EQ(std::memcmp(got.data(), want.data(), got.size() * sizeof(float)), 0);
  // NULL options: the defaults (here the Wyvill kernel), as pm_polygonize.
  pm_mesh* defaults = nullptr;
  ASSERT_EQ(pm_polygonize(with.handle, nullptr, nullptr, nullptr, &defaults), PM_OK);
  size_t dv = 0;
  ASSERT_EQ(pm_mesh_get_counts(defaults, &dv, &nt), PM_OK);
  std::vector<double> dpoints(3 * dv);
  ASSERT_EQ(pm_mesh_copy_positions(defaults, dpoints.data(), dv), PM_OK);
  std::vector<float> dwant(dv), dgot(4 * dv);
  ASSERT_EQ(pm_mesh_copy_attribute(defaults, "heat", dwant.data(), dv), PM_OK);
  ASSERT_EQ(pm_polygonize_attributes(with.handle, nullptr, nullptr, nullptr, dpoints.data(), dv, dgot.data(),
                                     dgot.size()),
            PM_OK);
  EXPECT_EQ(std::memcmp(dgot.data() + 3 * dv, dwant.data(), dv * sizeof(float)), 0);
  pm_mesh_destroy(defaults);
  // Misuse.
  std::vector<float> untouched(got.size(), 7.0f);
  EXPECT_EQ(pm_polygonize_attributes(with.handle, nullptr, nullptr, &opt, points.data(), nv, untouched.data(),
                                     4 * nv - 1),
            PM_STATUS_INVALID_ARGUMENT);
  EXPECT_NE(last().find("capacity " + std::to_string(4 * nv - 1) + " is less than the " + std::to_string(4 * nv)),
            std::string::npos)
      << last();
  EXPECT_EQ(pm_polygonize_attributes(nullptr, nullptr, nullptr, &opt, points.data(), nv, untouched.data(), 4 * nv),
            PM_STATUS_INVALID_ARGUMENT);
  EXPECT_NE(last().find("cloud"), std::string::npos) << last();
  EXPECT_EQ(pm_polygonize_attributes(with.handle, nullptr, nullptr, &opt, nullptr, nv, untouched.data(), 4 * nv),
            PM_STATUS_INVALID_ARGUMENT);
  EXPECT_NE(last().find("points"), std::string::npos) << last();
  EXPECT_EQ(pm_polygonize_attributes(with.handle, nullptr, nullptr, &opt, points.data(), nv, nullptr, 4 * nv),
            PM_STATUS_INVALID_ARGUMENT);
  EXPECT_NE(last().find("out_values"), std::string::npos) << last();
  std::vector<double> bad = points;
  bad[3 * 5 + 2] = std::nan("");
  EXPECT_EQ(pm_polygonize_attributes(with.handle, nullptr, nullptr, &opt, bad.data(), nv, untouched.data(), 4 * nv),
            PM_STATUS_INVALID_INPUT);
  EXPECT_NE(last().find("points[5].z is NaN"), std::string::npos) << last();
  pm_polygonize_options wrong = opt;
  wrong.radius = -2;
  EXPECT_EQ(pm_polygonize_attributes(with.handle, nullptr, nullptr, &wrong, points.data(), nv, untouched.data(),
                                     4 * nv),
            PM_STATUS_INVALID_ARGUMENT);
  EXPECT_NE(last().find("radius"), std::string::npos) << last();
  EXPECT_EQ(untouched, std::vector<float>(got.size(), 7.0f));
  // A cloud without attributes writes nothing, and needs no output.
  EXPECT_EQ(pm_polygonize_attributes(bare.handle, nullptr, nullptr, &opt, points.data(), nv, nullptr, 0), PM_OK)
      << last();
  pm_mesh_destroy(plain);
  pm_mesh_destroy(full);
}
