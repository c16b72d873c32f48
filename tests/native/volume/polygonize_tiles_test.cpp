// Polygonizing one cloud as tiles (PolygonizeOptions::domain_min, domain_max_radius, cells):
// each tile, given the whole cloud's anchor, its cell range and the particles within reach in
// their order in the cloud, yields exactly the whole cloud's triangles in its cells; the tiles'
// seam vertices are the same bit for bit. Also through the C ABI (flags, stats.origin).
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <functional>
#include <limits>
#include <map>
#include <set>
#include <string>
#include <vector>

#include "particlemesh/core/error.h"
#include "particlemesh/particlemesh.h"
#include "particlemesh/spatial/neighbor_grid.h"
#include "particlemesh/volume/polygonize.h"
#include "support/test_support.h"

using namespace particlemesh;
using particlemesh::test::status_of;

namespace {

using Corner = std::array<double, 3>;
using Face = std::array<Corner, 3>;

Corner key(const Vec3& v) { return {v.x, v.y, v.z}; }


// Each triangle as its three corner positions, sorted (order and numbering aside).
std::multiset<Face> faces(const TriMesh& m) {
  std::multiset<Face> out;
  for (const Triangle& t : m.triangles) {
    Face f{key(m.positions[t[0]]), key(m.positions[t[1]]), key(m.positions[t[2]])};
    std::sort(f.begin(), f.end());
    out.insert(f);
  }
  return out;
}

// The particles within `reach` of the x-slab [x0, x1], in the cloud's order.
PointCloud slab(const PointCloud& c, double x0, double x1, double reach) {
  PointCloud out;
  for (const Vec3& p : c.positions)
    if (p.x >= x0 - reach && p.x <= x1 + reach) out.positions.push_back(p);
  return out;
}

Vec3 lowest(const PointCloud& c) {
  Vec3 m = c.positions[0];
  for (const Vec3& p : c.positions) m = {std::min(m.x, p.x), std::min(m.y, p.y), std::min(m.z, p.z)};
  return m;
}

}  // namespace

TEST(PolygonizeTiles, LatticeIsAnchoredAtTheLowerCornerAndTheLargestRadius) {
  const PointCloud c = test::random_cloud(3000, 11, 2.0);
  PolygonizeOptions o;
  o.radius = 0.3;
  const PolygonizeResult r = polygonize(c, o);
  const Vec3 lo = lowest(c);
  const double h = r.stats.cell_size;
  const Vec3 expected = (lo - Vec3{0.3, 0.3, 0.3}) - Vec3{1, 1, 1} * (9 * h);
  EXPECT_TRUE(r.stats.origin == expected);
}

TEST(PolygonizeTiles, TwoTilesAreTheWholeCloudsMesh) {
  const PointCloud c = test::jittered(test::random_cloud(12000, 3, 2.0), 0.01, 4);
  PolygonizeOptions o;
  o.radius = 0.22;
  o.kernel = Kernel::Poly6;
  const PolygonizeResult whole = polygonize(c, o);
  ASSERT_GT(whole.mesh.triangles.size(), 5000u);
  const double h = whole.stats.cell_size;
  const Vec3 origin = whole.stats.origin;
  const int64_t cut = int64_t((1.0 - origin.x) / h);
  const double seam = origin.x + double(cut) * h;
  constexpr int64_t kFar = int64_t(1) << 40;
  std::multiset<Face> together;
  std::set<Corner> left_vertices;
  size_t seam_shared = 0;
  for (int side = 0; side < 2; ++side) {
    PolygonizeOptions t = o;
    t.domain_min = lowest(c);
    t.cells = PolygonizeOptions::CellRange{{side ? cut : -kFar, -kFar, -kFar}, {side ? kFar : cut, kFar, kFar}};
    const PointCloud part = side ? slab(c, seam, 1e9, 0.22 + h) : slab(c, -1e9, seam, 0.22 + h);
    ASSERT_LT(part.size(), c.size());
    const PolygonizeResult r = polygonize(part, t);
    EXPECT_TRUE(r.stats.origin == origin);
    for (const Face& f : faces(r.mesh)) together.insert(f);
    for (const Vec3& v : r.mesh.positions) {
      if (side == 0) left_vertices.insert(key(v));
      else if (left_vertices.count(key(v))) {
        ++seam_shared;
        EXPECT_NEAR(v.x, seam, 1e-12);  // shared vertices lie on the seam's plane
      }
    }
  }
  EXPECT_GT(seam_shared, 50u);
  EXPECT_TRUE(together == faces(whole.mesh));  // every triangle once, none changed
}

