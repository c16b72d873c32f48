// The C ABI: statuses and messages for every kind of misuse, no exception ever escapes,
// outputs untouched on failure, cancellation, and the same results as the C++ API.
#include "particlemesh/particlemesh.h"

#include <gtest/gtest.h>

#include <algorithm>

#include <cmath>
#include <fstream>
#include <string>
#include <vector>

#include "particlemesh/sample/shapes.h"
#include "particlemesh/surface/reconstruct.h"
#include "particlemesh/surface/triangulate.h"
#include "support/test_support.h"

using namespace particlemesh;

namespace {
std::vector<double> flat(const std::vector<Vec3>& v) {
  std::vector<double> out;
  for (const Vec3& p : v) out.insert(out.end(), {p.x, p.y, p.z});
  return out;
}
std::string last() { return pm_last_error_message(); }
// c's finished surface through the C ABI with the default options, *stats filled (its
// struct_size set here); nullptr on failure.
pm_mesh* triangulate_with_stats(const PointCloud& c, pm_triangulate_stats* stats,
                                const pm_triangulate_options* options = nullptr) {
  const auto pos = flat(c.positions);
  pm_cloud* cloud = nullptr;
  if (pm_cloud_create(pos.data(), nullptr, c.size(), &cloud) != PM_OK) return nullptr;
  *stats = {};
  stats->struct_size = sizeof(*stats);
  pm_mesh* mesh = nullptr;
  if (pm_triangulate(cloud, options, &mesh, stats) != PM_OK) mesh = nullptr;
  pm_cloud_destroy(cloud);
  return mesh;
}
}  // namespace

TEST(CApi, VersionAndStatusStrings) {
  EXPECT_EQ(pm_abi_version(), uint32_t(PM_ABI_VERSION));
  EXPECT_STRNE(pm_version_string(), "");
  EXPECT_STREQ(pm_status_string(PM_STATUS_CANCELLED), "cancelled");
  EXPECT_STREQ(pm_status_string(PM_OK), "ok");
  EXPECT_STREQ(pm_status_string(static_cast<pm_status>(999)), "unknown status");
}

TEST(CApi, TriangulateMatchesTheCppApi) {
  const PointCloud c = fibonacci_sphere(3000);
  const auto pos = flat(c.positions);
  pm_cloud* cloud = nullptr;
  ASSERT_EQ(pm_cloud_create(pos.data(), nullptr, c.size(), &cloud), PM_OK);
  pm_triangulate_options opt;
  pm_triangulate_options_init(&opt);
  opt.flags = PM_TRIANGULATE_RAW;
  pm_triangulate_stats stats{};
  stats.struct_size = sizeof(stats);
  pm_mesh* mesh = nullptr;
  ASSERT_EQ(pm_triangulate(cloud, &opt, &mesh, &stats), PM_OK) << last();
  size_t nv = 0, nt = 0;
  ASSERT_EQ(pm_mesh_get_counts(mesh, &nv, &nt), PM_OK);
  const TriangulateResult ref = triangulate_raw(c);
  EXPECT_EQ(nv, c.size());
  EXPECT_EQ(nt, ref.mesh.triangles.size());
  EXPECT_EQ(stats.kept, ref.stats.kept);
  EXPECT_DOUBLE_EQ(stats.spacing, ref.stats.spacing);
  EXPECT_EQ(stats.spacing_estimated, 1);
  std::vector<int32_t> tris(3 * nt);
  ASSERT_EQ(pm_mesh_copy_triangles(mesh, tris.data(), nt), PM_OK);
  for (size_t f = 0; f < nt; ++f)
    for (int k = 0; k < 3; ++k) ASSERT_EQ(uint32_t(tris[3 * f + k]), ref.mesh.triangles[f][k]);
  std::vector<float> p32(3 * nv);
  ASSERT_EQ(pm_mesh_copy_positions_f32(mesh, p32.data(), nv), PM_OK);
  EXPECT_FLOAT_EQ(p32[3], float(c.positions[1].x));
  pm_topology_report rep{};
  rep.struct_size = sizeof(rep);
  ASSERT_EQ(pm_mesh_report(mesh, &rep), PM_OK);
  EXPECT_EQ(rep.triangles, nt);
  EXPECT_EQ(rep.vertices_used, nv);
  pm_mesh_destroy(mesh);
  pm_cloud_destroy(cloud);
}

// The appended narrow-loop statistics are the library's: loops a fill of 1 x L did not try.
TEST(CApi, NarrowLoopsLeftOpenAreTheLibrarys) {
  const PointCloud c = poisson_disk_sample(icosphere_mesh(5), 0.05, 1);
  pm_triangulate_options opt;
  pm_triangulate_options_init(&opt);
  opt.fill_edge_factor = 1.0;
  pm_triangulate_stats stats;
  pm_mesh* mesh = triangulate_with_stats(c, &stats, &opt);
  ASSERT_NE(mesh, nullptr) << last();
  SurfaceOptions o;
  o.fill_edge_factor = 1.0;
  const SurfaceResult ref = reconstruct_surface(c, o);
  EXPECT_GT(stats.narrow_loops, 0u);
  EXPECT_EQ(stats.narrow_loops, ref.surface.narrow_loops.count);
  EXPECT_EQ(stats.narrow_loop_width, ref.surface.narrow_loops.width);
  EXPECT_EQ(stats.narrow_loop_edges, ref.surface.narrow_loops.edges);
  EXPECT_EQ(stats.holes_left, ref.surface.holes_left);
  EXPECT_EQ(stats.sampling_thickness, ref.triangulation.sampling_thickness);
  EXPECT_GT(stats.sampling_thickness, 0.0);
  EXPECT_LT(stats.sampling_thickness, 0.1);  // a clean sphere
  pm_mesh_destroy(mesh);
}

