// The repair passes (surface/repair.h): unpinching, fragments, unused particles, and the
// whole repair on a sheet with holes and a real opening.
#include "surface/repair.h"

#include <gtest/gtest.h>

#include "stage_support.h"
#include "support/test_support.h"

using namespace particlemesh;
using namespace particlemesh::detail;

TEST(Repair, UnpinchKeepsTheLargestFan) {
  // Around point 5 = (1, 1) of a 4 x 4-point sheet: one triangle of the square below-left
  // (a fan of 1) and three triangles above-right of it (a fan of 3), sharing no edge at 5.
  const test::Sheet s(4, 4);
  const std::vector<Triangle> tris = {{0, 1, 5}, {5, 6, 10}, {5, 10, 9}, {4, 5, 9}};
  EditableSurface e(s.P, s.frames, tris);
  EXPECT_EQ(unpinch(e), 1u);
  EXPECT_EQ(test::canonical(e.take()), test::canonical({{5, 6, 10}, {5, 10, 9}, {4, 5, 9}}));
  EXPECT_EQ(unpinch(e), 0u);
}

TEST(Repair, UnpinchLooksAgainWhereTrianglesChanged) {
  // Two closed fans at vertex 5 that share no edge (two sheets touching at a point): 5 starts
  // no boundary edge, so only its added triangles make it a suspect. The first fan is indexed,
  // the second added after an unpinch that found nothing: the next one must look at 5 again;
  // after it, a triangle of the removed fan brought back pinches 5 once more.
  const test::Sheet s(4, 4);
  const std::vector<Triangle> first = {{5, 0, 1}, {5, 1, 2}, {5, 2, 3}, {5, 3, 0}};
  EditableSurface e(s.P, s.frames, first);
  EXPECT_EQ(unpinch(e), 0u);
  for (const Triangle& t : std::vector<Triangle>{{5, 8, 9}, {5, 9, 10}, {5, 10, 11}, {5, 11, 8}}) e.add_triangle(t);
  EXPECT_EQ(unpinch(e), 1u);
  size_t live = 0;
  uint32_t killed = EditableSurface::kNoTriangle;
  for (uint32_t t = 0; t < e.triangle_slots(); ++t) {
    if (e.alive(t)) ++live;
    else killed = t;
  }
  EXPECT_EQ(live, 4u);
  ASSERT_NE(killed, EditableSurface::kNoTriangle);
  EXPECT_EQ(unpinch(e), 0u);
  e.revive_triangle(killed);
  EXPECT_EQ(unpinch(e), 1u);
  EXPECT_EQ(unpinch(e), 0u);
}

TEST(Repair, UnusedParticlesAreInsertedIntoTheTriangleOrEdgeUnderThem) {
  // A sheet with two extra particles: one over the middle of a triangle (0.1 above it) and
  // one on an outline edge. Both end up vertices of the surface; the windings stay.
  test::Sheet s(4, 4);
  s.P.push_back({1.7, 1.2, 0.1});  // over the triangle (1,1) (2,1) (2,2)
  s.P.push_back({1.5, 0, 0});      // on the edge (1,0) - (2,0)
  s.N.push_back({0, 0, 1});
  s.N.push_back({0, 0, 1});
  s.frames = tangent_frames(s.N);
  const uint32_t over = 16, on_edge = 17;
  EditableSurface e(s.P, s.frames, s.tris);
  const std::vector<uint8_t> active(s.P.size(), 1);
  // The raw triangles at the particles say which surface is around them.
  const std::vector<Triangle> raw = {{s.id(1, 1), s.id(2, 1), over}, {s.id(1, 0), s.id(2, 0), on_edge},
                                     {s.id(1, 0), on_edge, s.id(1, 1)}};
  const std::vector<double> L(s.P.size(), 2.0);
  FillOptions o;
  o.max_edge = &L;
  std::unique_ptr<NeighborGrid> near;
  EXPECT_EQ(insert_unused(e, active, raw, o, near), 2u);
  const auto tris = e.take();
  EXPECT_EQ(tris.size(), 18u + 2 + 1);  // a triangle split in three, an edge's triangle in two
  size_t at_over = 0, at_edge = 0;
  for (const Triangle& t : tris) {
    for (uint32_t v : t) at_over += v == over, at_edge += v == on_edge;
    EXPECT_GT(cross(s.P[t[1]] - s.P[t[0]], s.P[t[2]] - s.P[t[0]]).z, 0);
  }
  EXPECT_EQ(at_over, 3u);
  EXPECT_EQ(at_edge, 2u);
  for (const auto& [edge, count] : test::edge_counts(tris)) EXPECT_LE(count, 2);
}