// A few particles far larger than the rest are kept apart from the particle grid's cells
// (particle_grid_radius): tiles given the cloud's grid radius keep the same ones apart and
// again give exactly the whole cloud's triangles.
TEST(PolygonizeTiles, TilesKeepTheCloudsFewFarLargerParticlesApart) {
  const PointCloud c = test::jittered(test::random_cloud(12000, 3, 2.0), 0.01, 4);
  PolygonizeOptions o;
  o.kernel = Kernel::Poly6;
  o.radii.assign(c.size(), 0.22);
  o.radii[100] = 1.6;
  o.radii[7000] = 2.2;
  o.threshold = 1.5;
  const double grid_radius = particle_grid_radius(o.radii.data(), o.radii.size());
  ASSERT_EQ(grid_radius, 0.22);
  const PolygonizeResult whole = polygonize(c, o);
  ASSERT_GT(whole.mesh.triangles.size(), 5000u);
  const double h = whole.stats.cell_size, reach = 2.2 + h;
  const int64_t cut = int64_t((1.0 - whole.stats.origin.x) / h);
  const double seam = whole.stats.origin.x + double(cut) * h;
  constexpr int64_t kFar = int64_t(1) << 40;
  std::multiset<Face> together;
  for (int side = 0; side < 2; ++side) {
    PolygonizeOptions t = o;
    t.radii.clear();
    t.domain_min = lowest(c);
    t.domain_max_radius = 2.2;
    t.domain_grid_radius = grid_radius;
    t.cells = PolygonizeOptions::CellRange{{side ? cut : -kFar, -kFar, -kFar}, {side ? kFar : cut, kFar, kFar}};
    PointCloud part;
    for (size_t i = 0; i < c.size(); ++i) {
      const double x = c.positions[i].x;
      if (side ? x >= seam - reach : x <= seam + reach) {
        part.positions.push_back(c.positions[i]);
        t.radii.push_back(o.radii[i]);
      }
    }
    const PolygonizeResult r = polygonize(part, t);
    EXPECT_TRUE(r.stats.origin == whole.stats.origin);
    for (const Face& f : faces(r.mesh)) together.insert(f);
  }
  EXPECT_TRUE(together == faces(whole.mesh));
  // A grid radius above the largest radius is refused, naming it.
  PolygonizeOptions bad = o;
  bad.domain_max_radius = 2.2;
  bad.domain_grid_radius = 3.0;
  std::string msg;
  EXPECT_EQ(status_of([&] { polygonize(c, bad); }, &msg), Status::InvalidArgument);
  EXPECT_NE(msg.find("domain_grid_radius"), std::string::npos) << msg;
}