// The appended min_component_triangles reaches the library, and its counts come back; an
// options struct of the size before it (an older caller) keeps every piece.
TEST(CApi, SmallComponentsRemovedAsTheLibraryDoes) {
  const auto triangles = [](const pm_mesh* m) {
    size_t v = 0, t = 0;
    EXPECT_EQ(pm_mesh_get_counts(m, &v, &t), PM_OK);
    return t;
  };
  PointCloud c = fibonacci_sphere(3000);
  for (const Vec3& v : {Vec3{3, 0, 0}, Vec3{3.06, 0, 0}, Vec3{3.03, 0.05, 0}}) c.positions.push_back(v);
  c.normals.clear();
  pm_triangulate_options opt;
  pm_triangulate_options_init(&opt);
  EXPECT_EQ(opt.min_component_triangles, 0u);
  opt.min_component_triangles = 2;
  pm_triangulate_stats stats;
  pm_mesh* mesh = triangulate_with_stats(c, &stats, &opt);
  ASSERT_NE(mesh, nullptr) << last();
  SurfaceOptions o;
  o.min_component_triangles = 2;
  const SurfaceResult ref = reconstruct_surface(c, o);
  EXPECT_EQ(stats.components_removed, 1u);
  EXPECT_EQ(stats.component_triangles_removed, 1u);
  EXPECT_EQ(stats.stray_pieces, ref.surface.stray_pieces.count);
  EXPECT_EQ(stats.components_removed, ref.surface.components_removed);
  EXPECT_EQ(stats.unused_points, ref.surface.unused_points);
  EXPECT_EQ(triangles(mesh), ref.mesh.triangles.size());
  pm_mesh_destroy(mesh);
  opt.struct_size = uint32_t(offsetof(pm_triangulate_options, min_component_triangles));
  mesh = triangulate_with_stats(c, &stats, &opt);
  ASSERT_NE(mesh, nullptr) << last();
  EXPECT_EQ(stats.components_removed, 0u);
  EXPECT_EQ(triangles(mesh), ref.mesh.triangles.size() + 1);
  EXPECT_EQ(stats.stray_pieces, 1u);  // the lone triangle, kept
  EXPECT_EQ(stats.stray_piece_triangles, 1u);
  EXPECT_EQ(stats.stray_piece_largest, 1u);
  pm_mesh_destroy(mesh);
}

// The appended small_handles_removed comes back as the library counts it: a Fibonacci sphere
// flattened to 0.12 of its width has a rim thinner than its spacing, where the surface had a
// tunnel.
TEST(CApi, SmallHandlesRemovedAsTheLibraryCounts) {
  PointCloud c = fibonacci_sphere(800);
  for (Vec3& p : c.positions) p.z *= 0.12;
  c.normals.clear();
  pm_triangulate_stats stats;
  pm_mesh* mesh = triangulate_with_stats(c, &stats);
  ASSERT_NE(mesh, nullptr) << last();
  const SurfaceResult ref = reconstruct_surface(c, SurfaceOptions{});
  EXPECT_EQ(ref.surface.small_handles_removed, 1u);
  EXPECT_EQ(stats.small_handles_removed, ref.surface.small_handles_removed);
  pm_mesh_destroy(mesh);
  // A caller's struct of the size before the field is filled up to its size.
  stats = {};
  stats.struct_size = uint32_t(offsetof(pm_triangulate_stats, small_handles_removed));
  stats.small_handles_removed = 77;
  const auto pos = flat(c.positions);
  pm_cloud* cloud = nullptr;
  ASSERT_EQ(pm_cloud_create(pos.data(), nullptr, c.size(), &cloud), PM_OK);
  mesh = nullptr;
  ASSERT_EQ(pm_triangulate(cloud, nullptr, &mesh, &stats), PM_OK) << last();
  EXPECT_EQ(stats.small_handles_removed, 77u);  // not written
  pm_mesh_destroy(mesh);
  pm_cloud_destroy(cloud);
}

TEST(CApi, ParticlesAtRandomReportTheirLongerReach) {
  pm_triangulate_stats stats;
  pm_mesh* mesh = triangulate_with_stats(particlemesh::test::random_sphere(3000, 9), &stats);
  ASSERT_NE(mesh, nullptr) << last();
  EXPECT_GT(stats.sampling_irregularity, 0.45);
  EXPECT_EQ(stats.reach_factor, 1.75);
  EXPECT_EQ(stats.holes_left, 0u);
  pm_mesh_destroy(mesh);
}

TEST(CApi, DefaultIsTheFinishedSurface) {
  const PointCloud c = fibonacci_sphere(5000);
  const auto pos = flat(c.positions);
  pm_cloud* cloud = nullptr;
  ASSERT_EQ(pm_cloud_create(pos.data(), nullptr, c.size(), &cloud), PM_OK);
  pm_triangulate_stats stats{};
  stats.struct_size = sizeof(stats);
  pm_mesh* mesh = nullptr;
  ASSERT_EQ(pm_triangulate(cloud, nullptr, &mesh, &stats), PM_OK) << last();
  pm_topology_report rep{};
  rep.struct_size = sizeof(rep);
  ASSERT_EQ(pm_mesh_report(mesh, &rep), PM_OK);
  EXPECT_EQ(rep.closed, 1);
  EXPECT_EQ(rep.outward, 1);
  EXPECT_EQ(rep.euler_characteristic, 2);
  EXPECT_EQ(rep.vertices_used, c.size());
  EXPECT_EQ(stats.unused_points, 0u);
  EXPECT_EQ(stats.holes_left, 0u);
  EXPECT_EQ(stats.normals_estimated, 1);  // the cloud came without normals
  EXPECT_EQ(stats.reach_factor, 1.0);      // an even sampling: the limits as they are
  EXPECT_LT(stats.sampling_irregularity, 0.25);
  int32_t has = 0;
  ASSERT_EQ(pm_mesh_has_normals(mesh, &has), PM_OK);
  EXPECT_EQ(has, 1);
  pm_mesh_destroy(mesh);
  pm_triangulate_options opt;
  pm_triangulate_options_init(&opt);
  opt.normals = PM_NORMALS_INPUT;  // the cloud has none
  EXPECT_EQ(pm_triangulate(cloud, &opt, &mesh, nullptr), PM_STATUS_INVALID_ARGUMENT);
  opt.normals = 7;
  EXPECT_EQ(pm_triangulate(cloud, &opt, &mesh, nullptr), PM_STATUS_INVALID_ARGUMENT);
  pm_triangulate_options_init(&opt);
  opt.flags = 0x80;
  EXPECT_EQ(pm_triangulate(cloud, &opt, &mesh, nullptr), PM_STATUS_INVALID_ARGUMENT);
  EXPECT_NE(last().find("flags"), std::string::npos);
  pm_cloud_destroy(cloud);
}

