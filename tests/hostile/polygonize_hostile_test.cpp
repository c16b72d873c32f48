// Polygonization under hostile inputs: the grid memory budget (C++ and
// C ABI), bad radii and strengths named with their index, cancellation of a 1M-particle run,
// and byte-identical output for any thread count. The CLI's budget flag (--max-grid-mib) and
// Ctrl-C are tested in tests/cli/test_polygonize.py.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "hostile_support.h"
#include "particlemesh/particlemesh.h"
#include "particlemesh/mesh/topology_report.h"
#include "particlemesh/sample/shapes.h"
#include "particlemesh/volume/polygonize.h"

using namespace particlemesh;
using namespace particlemesh::test;

namespace {

// Particles filling a ball: n on a cubic lattice of spacing 1 (volume particles).
PointCloud ball(size_t n) {
  PointCloud c;
  const double r = std::cbrt(double(n) * 3 / (4 * M_PI));
  const int k = int(std::ceil(r));
  for (int z = -k; z <= k; ++z)
    for (int y = -k; y <= k; ++y)
      for (int x = -k; x <= k; ++x)
        if (x * x + y * y + z * z <= r * r) c.positions.push_back({double(x), double(y), double(z)});
  return c;
}

std::vector<double> flat(const std::vector<Vec3>& v) {
  std::vector<double> out;
  for (const Vec3& p : v) out.insert(out.end(), {p.x, p.y, p.z});
  return out;
}

}  // namespace

TEST(PolygonizeLimits, GridBudgetIsCheckedBeforeAllocatingAndSettable) {
  const PointCloud c = ball(4000);
  const PolygonizeResult ok = polygonize(c);
  ASSERT_GT(ok.stats.grid_bytes, 0u);
  PolygonizeOptions o;
  o.max_grid_bytes = ok.stats.grid_bytes - 1;
  PM_EXPECT_ERROR(polygonize(c, o), Status::LimitExceeded, "max_grid_bytes");
  o.max_grid_bytes = ok.stats.grid_bytes;
  EXPECT_EQ(polygonize(c, o).mesh.triangles, ok.mesh.triangles);
  // A cell size 1000x too small: refused at once (the grid would need petabytes).
  o = {};
  o.cell_size = ok.stats.cell_size / 1000;
  const auto t0 = Clock::now();
  PM_EXPECT_ERROR(polygonize(c, o), Status::LimitExceeded, "grid memory budget");
  EXPECT_LT(seconds(Clock::now() - t0), 5.0);
  // 0 = no limit (a small case that fits).
  o = {};
  o.max_grid_bytes = 0;
  EXPECT_EQ(polygonize(c, o).mesh.triangles, ok.mesh.triangles);
}

TEST(PolygonizeLimits, BudgetAndBadValuesThroughTheCAbi) {
  const PointCloud c = ball(2000);
  const auto pos = flat(c.positions);
  pm_cloud* cloud = nullptr;
  ASSERT_EQ(pm_cloud_create(pos.data(), nullptr, c.size(), &cloud), PM_OK);
  pm_polygonize_options o;
  pm_polygonize_options_init(&o);
  EXPECT_EQ(o.max_grid_bytes, uint64_t(4) << 30);
  o.max_grid_bytes = 100000;
  pm_mesh* mesh = reinterpret_cast<pm_mesh*>(0x2);
  pm_polygonize_stats stats{};
  stats.struct_size = sizeof stats;
  stats.grid_bytes = 77;
  EXPECT_EQ(pm_polygonize_ex(cloud, nullptr, nullptr, &o, &mesh, &stats), PM_STATUS_LIMIT_EXCEEDED);
  EXPECT_NE(std::string(pm_last_error_message()).find("max_grid_bytes"), std::string::npos) << pm_last_error_message();
  EXPECT_EQ(mesh, reinterpret_cast<pm_mesh*>(0x2));
  EXPECT_EQ(stats.grid_bytes, 77u);

  pm_polygonize_options_init(&o);
  std::vector<double> radii(c.size(), 2.0), strengths(c.size(), 1.0);
  radii[17] = NAN;
  EXPECT_EQ(pm_polygonize(cloud, radii.data(), nullptr, &o, &mesh), PM_STATUS_INVALID_ARGUMENT);
  EXPECT_NE(std::string(pm_last_error_message()).find("radii[17]"), std::string::npos) << pm_last_error_message();
  radii[17] = -1;
  EXPECT_EQ(pm_polygonize(cloud, radii.data(), nullptr, &o, &mesh), PM_STATUS_INVALID_ARGUMENT);
  EXPECT_NE(std::string(pm_last_error_message()).find("radii[17]"), std::string::npos) << pm_last_error_message();
  radii[17] = 2.0;
  strengths[5] = INFINITY;
  EXPECT_EQ(pm_polygonize(cloud, radii.data(), strengths.data(), &o, &mesh), PM_STATUS_INVALID_ARGUMENT);
  EXPECT_NE(std::string(pm_last_error_message()).find("strengths[5]"), std::string::npos) << pm_last_error_message();
  o.radius = -1;
  EXPECT_EQ(pm_polygonize(cloud, nullptr, nullptr, &o, &mesh), PM_STATUS_INVALID_ARGUMENT);
  pm_polygonize_options_init(&o);
  o.kernel = 99;
  EXPECT_EQ(pm_polygonize(cloud, nullptr, nullptr, &o, &mesh), PM_STATUS_INVALID_ARGUMENT);
  EXPECT_EQ(pm_polygonize(nullptr, nullptr, nullptr, nullptr, &mesh), PM_STATUS_INVALID_ARGUMENT);
  EXPECT_EQ(std::string(pm_last_error_message()), "cloud is NULL");
  EXPECT_EQ(pm_polygonize(cloud, nullptr, nullptr, nullptr, nullptr), PM_STATUS_INVALID_ARGUMENT);
  EXPECT_EQ(std::string(pm_last_error_message()), "out_mesh is NULL");
  EXPECT_EQ(mesh, reinterpret_cast<pm_mesh*>(0x2));
  pm_cloud_destroy(cloud);
}