TEST(PolygonizeTiles, PerParticleRadiiNeedTheWholeCloudsLargestRadius) {
  const PointCloud c = test::random_cloud(4000, 5, 2.0);
  std::vector<double> radii(c.size());
  for (size_t i = 0; i < radii.size(); ++i) radii[i] = 0.15 + 0.1 * double(i % 7) / 7.0;
  PolygonizeOptions o;
  o.radii = radii;
  o.cell_size = 0.05;
  const PolygonizeResult whole = polygonize(c, o);
  // A tile of the left half, with its own radii (all below the largest) and the cloud's.
  PolygonizeOptions t = o;
  t.radii.clear();
  PointCloud part;
  for (size_t i = 0; i < c.size(); ++i)
    if (c.positions[i].x < 1.3 && radii[i] < 0.2) {
      part.positions.push_back(c.positions[i]);
      t.radii.push_back(radii[i]);
    }
  t.domain_min = lowest(c);
  t.domain_max_radius = *std::max_element(radii.begin(), radii.end());
  EXPECT_TRUE(polygonize(part, t).stats.origin == whole.stats.origin);
  t.domain_max_radius = 0.1;  // below a radius given
  std::string msg;
  EXPECT_EQ(status_of([&] { polygonize(part, t); }, &msg), Status::InvalidArgument);
  EXPECT_NE(msg.find("domain_max_radius"), std::string::npos) << msg;
}

TEST(PolygonizeTiles, BadTileOptionsGiveClearErrors) {
  const PointCloud c = test::random_cloud(500, 2);
  std::string msg;
  PolygonizeOptions o;
  o.radius = 0.2;
  o.domain_min = lowest(c) + Vec3{0, 0.01, 0};
  EXPECT_EQ(status_of([&] { polygonize(c, o); }, &msg), Status::InvalidArgument);
  EXPECT_NE(msg.find("domain_min.y"), std::string::npos) << msg;
  o.domain_min = Vec3{0, std::numeric_limits<double>::quiet_NaN(), 0};
  EXPECT_EQ(status_of([&] { polygonize(c, o); }, &msg), Status::InvalidArgument);
  o.domain_min.reset();
  o.cells = PolygonizeOptions::CellRange{{0, 0, 5}, {10, 10, 5}};
  EXPECT_EQ(status_of([&] { polygonize(c, o); }, &msg), Status::InvalidArgument);
  EXPECT_NE(msg.find("empty along z"), std::string::npos) << msg;
  // Dropping pieces or smoothing a tile would treat its cut-off parts as the surface's.
  o.cells = PolygonizeOptions::CellRange{{0, 0, 0}, {10, 10, 10}};
  o.surface_smoothing.iterations = 3;
  EXPECT_EQ(status_of([&] { polygonize(c, o); }, &msg), Status::InvalidArgument);
  EXPECT_NE(msg.find("whole surface"), std::string::npos) << msg;
  o.surface_smoothing.iterations = 0;
  o.min_component_particles = 2;
  EXPECT_EQ(status_of([&] { polygonize(c, o); }, &msg), Status::InvalidArgument);
  o.min_component_particles = 0;
  // A tile far above its domain's corner: a clear limit, not a wrapped block key (from the
  // particle grid, of cells R, or from the lattice, of cells h, whichever overflows first).
  o.cells.reset();
  o.domain_min = lowest(c) - Vec3{1e7, 0, 0};
  EXPECT_EQ(status_of([&] { polygonize(c, o); }, &msg), Status::LimitExceeded);
  EXPECT_NE(msg.find("along x"), std::string::npos) << msg;
  EXPECT_NE(msg.find("lower corner is domain_min"), std::string::npos) << msg;
  // The same with one particle (the message's search for a gap between particles needs two:
  // it read past the one; found by fuzzing).
  PointCloud one;
  one.positions = {c.positions[0]};
  EXPECT_EQ(status_of([&] { polygonize(one, o); }, &msg), Status::LimitExceeded);
  EXPECT_NE(msg.find("from the grid's lower corner x = "), std::string::npos) << msg;
  o.cell_size = 0.02;  // 350000 / 0.2 cells of the particle grid fit, 350000 / 0.02 of the lattice do not
  o.domain_min = lowest(c) - Vec3{350000, 0, 0};
  EXPECT_EQ(status_of([&] { polygonize(c, o); }, &msg), Status::LimitExceeded);
  EXPECT_NE(msg.find("above the lattice's origin along x"), std::string::npos) << msg;
  o.cell_size = 0;
  // A range that holds no cell of the particles: an empty mesh.
  o.domain_min.reset();
  o.cells = PolygonizeOptions::CellRange{{-100, -100, -100}, {-90, -90, -90}};
  EXPECT_TRUE(polygonize(c, o).mesh.positions.empty());
}