TEST(CApi, LocalSpacingByDefaultGlobalOnRequestAndTheViewpoint) {
  // A sphere whose upper half is 2.8 times sparser: whole by default (each particle's own
  // spacing, reported in units of r0), not with PM_TRIANGULATE_GLOBAL_SPACING.
  PointCloud c;
  for (const Vec3& p : fibonacci_sphere(20000).positions)
    if (p.z < 0) c.positions.push_back(p);
  for (const Vec3& p : fibonacci_sphere(2500).positions)
    if (p.z >= 0) c.positions.push_back(p);
  const auto pos = flat(c.positions);
  pm_cloud* cloud = nullptr;
  ASSERT_EQ(pm_cloud_create(pos.data(), nullptr, c.size(), &cloud), PM_OK);
  pm_triangulate_stats stats{};
  stats.struct_size = sizeof(stats);
  pm_mesh* mesh = nullptr;
  ASSERT_EQ(pm_triangulate(cloud, nullptr, &mesh, &stats), PM_OK) << last();
  EXPECT_EQ(stats.unused_points, 0u);
  EXPECT_NEAR(stats.local_spacing[0], 1.0, 0.02);
  EXPECT_GT(stats.local_spacing[4], 2.0);
  EXPECT_LE(stats.local_spacing[1], stats.local_spacing[2]);
  EXPECT_LE(stats.local_spacing[2], stats.local_spacing[3]);
  EXPECT_EQ(stats.viewpoint_used, 0);
  pm_mesh_destroy(mesh);
  pm_triangulate_options opt;
  pm_triangulate_options_init(&opt);
  opt.flags = PM_TRIANGULATE_GLOBAL_SPACING;
  ASSERT_EQ(pm_triangulate(cloud, &opt, &mesh, &stats), PM_OK) << last();
  EXPECT_GT(stats.unused_points * 20, c.size());
  EXPECT_EQ(stats.local_spacing[4], 1.0);
  pm_mesh_destroy(mesh);
  // A viewpoint outside, over the pole: most of the sphere is seen at a slant, not edge-on,
  // so it is taken; a non-finite one is refused.
  opt.flags = PM_TRIANGULATE_VIEWPOINT;
  opt.viewpoint[0] = 0, opt.viewpoint[1] = 0, opt.viewpoint[2] = 10;
  ASSERT_EQ(pm_triangulate(cloud, &opt, &mesh, &stats), PM_OK) << last();
  EXPECT_EQ(stats.viewpoint_used, 1);
  pm_mesh_destroy(mesh);
  opt.viewpoint[1] = std::nan("");
  EXPECT_EQ(pm_triangulate(cloud, &opt, &mesh, &stats), PM_STATUS_INVALID_ARGUMENT);
  EXPECT_NE(last().find("viewpoint"), std::string::npos);
  pm_cloud_destroy(cloud);
}

TEST(CApi, Float32InputAndNormals) {
  const PointCloud c = fibonacci_sphere(500);
  std::vector<float> p, n;
  for (size_t i = 0; i < c.size(); ++i) {
    p.insert(p.end(), {float(c.positions[i].x), float(c.positions[i].y), float(c.positions[i].z)});
    n.insert(n.end(), {float(c.normals[i].x), float(c.normals[i].y), float(c.normals[i].z)});
  }
  pm_cloud* cloud = nullptr;
  ASSERT_EQ(pm_cloud_create_f32(p.data(), n.data(), c.size(), &cloud), PM_OK);
  int32_t has = 0;
  ASSERT_EQ(pm_cloud_has_normals(cloud, &has), PM_OK);
  EXPECT_EQ(has, 1);
  double spacing = 0;
  ASSERT_EQ(pm_estimate_spacing(cloud, 1, &spacing), PM_OK);
  EXPECT_GT(spacing, 0.05);
  EXPECT_LT(spacing, 0.2);
  pm_cloud_destroy(cloud);
}

