#include "particlemesh/mesh/topology_report.h"

#include <gtest/gtest.h>

#include "particlemesh/sample/shapes.h"
#include "support/test_support.h"

using namespace particlemesh;

namespace {
TriMesh tetrahedron() {
  TriMesh m;
  m.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  m.triangles = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};  // outward
  return m;
}
}  // namespace

TEST(TopologyReport, ClosedOutwardTetrahedron) {
  const TopologyReport r = topology_report(tetrahedron());
  EXPECT_EQ(r.edges, 6u);
  EXPECT_EQ(r.manifold_edges, 6u);
  EXPECT_EQ(r.euler_characteristic, 2);
  EXPECT_TRUE(r.closed);
  EXPECT_TRUE(r.manifold);
  EXPECT_TRUE(r.consistently_oriented);
  EXPECT_TRUE(r.outward);
  ASSERT_EQ(r.per_component.size(), 1u);
  EXPECT_EQ(r.per_component[0].genus, 0);
  EXPECT_NEAR(r.per_component[0].signed_volume, 1.0 / 6.0, 1e-12);
}

TEST(TopologyReport, InwardAndInconsistentWindingsAreSeen) {
  TriMesh m = tetrahedron();
  for (auto& t : m.triangles) std::swap(t[1], t[2]);
  TopologyReport r = topology_report(m);
  EXPECT_TRUE(r.consistently_oriented);
  EXPECT_FALSE(r.outward);
  EXPECT_LT(r.per_component[0].signed_volume, 0);
  std::swap(m.triangles[0][1], m.triangles[0][2]);  // flip one face back
  r = topology_report(m);
  EXPECT_FALSE(r.consistently_oriented);
  EXPECT_EQ(r.orientation_conflicts, 3u);
}

TEST(TopologyReport, TorusHasGenusOneAndIcosphereGenusZero) {
  const TopologyReport t = topology_report(torus_mesh(1, 0.3, 24, 12));
  EXPECT_EQ(t.euler_characteristic, 0);
  EXPECT_TRUE(t.closed);
  EXPECT_EQ(t.per_component[0].genus, 1);
  EXPECT_TRUE(t.outward);
  const TopologyReport s = topology_report(icosphere_mesh(3));
  EXPECT_EQ(s.euler_characteristic, 2);
  EXPECT_TRUE(s.closed && s.outward);
  EXPECT_EQ(s.triangles, 20u * 64u);
}

TEST(TopologyReport, OpenDiskHasOneBoundaryLoop) {
  TriMesh m;
  m.positions = {{0, 0, 0}};
  for (int i = 0; i < 6; ++i) m.positions.push_back({std::cos(i * 1.047), std::sin(i * 1.047), 0});
  for (uint32_t i = 0; i < 6; ++i) m.triangles.push_back({0, 1 + i, 1 + (i + 1) % 6});
  const TopologyReport r = topology_report(m);
  EXPECT_EQ(r.boundary_edges, 6u);
  EXPECT_EQ(r.boundary_loops, 1u);
  EXPECT_EQ(r.euler_characteristic, 1);
  EXPECT_TRUE(r.manifold);
  EXPECT_FALSE(r.closed);
  EXPECT_EQ(r.per_component[0].genus, 0);
}

TEST(TopologyReport, PinchedVertexAndFinAreNonManifold) {
  // Two triangles that share only vertex 0: a pinch. The boundary is traced as two loops.
  TriMesh pinch;
  pinch.positions = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {-1, 0, 0}, {-1, -1, 0}};
  pinch.triangles = {{0, 1, 2}, {0, 3, 4}};
  TopologyReport r = topology_report(pinch);
  EXPECT_EQ(r.nonmanifold_vertices, 1u);
  EXPECT_FALSE(r.manifold);
  EXPECT_EQ(r.components, 2u);
  EXPECT_EQ(r.boundary_loops, 2u);
  // Three triangles on one edge: a fin.
  TriMesh fin;
  fin.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}};
  fin.triangles = {{0, 1, 2}, {1, 0, 3}, {0, 1, 4}};
  r = topology_report(fin);
  EXPECT_EQ(r.nonmanifold_edges, 1u);
  EXPECT_FALSE(r.consistently_oriented);
  EXPECT_EQ(r.components, 1u);
}

TEST(TopologyReport, DegenerateDuplicateAndUnusedAreCounted) {
  TriMesh m = tetrahedron();
  m.positions.push_back({5, 5, 5});         // unused
  m.triangles.push_back({0, 1, 2});         // duplicate of {0, 2, 1} as a vertex set
  m.triangles.push_back({1, 1, 2});         // repeated index
  const TopologyReport r = topology_report(m);
  EXPECT_EQ(r.vertices, 5u);
  EXPECT_EQ(r.vertices_used, 4u);
  EXPECT_EQ(r.duplicate_triangles, 1u);
  EXPECT_EQ(r.degenerate_triangles, 1u);
}

TEST(TopologyReport, EmptyMesh) {
  const TopologyReport r = topology_report(TriMesh{});
  EXPECT_EQ(r.triangles, 0u);
  EXPECT_EQ(r.components, 0u);
  EXPECT_FALSE(r.closed);
}