TEST(PolygonizeTiles, ThroughTheCAbi) {
  const PointCloud c = test::random_cloud(3000, 9, 2.0);
  std::vector<double> pos;
  for (const Vec3& p : c.positions) pos.insert(pos.end(), {p.x, p.y, p.z});
  pm_cloud* cloud = nullptr;
  ASSERT_EQ(pm_cloud_create(pos.data(), nullptr, c.size(), &cloud), PM_OK);
  pm_polygonize_options o;
  pm_polygonize_options_init(&o);
  EXPECT_EQ(o.flags, 0u);
  EXPECT_EQ(o.domain_max_radius, 0.0);
  o.radius = 0.25;
  pm_polygonize_stats s{};
  s.struct_size = sizeof s;
  pm_mesh* whole = nullptr;
  ASSERT_EQ(pm_polygonize_ex(cloud, nullptr, nullptr, &o, &whole, &s), PM_OK);
  const Vec3 lo = lowest(c);
  EXPECT_EQ(s.origin[0], (lo.x - 0.25) - 9 * s.cell_size);
  size_t nv = 0, nt = 0;
  ASSERT_EQ(pm_mesh_get_counts(whole, &nv, &nt), PM_OK);
  // The whole lattice as one range, anchored at the particles' own corner: the same mesh.
  o.flags = PM_POLYGONIZE_DOMAIN_MIN | PM_POLYGONIZE_CELL_RANGE;
  o.domain_min[0] = lo.x, o.domain_min[1] = lo.y, o.domain_min[2] = lo.z;
  for (int a = 0; a < 3; ++a) o.cell_min[a] = -1000000, o.cell_max[a] = 1000000;
  pm_mesh* ranged = nullptr;
  ASSERT_EQ(pm_polygonize(cloud, nullptr, nullptr, &o, &ranged), PM_OK);
  size_t nv2 = 0, nt2 = 0;
  ASSERT_EQ(pm_mesh_get_counts(ranged, &nv2, &nt2), PM_OK);
  EXPECT_EQ(nv2, nv);
  EXPECT_EQ(nt2, nt);
  o.flags = 0x8;
  pm_mesh* bad = reinterpret_cast<pm_mesh*>(0x2);
  EXPECT_EQ(pm_polygonize(cloud, nullptr, nullptr, &o, &bad), PM_STATUS_INVALID_ARGUMENT);
  EXPECT_NE(std::string(pm_last_error_message()).find("flags"), std::string::npos);
  EXPECT_EQ(bad, reinterpret_cast<pm_mesh*>(0x2));
  pm_mesh_destroy(whole);
  pm_mesh_destroy(ranged);
  pm_cloud_destroy(cloud);
}

TEST(NeighborGrid, AnchoredGridsOfSubsetsShareTheCells) {
  const PointCloud c = test::random_cloud(5000, 21, 3.0);
  const Vec3 lower{-0.5, -0.25, -1.0};
  const NeighborGrid whole(c.positions.data(), c.size(), 0.3, lower);
  std::vector<Vec3> half;
  for (const Vec3& p : c.positions)
    if (p.x > 1.7) half.push_back(p);
  const NeighborGrid part(half.data(), half.size(), 0.3, lower);
  for (const Vec3& p : half) EXPECT_TRUE(part.coord_of(p) == whole.coord_of(p));
  std::string msg;
  EXPECT_EQ(status_of([&] { NeighborGrid(c.positions.data(), c.size(), 0.3, Vec3{0.5, 0, 0}); }, &msg),
            Status::InvalidArgument);
  EXPECT_NE(msg.find("below the grid's lower corner"), std::string::npos) << msg;
}