TEST(CApi, FullPrecisionReadBack) {
  // Georeferenced coordinates (UTM) differ from their float32 rounding by decimetres: the
  // double read-back gives exactly what went in, for a cloud's positions and normals and for
  // a mesh's normals.
  const double p[] = {500000.123456789, 4649776.987654321, 213.000000001, 500001.5, 4649777.25, 213.75,
                      500000.75, 4649778.125, 214.0625};
  const double n[] = {0.1, 0.2, 0.9746794344808963, 0, 0, 1, 0.6, 0.0, 0.8};
  pm_cloud* cloud = nullptr;
  ASSERT_EQ(pm_cloud_create(p, n, 3, &cloud), PM_OK) << last();
  std::vector<double> back(9), normals(9);
  ASSERT_EQ(pm_cloud_copy_positions(cloud, back.data(), 3), PM_OK) << last();
  ASSERT_EQ(pm_cloud_copy_normals(cloud, normals.data(), 3), PM_OK) << last();
  EXPECT_EQ(back, std::vector<double>(p, p + 9));
  EXPECT_EQ(normals, std::vector<double>(n, n + 9));
  EXPECT_EQ(pm_cloud_copy_positions(cloud, back.data(), 2), PM_STATUS_INVALID_ARGUMENT);
  EXPECT_NE(last().find("capacity 2"), std::string::npos) << last();
  pm_cloud_destroy(cloud);
  ASSERT_EQ(pm_cloud_create(p, nullptr, 3, &cloud), PM_OK);
  EXPECT_EQ(pm_cloud_copy_normals(cloud, normals.data(), 3), PM_STATUS_INVALID_ARGUMENT);
  EXPECT_NE(last().find("no normals"), std::string::npos) << last();
  pm_cloud_destroy(cloud);

  const int32_t tri[] = {0, 1, 2};
  pm_mesh* mesh = nullptr;
  ASSERT_EQ(pm_mesh_create(p, 3, tri, 1, n, &mesh), PM_OK) << last();
  std::fill(normals.begin(), normals.end(), 0.0);
  ASSERT_EQ(pm_mesh_copy_normals(mesh, normals.data(), 3), PM_OK) << last();
  EXPECT_EQ(normals, std::vector<double>(n, n + 9));
  EXPECT_EQ(pm_mesh_copy_normals(mesh, normals.data(), 1), PM_STATUS_INVALID_ARGUMENT);
  pm_mesh_destroy(mesh);
  ASSERT_EQ(pm_mesh_create(p, 3, tri, 1, nullptr, &mesh), PM_OK);
  EXPECT_EQ(pm_mesh_copy_normals(mesh, normals.data(), 3), PM_STATUS_INVALID_ARGUMENT);
  EXPECT_NE(last().find("no normals"), std::string::npos) << last();
  pm_mesh_destroy(mesh);
}

TEST(CApi, LentArraysAreTheMeshsOwnUntilItIsDestroyed) {
  // A triangulated sphere: the lent arrays hold exactly what the copying calls give, and
  // writing through them changes the mesh (they are its storage, not a copy).
  const PointCloud s = fibonacci_sphere(2000);
  pm_cloud* cloud = nullptr;
  ASSERT_EQ(pm_cloud_create(flat(s.positions).data(), flat(s.normals).data(), s.positions.size(), &cloud), PM_OK);
  pm_mesh* mesh = nullptr;
  ASSERT_EQ(pm_triangulate(cloud, nullptr, &mesh, nullptr), PM_OK) << last();
  pm_cloud_destroy(cloud);
  size_t nv = 0, nt = 0;
  ASSERT_EQ(pm_mesh_get_counts(mesh, &nv, &nt), PM_OK);
  ASSERT_GT(nt, 1000u);
  std::vector<double> positions(3 * nv), normals(3 * nv);
  std::vector<int32_t> tris(3 * nt);
  ASSERT_EQ(pm_mesh_copy_positions(mesh, positions.data(), nv), PM_OK);
  ASSERT_EQ(pm_mesh_copy_normals(mesh, normals.data(), nv), PM_OK);
  ASSERT_EQ(pm_mesh_copy_triangles(mesh, tris.data(), nt), PM_OK);
  double *lp = nullptr, *ln = nullptr;
  uint32_t* lt = nullptr;
  ASSERT_EQ(pm_mesh_lend_arrays(mesh, &lp, &ln, &lt), PM_OK) << last();
  ASSERT_TRUE(lp && ln && lt);
  EXPECT_TRUE(std::equal(positions.begin(), positions.end(), lp));
  EXPECT_TRUE(std::equal(normals.begin(), normals.end(), ln));
  for (size_t i = 0; i < 3 * nt; ++i) ASSERT_EQ(int64_t(lt[i]), int64_t(tris[i])) << i;
  lp[4] = 12.5;  // vertex 1's y
  lt[0] = lt[1];
  ASSERT_EQ(pm_mesh_copy_positions(mesh, positions.data(), nv), PM_OK);
  ASSERT_EQ(pm_mesh_copy_triangles(mesh, tris.data(), nt), PM_OK);
  EXPECT_EQ(positions[4], 12.5);
  EXPECT_EQ(tris[0], tris[1]);
  // Lent again: the same storage.
  double *lp2 = nullptr, *ln2 = nullptr;
  uint32_t* lt2 = nullptr;
  ASSERT_EQ(pm_mesh_lend_arrays(mesh, &lp2, &ln2, &lt2), PM_OK);
  EXPECT_EQ(lp2, lp);
  EXPECT_EQ(ln2, ln);
  EXPECT_EQ(lt2, lt);
  // An attribute: lent as it is held, and its name checked.
  const std::vector<float> speed(nv * 2, 0.25f);
  ASSERT_EQ(pm_mesh_set_attribute(mesh, "speed", 2, speed.data(), nv), PM_OK) << last();
  float* values = nullptr;
  ASSERT_EQ(pm_mesh_lend_attribute(mesh, "speed", &values), PM_OK) << last();
  ASSERT_NE(values, nullptr);
  EXPECT_TRUE(std::equal(speed.begin(), speed.end(), values));
  values[3] = 2.0f;
  std::vector<float> back(nv * 2);
  ASSERT_EQ(pm_mesh_copy_attribute(mesh, "speed", back.data(), nv), PM_OK);
  EXPECT_EQ(back[3], 2.0f);
  float* untouched = reinterpret_cast<float*>(0x7);
  EXPECT_EQ(pm_mesh_lend_attribute(mesh, "colour", &untouched), PM_STATUS_INVALID_ARGUMENT);
  EXPECT_NE(last().find("'colour'"), std::string::npos) << last();
  EXPECT_EQ(untouched, reinterpret_cast<float*>(0x7));
  pm_mesh_destroy(mesh);

  // Empty arrays and a mesh without normals lend NULL.
  const double p[] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
  const int32_t tri[] = {0, 1, 2};
  ASSERT_EQ(pm_mesh_create(p, 3, tri, 1, nullptr, &mesh), PM_OK);
  ASSERT_EQ(pm_mesh_lend_arrays(mesh, &lp, &ln, &lt), PM_OK);
  EXPECT_TRUE(lp != nullptr && ln == nullptr && lt != nullptr);
  EXPECT_EQ(lp[3], 1.0);
  EXPECT_EQ(lt[2], 2u);
  pm_mesh_destroy(mesh);
  ASSERT_EQ(pm_mesh_create(nullptr, 0, nullptr, 0, nullptr, &mesh), PM_OK) << last();
  ASSERT_EQ(pm_mesh_lend_arrays(mesh, &lp, &ln, &lt), PM_OK);
  EXPECT_TRUE(lp == nullptr && ln == nullptr && lt == nullptr);
  pm_mesh_destroy(mesh);
}

