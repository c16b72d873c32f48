// The surface the repair edits (surface/editable_surface.h): boundary half-edges kept up to
// date, loops traced and split at repeated vertices, pieces.
#include "surface/editable_surface.h"

#include <gtest/gtest.h>

#include <algorithm>

#include "stage_support.h"

using namespace particlemesh;
using namespace particlemesh::detail;

TEST(EditableSurface, BoundaryFollowsAddedAndKilledTriangles) {
  const test::Sheet s(4, 4);  // 3 x 3 squares, 18 triangles
  EditableSurface e(s.P, s.frames, s.tris);
  EXPECT_EQ(e.boundary().size(), 12u);  // the outline: 12 unit edges
  auto loops = e.trace_loops();
  ASSERT_EQ(loops.size(), 1u);
  EXPECT_EQ(loops[0].size(), 12u);
  EXPECT_EQ(loops[0][0], 0u);  // starts at its smallest vertex
  // Kill the two triangles of the middle square: a second loop of 4 edges.
  for (uint32_t t = 0; t < e.triangle_slots(); ++t) {
    const Triangle& T = e.triangle(t);
    if (T[0] == s.id(1, 1) && (T[1] == s.id(2, 1) || T[1] == s.id(2, 2))) e.kill_triangle(t);
  }
  loops = e.trace_loops();
  ASSERT_EQ(loops.size(), 2u);
  EXPECT_EQ(loops[1], (std::vector<uint32_t>{s.id(1, 1), s.id(1, 2), s.id(2, 2), s.id(2, 1)}));
  EXPECT_FALSE(e.edge_exists(s.id(1, 1), s.id(2, 2)));
  EXPECT_TRUE(e.directed_used(s.id(2, 1), s.id(1, 1)));  // the square below holds 2,1 -> 1,1
  EXPECT_TRUE(e.starts_boundary(s.id(1, 1)));
  // Put them back: one loop again, and the added triangles are known.
  e.add_triangle({s.id(1, 1), s.id(2, 1), s.id(2, 2)});
  e.add_triangle({s.id(1, 1), s.id(2, 2), s.id(1, 2)});
  EXPECT_EQ(e.trace_loops().size(), 1u);
  EXPECT_FALSE(e.starts_boundary(s.id(1, 1)));
  EXPECT_EQ(e.take().size(), 18u);
  size_t added = 0;
  for (uint32_t v = 0; v < e.point_count(); ++v) added += e.has_added_triangles(v);
  EXPECT_EQ(added, 4u);
  EXPECT_TRUE(e.has_added_triangles(s.id(2, 2)));
}

TEST(EditableSurface, ChangedVerticesAreTheCornersOfTrianglesAddedKilledOrRevived) {
  const test::Sheet s(4, 4);
  EditableSurface e(s.P, s.frames, s.tris);
  EXPECT_TRUE(e.take_changed_vertices().empty());  // indexing changes nothing
  e.kill_triangle(0);
  const Triangle T = e.triangle(0);
  std::vector<uint32_t> got = e.take_changed_vertices();
  std::sort(got.begin(), got.end());
  std::vector<uint32_t> want(T.begin(), T.end());
  std::sort(want.begin(), want.end());
  EXPECT_EQ(got, want);
  EXPECT_TRUE(e.take_changed_vertices().empty());  // the record starts afresh
  e.revive_triangle(0);
  e.add_triangle({s.id(3, 3), s.id(2, 3), s.id(3, 2)});  // (a copy's corners: each listed once)
  e.kill_triangle(0);
  got = e.take_changed_vertices();
  EXPECT_EQ(got.size(), 6u);
  std::sort(got.begin(), got.end());
  EXPECT_TRUE(std::unique(got.begin(), got.end()) == got.end());
}

TEST(EditableSurface, LoopsThroughAVertexTwiceAreSplitThere) {
  // Two squares of a 3 x 3-point sheet that touch only at the centre (a pinch): the outline
  // passes the centre twice and is traced as two loops of 4.
  const test::Sheet s(3, 3);
  std::vector<Triangle> two;
  for (const Triangle& t : s.tris) {
    const bool lower_left = t[0] == s.id(0, 0), upper_right = t[0] == s.id(1, 1);
    if (lower_left || upper_right) two.push_back(t);
  }
  ASSERT_EQ(two.size(), 4u);
  EditableSurface e(s.P, s.frames, two);
  const auto loops = e.trace_loops();
  ASSERT_EQ(loops.size(), 2u);
  EXPECT_EQ(loops[0].size(), 4u);
  EXPECT_EQ(loops[1].size(), 4u);
  std::vector<uint32_t> piece, count;
  e.surface_pieces(piece, count);
  EXPECT_EQ(piece[s.id(2, 2)], 0u);  // one piece by shared vertices, named by vertex 0
  EXPECT_EQ(count[0], 4u);
}