TEST(Repair, FragmentsAgainstALargerPieceDissolveLonePiecesStay) {
  // A sheet and two lone triangles beside it; a raw triangle joins the first to the sheet.
  test::Sheet s(4, 4);
  for (const Vec3& p : {Vec3{4, 0, 0}, Vec3{5, 0, 0}, Vec3{4, 1, 0}, Vec3{9, 0, 0}, Vec3{10, 0, 0}, Vec3{9, 1, 0}}) {
    s.P.push_back(p);
    s.N.push_back({0, 0, 1});
  }
  s.frames = tangent_frames(s.N);
  std::vector<Triangle> tris = s.tris;
  tris.push_back({16, 17, 18});
  tris.push_back({19, 20, 21});
  EditableSurface e(s.P, s.frames, tris);
  const std::vector<Triangle> raw = {{s.id(3, 0), 16, 18}};
  EXPECT_EQ(drop_fragments(e, raw), 1u);
  const auto kept = test::canonical(e.take());
  EXPECT_EQ(kept.size(), 19u);
  EXPECT_TRUE(std::binary_search(kept.begin(), kept.end(), Triangle{19, 20, 21}));
}

TEST(Repair, SheetWithHolesClosesThemAndKeepsItsOutline) {
  // A 12 x 12 sheet missing two single points (small holes) and a 4 x 4 block (an opening
  // wider than the fill limit). The repair fills both holes and reports the opening.
  const test::Sheet s(12, 12);
  std::vector<uint32_t> out = {s.id(2, 2), s.id(8, 3)};
  for (size_t j = 6; j < 10; ++j)
    for (size_t i = 4; i < 8; ++i) out.push_back(s.id(i, j));
  EditableSurface e(s.P, s.frames, s.without(out));
  std::vector<uint8_t> active(s.P.size(), 1);
  for (uint32_t v : out) active[v] = 0;  // not particles: nothing to insert
  RepairOptions o;
  const std::vector<double> L(s.P.size(), 2.0);
  o.fill.max_edge = &L;
  RepairStats st;
  test::QuietTracker q;
  repair_surface(e, active, {}, o, st, q.tracker);
  EXPECT_EQ(st.holes_filled, 2u);
  EXPECT_EQ(st.holes_left, 2u);  // the outline and the opening
  EXPECT_EQ(st.largest_hole_left, 44u);
  ASSERT_EQ(st.open_loops.size(), 2u);
  for (const auto& [edges, width] : st.open_loops) EXPECT_GT(width, o.fill.fill_edge_factor);
}

TEST(Repair, InsertedParticlesStayWithinTheFillLimit) {
  // Beside a sheet (spacing 1, L = 2, fill limit 3): a particle 0.8 beyond its outline becomes
  // a triangle on the nearest outline edge (the edge's triangle stays); one 2.5 above its
  // middle, whose edges to any triangle's corners would be over 3, stays out.
  test::Sheet s(5, 5);
  s.P.push_back({2.5, -0.8, 0});  // beyond the edge (2,0) - (3,0)
  s.P.push_back({2.0, 2.0, 3.2});  // far above point (2, 2)
  s.N.push_back({0, 0, 1});
  s.N.push_back({0, 0, 1});
  s.frames = tangent_frames(s.N);
  const uint32_t beside = 25, above = 26;
  EditableSurface e(s.P, s.frames, s.tris);
  const std::vector<uint8_t> active(s.P.size(), 1);
  const std::vector<Triangle> raw = {{s.id(2, 0), s.id(3, 0), beside}, {s.id(2, 2), s.id(3, 2), above}};
  const std::vector<double> L(s.P.size(), 2.0);
  FillOptions o;
  o.max_edge = &L;
  std::unique_ptr<NeighborGrid> near;
  EXPECT_EQ(insert_unused(e, active, raw, o, near), 1u);
  const auto tris = e.take();
  EXPECT_EQ(tris.size(), s.tris.size() + 1);  // an ear: nothing split
  bool ear = false;
  for (const Triangle& t : tris) {
    for (uint32_t v : t) EXPECT_NE(v, above);
    ear = ear || test::canonical({t})[0] == test::canonical({{s.id(2, 0), s.id(3, 0), beside}})[0];
    EXPECT_GT(cross(s.P[t[1]] - s.P[t[0]], s.P[t[2]] - s.P[t[0]]).z, 0);
  }
  EXPECT_TRUE(ear);
  for (const auto& [edge, count] : test::edge_counts(tris)) EXPECT_LE(distance(s.P[edge.first], s.P[edge.second]), 3.0);
}