// A cell far larger than the particles' radius: each block of cells scanned every empty
// cell of the particle grid under it, 3.8e8 lookups per block (8 particles took 8 s in
// Release and timed out under the fuzzer). The scan now visits the occupied cells instead.
TEST(PolygonizeLimits, CellsFarLargerThanTheRadiusStayCheap) {
  PointCloud c;
  c.positions = {{0, 0, 0}, {0, 0, 0}, {-25.5, 0, 0.5}, {0, 0, 0}, {0, 1.5e-36, 2.5}, {0, 0, -0.000244140625},
                 {-0.000244140625, -0.000244140625, -0.000244140625}};
  PolygonizeOptions o;
  o.kernel = Kernel::Poly6;
  o.threshold = 1.5e-36;
  o.cell_size = 0.0625;  // R defaults to 2 x spacing = 0.0007: 90 cells of the particle grid per cell
  const auto t0 = Clock::now();
  const PolygonizeResult r = polygonize(c, o);
  EXPECT_LT(seconds(Clock::now() - t0), 5.0) << "a scan of empty cells, not a check";
  EXPECT_GT(r.stats.sampled_blocks, 0u);
  EXPECT_TRUE(topology_report(r.mesh).manifold);
}

TEST(Cancellation, PolygonizeMillionParticles) {
  const PointCloud c = ball(million());
  expect_prompt_cancellation("polygonize", [&](const ProgressCallback& p) {
    PolygonizeOptions o;
    o.progress = p;
    polygonize(c, o);
  });
}

// The short edges' collapses are a stage of their own, and a request to stop made in it ends
// the call with Cancelled (the collapses ask the callback as they go).
TEST(Cancellation, PolygonizeCollapsingEdges) {
  PointCloud c = ball(kSanitized ? 4000 : 30000);
  for (size_t i = 0; i < c.size(); ++i)
    c.positions[i] += Vec3{std::sin(i * 1.3) * 0.3, std::cos(i * 0.7) * 0.3, std::sin(i * 2.9) * 0.3};
  PolygonizeOptions o;
  o.collapse_edges = 0.3;
  bool seen = false;
  o.progress = [&](std::string_view stage, double) {
    seen = seen || stage == "collapsing short edges";
    return !seen;
  };
  PM_EXPECT_ERROR(polygonize(c, o), Status::Cancelled, "cancelled");
  EXPECT_TRUE(seen);
  o.progress = {};
  EXPECT_GT(polygonize(c, o).stats.edges_collapsed, 0u);
}

TEST(Determinism, Polygonize) {
  PointCloud c = ball(30000);
  // Jitter, per-particle radii and strengths: sums in a different order would show.
  std::vector<double> radii, strengths;
  for (size_t i = 0; i < c.size(); ++i) {
    c.positions[i] += Vec3{std::sin(i * 1.3) * 0.3, std::cos(i * 0.7) * 0.3, std::sin(i * 2.9) * 0.3};
    radii.push_back(1.8 + 0.4 * std::abs(std::sin(double(i))));
    strengths.push_back(0.8 + 0.4 * std::abs(std::cos(double(i))));
  }
  uint64_t first = 0;
  for (int t : {1, 2, 3, 0, 1, 0}) {
    PolygonizeOptions o;
    o.threads = t;
    o.radii = radii;
    o.strengths = strengths;
    const uint64_t h = mesh_hash(polygonize(c, o).mesh);
    if (first == 0) first = h;
    EXPECT_EQ(h, first) << "threads = " << t;
  }
}
