// Connected pieces of a mesh, their volumes, and dropping the small ones (alone and as
// polygonize's option).
#include "particlemesh/mesh/components.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "particlemesh/core/error.h"
#include "particlemesh/mesh/topology_report.h"
#include "particlemesh/sample/shapes.h"
#include "particlemesh/volume/polygonize.h"

using namespace particlemesh;

namespace {

// Two closed pieces: a unit box far from the origin, and a small box of side 0.2 beside it,
// with an unused vertex between them and a colour channel.
TriMesh two_boxes() {
  TriMesh big = box_mesh({1, 1, 1}), small = box_mesh({0.2, 0.2, 0.2});
  TriMesh m;
  const Vec3 far{1e6, -2e6, 3e6};
  for (const Vec3& p : big.positions) m.positions.push_back(p + far);
  m.positions.push_back({0, 0, 0});  // unused
  const uint32_t off = uint32_t(m.positions.size());
  for (const Vec3& p : small.positions) m.positions.push_back(p + far + Vec3{3, 0, 0});
  m.triangles = big.triangles;
  for (Triangle t : small.triangles) m.triangles.push_back({t[0] + off, t[1] + off, t[2] + off});
  m.normals.assign(m.positions.size(), Vec3{0, 0, 1});
  VertexAttribute a{"color", 1, {}};
  for (size_t v = 0; v < m.positions.size(); ++v) a.values.push_back(float(v));
  m.attributes.push_back(a);
  return m;
}

}  // namespace

TEST(MeshComponents, CountsAreasAndVolumesFarFromTheOrigin) {
  const TriMesh m = two_boxes();
  const MeshComponents c = mesh_components(m);
  ASSERT_EQ(c.volume.size(), 2u);
  // To the rounding of coordinates of 1e6 (1e-10): summed about the world origin, each term
  // would be ~1e18 and the sum off by hundreds.
  EXPECT_NEAR(c.volume[0], 1.0, 1e-8);
  EXPECT_NEAR(c.volume[1], 0.008, 1e-8);
  EXPECT_NEAR(c.area[0], 6.0, 1e-8);
  EXPECT_NEAR(c.area[1], 0.24, 1e-8);
  EXPECT_EQ(c.triangles[0], box_mesh({1, 1, 1}).triangles.size());
  const size_t nbig = box_mesh({1, 1, 1}).positions.size();
  EXPECT_EQ(c.vertex_component[0], 0u);
  EXPECT_EQ(c.vertex_component[nbig], UINT32_MAX);  // the unused vertex
  EXPECT_EQ(c.vertex_component[nbig + 1], 1u);
}

TEST(MeshComponents, DropsTheSmallPiecesAndKeepsEverythingElse) {
  TriMesh m = two_boxes();
  const size_t nbig = box_mesh({1, 1, 1}).positions.size();
  // A value per triangle corner (its triangle's index): it follows its triangle.
  std::vector<float> corner;
  for (size_t f = 0; f < m.triangles.size(); ++f) corner.insert(corner.end(), {float(f), float(f), float(f)});
  m.corner_attributes = {{"face", 1, corner}};
  TriMesh keep = m;
  EXPECT_EQ(remove_small_components(keep, 0.0), 0u);
  EXPECT_EQ(remove_small_components(keep, 0.005), 0u);
  EXPECT_EQ(keep.triangles, m.triangles);
  EXPECT_EQ(remove_small_components(m, 0.01), 1u);
  ASSERT_EQ(m.positions.size(), nbig + 1);  // the big box and the unused vertex
  ASSERT_EQ(m.normals.size(), nbig + 1);
  ASSERT_EQ(m.attributes[0].values.size(), nbig + 1);
  EXPECT_EQ(m.attributes[0].values[nbig], float(nbig));  // the channel follows its vertex
  EXPECT_EQ(m.triangles, box_mesh({1, 1, 1}).triangles);
  ASSERT_EQ(m.corner_attributes[0].values.size(), 3 * m.triangles.size());
  EXPECT_TRUE(std::equal(m.corner_attributes[0].values.begin(), m.corner_attributes[0].values.end(), corner.begin()));
  const TopologyReport r = topology_report(m);
  EXPECT_TRUE(r.closed);
  EXPECT_EQ(r.components, 1u);
  EXPECT_THROW(remove_small_components(m, std::nan("")), Error);
  m.triangles.push_back({0, 1, 999});
  EXPECT_THROW(mesh_components(m), Error);
}

// polygonize's options: a block with a few lone splashes drops them by volume or by
// particles' worth, and says how many.
TEST(MeshComponents, PolygonizeDropsSplashes) {
  PointCloud c;
  for (int z = 0; z < 10; ++z)
    for (int y = 0; y < 10; ++y)
      for (int x = 0; x < 10; ++x) c.positions.push_back({double(x), double(y), double(z)});
  // Three pairs of particles far out: small blobs at a low threshold.
  for (int k = 0; k < 3; ++k) {
    c.positions.push_back({30.0 + 10 * k, 0, 0});
    c.positions.push_back({30.5 + 10 * k, 0, 0});
  }
  PolygonizeOptions o;
  o.radius = 2;
  o.threshold = 0.5;
  const PolygonizeResult all = polygonize(c, o);
  EXPECT_EQ(topology_report(all.mesh).components, 4u);
  EXPECT_EQ(all.stats.components_removed, 0u);
  o.min_component_particles = 50;  // the block is ~1000 particles' worth, a pair a few
  const PolygonizeResult kept = polygonize(c, o);
  EXPECT_EQ(topology_report(kept.mesh).components, 1u);
  EXPECT_EQ(kept.stats.components_removed, 3u);
  EXPECT_NEAR(kept.stats.min_component_volume, 50.0, 1e-9);  // spacing 1
  EXPECT_EQ(kept.stats.vertices, kept.mesh.positions.size());
  o.min_component_particles = 0;
  o.min_component_volume = 50;
  EXPECT_EQ(polygonize(c, o).mesh.triangles, kept.mesh.triangles);
  o.min_component_volume = -1;
  EXPECT_THROW(polygonize(c, o), Error);
}