TEST(CApi, ThinKeepsAnEvenSubsetAndChecksItsArguments) {
  const PointCloud c = fibonacci_sphere(5000);
  pm_cloud* cloud = nullptr;
  ASSERT_EQ(pm_cloud_create(&c.positions[0].x, nullptr, c.size(), &cloud), PM_OK);
  double spacing = 0;
  ASSERT_EQ(pm_estimate_spacing(cloud, 0, &spacing), PM_OK);
  double sampled = 0;
  ASSERT_EQ(pm_estimate_spacing_sampled(cloud, 1000, 0, &sampled), PM_OK) << last();
  EXPECT_NEAR(sampled, spacing, 0.01 * spacing);
  EXPECT_EQ(pm_estimate_spacing_sampled(cloud, 0, 0, &sampled), PM_STATUS_INVALID_ARGUMENT);
  EXPECT_NE(last().find("max_samples"), std::string::npos) << last();
  std::vector<uint32_t> idx(c.size(), 0xdeadbeefu);
  size_t kept = 0;
  ASSERT_EQ(pm_cloud_thin(cloud, 2 * spacing, idx.data(), idx.size(), &kept), PM_OK) << last();
  EXPECT_GT(kept, c.size() / 12);
  EXPECT_LT(kept, c.size() / 3);
  for (size_t k = 1; k < kept; ++k) ASSERT_LT(idx[k - 1], idx[k]);
  EXPECT_LT(idx[kept - 1], c.size());
  EXPECT_EQ(idx[kept], 0xdeadbeefu);  // nothing written past the kept ones

  size_t untouched = 12345;
  EXPECT_EQ(pm_cloud_thin(cloud, 0.0, idx.data(), idx.size(), &untouched), PM_STATUS_INVALID_ARGUMENT);
  EXPECT_NE(last().find("min_distance"), std::string::npos) << last();
  EXPECT_EQ(pm_cloud_thin(cloud, NAN, idx.data(), idx.size(), &untouched), PM_STATUS_INVALID_ARGUMENT);
  EXPECT_EQ(pm_cloud_thin(cloud, spacing, idx.data(), idx.size() - 1, &untouched), PM_STATUS_INVALID_ARGUMENT);
  EXPECT_NE(last().find("capacity"), std::string::npos) << last();
  EXPECT_EQ(pm_cloud_thin(cloud, spacing, nullptr, idx.size(), &untouched), PM_STATUS_INVALID_ARGUMENT);
  EXPECT_EQ(pm_cloud_thin(nullptr, spacing, idx.data(), idx.size(), &untouched), PM_STATUS_INVALID_ARGUMENT);
  EXPECT_EQ(pm_cloud_thin(cloud, spacing, idx.data(), idx.size(), nullptr), PM_STATUS_INVALID_ARGUMENT);
  EXPECT_EQ(untouched, 12345u);
  // A distance so small that the grid would span too many cells: an error, not a crash.
  EXPECT_EQ(pm_cloud_thin(cloud, 1e-300, idx.data(), idx.size(), &untouched), PM_STATUS_LIMIT_EXCEEDED);
  EXPECT_EQ(untouched, 12345u);
  pm_cloud_destroy(cloud);
}

TEST(CApi, TriangleEdgesNumberEachEdgeOnceAndEveryCorner) {
  // Two triangles sharing the edge (1, 2), and a third on (2, 3) only.
  const uint32_t tris[] = {0, 1, 2, 2, 1, 3, 3, 4, 2};
  std::vector<uint32_t> edges(2 * 9, 0xdeadbeefu), corners(9, 0xdeadbeefu);
  size_t count = 0;
  ASSERT_EQ(pm_triangle_edges(tris, 3, 5, 0, edges.data(), 9, corners.data(), &count), PM_OK) << last();
  ASSERT_EQ(count, 7u);
  const std::vector<uint32_t> want = {0, 1, 0, 2, 1, 2, 1, 3, 2, 3, 2, 4, 3, 4};  // ordered, a < b
  EXPECT_EQ(std::vector<uint32_t>(edges.begin(), edges.begin() + 14), want);
  EXPECT_EQ(edges[14], 0xdeadbeefu);  // nothing past the count
  for (size_t c = 0; c < 9; ++c) {
    const uint32_t a = tris[c], b = tris[c % 3 == 2 ? c - 2 : c + 1];
    EXPECT_EQ(edges[2 * corners[c]], std::min(a, b));
    EXPECT_EQ(edges[2 * corners[c] + 1], std::max(a, b));
  }
  // Too little room: the count needed, and an error; an index beyond the vertices is named.
  EXPECT_EQ(pm_triangle_edges(tris, 3, 5, 0, edges.data(), 6, corners.data(), &count), PM_STATUS_INVALID_ARGUMENT);
  EXPECT_EQ(count, 7u);
  EXPECT_NE(last().find("edge_capacity 6"), std::string::npos) << last();
  EXPECT_EQ(pm_triangle_edges(tris, 3, 4, 0, edges.data(), 9, corners.data(), &count), PM_STATUS_INVALID_ARGUMENT);
  EXPECT_NE(last().find("triangle 2 has vertex index 4"), std::string::npos) << last();
  EXPECT_EQ(pm_triangle_edges(nullptr, 0, 0, 0, nullptr, 0, nullptr, &count), PM_OK) << last();
  EXPECT_EQ(count, 0u);
}

// A point inside a closed tetrahedron crosses it once, whatever its winding; one below it
// twice (also through its apex's vertex); beside it never. Counts, not a yes or no, so that
// pieces of one surface in different processes add up.
TEST(CApi, RayCrossingsCountEveryTriangleTheRayCrosses) {
  const double p[] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1};
  const int32_t tri[] = {0, 2, 1, 0, 1, 3, 0, 3, 2, 1, 2, 3};
  pm_mesh* mesh = nullptr;
  ASSERT_EQ(pm_mesh_create(p, 4, tri, 4, nullptr, &mesh), PM_OK) << last();
  const double q[] = {0.2, 0.2, 0.2, 0.2, 0.2, -1, 0, 0, -1, 2, 2, 0, 0.2, 0.2, 5};
  uint64_t count[5] = {9, 9, 9, 9, 9};
  ASSERT_EQ(pm_mesh_ray_crossings(mesh, q, 5, 0, count), PM_OK) << last();
  EXPECT_EQ(std::vector<uint64_t>(count, count + 5), (std::vector<uint64_t>{1, 2, 2, 0, 0}));
  const double nan_point[] = {0, 0, 0, 0, NAN, 0};
  EXPECT_EQ(pm_mesh_ray_crossings(mesh, nan_point, 2, 0, count), PM_STATUS_INVALID_INPUT);
  EXPECT_NE(last().find("point 1 is not finite"), std::string::npos) << last();
  EXPECT_EQ(pm_mesh_ray_crossings(mesh, nullptr, 0, 0, nullptr), PM_OK) << last();
  pm_mesh_destroy(mesh);
}

// Pieces numbered by their first triangle, each vertex's piece (none for an unused one), and
// per piece its triangles, area and enclosed volume; too small a capacity fails with the count
// set and the outputs untouched.
TEST(CApi, ComponentsOfAMeshAndTheirVolumes) {
  // The outward unit corner tetrahedron, one triangle at z = 2 (open: the cone over it from
  // its own corner, 0), and a vertex no triangle uses.
  const double p[] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 2, 1, 0, 2, 0, 1, 2, 5, 5, 5};
  const int32_t tri[] = {0, 2, 1, 0, 1, 3, 4, 5, 6, 0, 3, 2, 1, 2, 3};
  pm_mesh* mesh = nullptr;
  ASSERT_EQ(pm_mesh_create(p, 8, tri, 5, nullptr, &mesh), PM_OK) << last();
  size_t count = 0;
  ASSERT_EQ(pm_mesh_components(mesh, &count, nullptr, nullptr, nullptr, nullptr, 0), PM_OK) << last();
  ASSERT_EQ(count, 2u);
  uint32_t vertex[8];
  uint64_t triangles[2] = {9, 9};
  double area[2], volume[2];
  ASSERT_EQ(pm_mesh_components(mesh, &count, vertex, triangles, area, volume, 2), PM_OK) << last();
  EXPECT_EQ(std::vector<uint32_t>(vertex, vertex + 8), (std::vector<uint32_t>{0, 0, 0, 0, 1, 1, 1, UINT32_MAX}));
  EXPECT_EQ(triangles[0], 4u);
  EXPECT_EQ(triangles[1], 1u);
  EXPECT_NEAR(area[0], 1.5 + std::sqrt(3.0) / 2, 1e-12);
  EXPECT_NEAR(area[1], 0.5, 1e-12);
  EXPECT_NEAR(volume[0], 1.0 / 6, 1e-12);
  EXPECT_EQ(volume[1], 0.0);
  uint64_t untouched[1] = {7};
  count = 0;
  EXPECT_EQ(pm_mesh_components(mesh, &count, nullptr, untouched, nullptr, nullptr, 1), PM_STATUS_INVALID_ARGUMENT);
  EXPECT_NE(last().find("capacity 1 is below the mesh's 2 components"), std::string::npos) << last();
  EXPECT_EQ(count, 2u);
  EXPECT_EQ(untouched[0], 7u);
  EXPECT_EQ(pm_mesh_components(nullptr, &count, nullptr, nullptr, nullptr, nullptr, 0), PM_STATUS_INVALID_ARGUMENT);
  EXPECT_EQ(pm_mesh_components(mesh, nullptr, nullptr, nullptr, nullptr, nullptr, 0), PM_STATUS_INVALID_ARGUMENT);
  pm_mesh_destroy(mesh);
}

// What pm_mesh_read does not carry is named line by line; a mesh made here names nothing.
TEST(CApi, WhatAMeshFileHoldsButIsNotReadIsNamed) {
  const std::string path = (particlemesh::test::scratch_dir("capi_mesh_not_read") / "uv.obj").string();
  std::ofstream(path) << "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nf 1/1 2/1 3\n";
  pm_mesh* mesh = nullptr;
  ASSERT_EQ(pm_mesh_read(path.c_str(), &mesh), PM_OK) << last();
  size_t n = 9;
  ASSERT_EQ(pm_mesh_get_not_read_count(mesh, &n), PM_OK) << last();
  ASSERT_EQ(n, 1u);
  const char* text = nullptr;
  ASSERT_EQ(pm_mesh_get_not_read(mesh, 0, &text), PM_OK) << last();
  EXPECT_STREQ(text, "texture coordinates (1 vt; 1 face corner names none)");
  const char* untouched = "x";
  text = untouched;
  EXPECT_EQ(pm_mesh_get_not_read(mesh, 1, &text), PM_STATUS_INVALID_ARGUMENT);
  EXPECT_EQ(text, untouched);
  EXPECT_EQ(pm_mesh_get_not_read(nullptr, 0, &text), PM_STATUS_INVALID_ARGUMENT);
  EXPECT_EQ(pm_mesh_get_not_read_count(mesh, nullptr), PM_STATUS_INVALID_ARGUMENT);
  pm_mesh_destroy(mesh);
  const double p[] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
  const int32_t tri[] = {0, 1, 2};
  ASSERT_EQ(pm_mesh_create(p, 3, tri, 1, nullptr, &mesh), PM_OK) << last();
  ASSERT_EQ(pm_mesh_get_not_read_count(mesh, &n), PM_OK);
  EXPECT_EQ(n, 0u);
  pm_mesh_destroy(mesh);
}

// A collection's frames by time, through the handle; misuse is named, outputs left alone.
TEST(CApi, FrameCollectionsListTheirFilesByTime) {
  const auto dir = particlemesh::test::scratch_dir("collection");
  std::ofstream((dir / "run.series").string())
      << R"({"file-series-version": "1.0", "files": [{"name": "b.vtu", "time": 3}, {"name": "a.vtu", "time": 1}]})";
  pm_frame_collection* c = nullptr;
  ASSERT_EQ(pm_frame_collection_read((dir / "run.series").c_str(), &c), PM_OK) << last();
  size_t count = 0;
  ASSERT_EQ(pm_frame_collection_get_count(c, &count), PM_OK);
  ASSERT_EQ(count, 2u);
  double time = -1;
  const char* path = nullptr;
  ASSERT_EQ(pm_frame_collection_get_frame(c, 0, &time, &path), PM_OK);
  EXPECT_EQ(time, 1.0);
  EXPECT_EQ(std::string(path), (dir / "a.vtu").string());
  ASSERT_EQ(pm_frame_collection_get_frame(c, 1, &time, &path), PM_OK);
  EXPECT_EQ(time, 3.0);
  time = -1;
  EXPECT_EQ(pm_frame_collection_get_frame(c, 2, &time, &path), PM_STATUS_INVALID_ARGUMENT);
  EXPECT_NE(last().find("frame 2 of a collection of 2"), std::string::npos) << last();
  EXPECT_EQ(time, -1);
  EXPECT_EQ(pm_frame_collection_get_count(c, nullptr), PM_STATUS_INVALID_ARGUMENT);
  EXPECT_EQ(pm_frame_collection_get_frame(c, 0, nullptr, &path), PM_STATUS_INVALID_ARGUMENT);
  EXPECT_EQ(pm_frame_collection_get_frame(c, 0, &time, nullptr), PM_STATUS_INVALID_ARGUMENT);
  EXPECT_NE(last().find("out_path"), std::string::npos) << last();
  pm_frame_collection_destroy(c);
  pm_frame_collection_destroy(nullptr);
  pm_frame_collection* untouched = reinterpret_cast<pm_frame_collection*>(0x1);
  std::ofstream((dir / "bad.pvd").string()) << "<VTKFile type=\"Collection\"><Collection/></VTKFile>";
  EXPECT_EQ(pm_frame_collection_read((dir / "bad.pvd").c_str(), &untouched), PM_STATUS_FORMAT_ERROR);
  EXPECT_NE(last().find("lists no frame"), std::string::npos) << last();
  EXPECT_EQ(untouched, reinterpret_cast<pm_frame_collection*>(0x1));
}

TEST(CApi, MisuseGivesStatusAndMessageAndLeavesOutputsAlone) {
  const double pts[] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1};
  pm_cloud* sentinel = reinterpret_cast<pm_cloud*>(0x1);
  pm_cloud* out = sentinel;
  EXPECT_EQ(pm_cloud_create(nullptr, nullptr, 4, &out), PM_STATUS_INVALID_ARGUMENT);
  EXPECT_NE(last().find("positions is NULL"), std::string::npos);
  EXPECT_EQ(out, sentinel);
  EXPECT_EQ(pm_cloud_create(pts, nullptr, 4, nullptr), PM_STATUS_INVALID_ARGUMENT);
  EXPECT_NE(last().find("out_cloud"), std::string::npos);
  EXPECT_EQ(pm_cloud_create(pts, nullptr, 0, &out), PM_STATUS_INVALID_INPUT);
  EXPECT_NE(last().find("empty"), std::string::npos);
  double bad[] = {0, 0, 0, 1, NAN, 0, 0, 1, 0};
  EXPECT_EQ(pm_cloud_create(bad, nullptr, 3, &out), PM_STATUS_INVALID_INPUT);
  EXPECT_NE(last().find("positions[1].y is NaN"), std::string::npos) << last();
  EXPECT_EQ(out, sentinel);

  pm_cloud* cloud = nullptr;
  ASSERT_EQ(pm_cloud_create(pts, nullptr, 4, &cloud), PM_OK);
  EXPECT_EQ(last(), "");  // cleared by a successful call
  pm_mesh* mesh = reinterpret_cast<pm_mesh*>(0x2);
  EXPECT_EQ(pm_triangulate(nullptr, nullptr, &mesh, nullptr), PM_STATUS_INVALID_ARGUMENT);
  pm_triangulate_options opt;
  pm_triangulate_options_init(&opt);
  opt.spacing = -1;
  EXPECT_EQ(pm_triangulate(cloud, &opt, &mesh, nullptr), PM_STATUS_INVALID_ARGUMENT);
  EXPECT_NE(last().find("spacing"), std::string::npos);
  opt.spacing = 0;
  opt.struct_size = 0;  // not initialised
  EXPECT_EQ(pm_triangulate(cloud, &opt, &mesh, nullptr), PM_STATUS_INVALID_ARGUMENT);
  EXPECT_NE(last().find("struct_size"), std::string::npos);
  pm_triangulate_stats stats{};
  stats.struct_size = 0;
  pm_triangulate_options_init(&opt);
  EXPECT_EQ(pm_triangulate(cloud, &opt, &mesh, &stats), PM_STATUS_INVALID_ARGUMENT);
  EXPECT_EQ(mesh, reinterpret_cast<pm_mesh*>(0x2));

  // A struct_size that ends half-way through a pointer field is refused: the library would
  // otherwise read half of the caller's pointer (found by fuzzing).
  pm_smooth_options sopt;
  pm_smooth_options_init(&sopt);
  sopt.struct_size = offsetof(pm_smooth_options, crease_edges) + 4;
  EXPECT_EQ(pm_smooth(reinterpret_cast<pm_mesh*>(0x1), &sopt, &mesh), PM_STATUS_INVALID_ARGUMENT);
  EXPECT_NE(last().find("options->struct_size is " + std::to_string(sopt.struct_size) + ", which ends inside a pointer field"),
            std::string::npos) << last();
  EXPECT_EQ(mesh, reinterpret_cast<pm_mesh*>(0x2));

  // An older, shorter options struct still works (fields beyond it take defaults).
  pm_triangulate_options_init(&opt);
  opt.struct_size = offsetof(pm_triangulate_options, threads);
  mesh = nullptr;
  ASSERT_EQ(pm_triangulate(cloud, &opt, &mesh, nullptr), PM_OK) << last();
  size_t nt = 0;
  ASSERT_EQ(pm_mesh_get_counts(mesh, nullptr, &nt), PM_OK);
  std::vector<int32_t> small(3);
  EXPECT_EQ(pm_mesh_copy_triangles(mesh, small.data(), 1), nt > 1 ? PM_STATUS_INVALID_ARGUMENT : PM_OK);
  std::vector<float> normals(3);
  EXPECT_EQ(pm_mesh_copy_normals_f32(mesh, normals.data(), 1), PM_STATUS_INVALID_ARGUMENT);  // 4 vertices
  EXPECT_NE(last().find("capacity"), std::string::npos);
  pm_mesh_destroy(mesh);

  const int32_t tri[] = {0, 1, 7};
  EXPECT_EQ(pm_mesh_create(pts, 4, tri, 1, nullptr, &mesh), PM_STATUS_INVALID_INPUT);
  EXPECT_NE(last().find("triangles[0]"), std::string::npos);
  EXPECT_EQ(pm_mesh_read("/nonexistent/file.ply", &mesh), PM_STATUS_IO_ERROR);
  EXPECT_NE(last().find("file.ply"), std::string::npos);
  EXPECT_EQ(pm_cloud_read(nullptr, &cloud), PM_STATUS_INVALID_ARGUMENT);
  pm_cloud_destroy(cloud);
  pm_mesh_destroy(nullptr);
}

TEST(CApi, CoincidentAndTooFewPoints) {
  const double same[] = {1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1};
  pm_cloud* cloud = nullptr;
  ASSERT_EQ(pm_cloud_create(same, nullptr, 4, &cloud), PM_OK);
  pm_mesh* mesh = nullptr;
  EXPECT_EQ(pm_triangulate(cloud, nullptr, &mesh, nullptr), PM_STATUS_INVALID_INPUT);
  EXPECT_NE(last().find("coincide"), std::string::npos) << last();
  pm_cloud_destroy(cloud);
  ASSERT_EQ(pm_cloud_create(same, nullptr, 1, &cloud), PM_OK);
  EXPECT_EQ(pm_triangulate(cloud, nullptr, &mesh, nullptr), PM_STATUS_INVALID_INPUT);
  EXPECT_EQ(mesh, nullptr);
  pm_cloud_destroy(cloud);
}

TEST(CApi, ProgressCallbackCancels) {
  const PointCloud c = fibonacci_sphere(300000);
  const auto pos = flat(c.positions);
  pm_cloud* cloud = nullptr;
  ASSERT_EQ(pm_cloud_create(pos.data(), nullptr, c.size(), &cloud), PM_OK);
  struct State {
    int calls = 0;
    double last = -1;
  } state;
  pm_triangulate_options opt;
  pm_triangulate_options_init(&opt);
  opt.progress = [](void* user, const char* stage, double f) -> int {
    auto* s = static_cast<State*>(user);
    EXPECT_NE(stage, nullptr);
    EXPECT_GE(f, s->last);
    s->last = f;
    return ++s->calls >= 3 ? 1 : 0;
  };
  opt.progress_user_data = &state;
  pm_mesh* mesh = nullptr;
  EXPECT_EQ(pm_triangulate(cloud, &opt, &mesh, nullptr), PM_STATUS_CANCELLED);
  EXPECT_EQ(mesh, nullptr);
  EXPECT_EQ(state.calls, 3);
  pm_cloud_destroy(cloud);
}
