// Loop filling (surface/hole_fill.h): holes narrower than the fill limit close, wider
// openings stay open, and an isolated patch's outline is never capped.
#include "surface/hole_fill.h"

#include <gtest/gtest.h>

#include <cmath>

#include "stage_support.h"

using namespace particlemesh;
using namespace particlemesh::detail;

namespace {

// Fill options with every point's edge limit L (kept alive in `limits`).
FillOptions with_limit(std::vector<double>& limits, size_t points, double L) {
  limits.assign(points, L);
  FillOptions o;
  o.max_edge = &limits;
  return o;
}

// A 7 x 7-point sheet with the points of the k x k block at (2, 2) taken out.
std::vector<uint32_t> block(const test::Sheet& s, size_t k) {
  std::vector<uint32_t> out;
  for (size_t j = 2; j < 2 + k; ++j)
    for (size_t i = 2; i < 2 + k; ++i) out.push_back(s.id(i, j));
  return out;
}

}  // namespace

TEST(HoleFill, LoopWidthIsTheShortestPossibleLongestEdge) {
  const std::vector<Vec3> P = {{0, 0, 0}, {2, 0, 0}, {2, 1, 0}, {0, 1, 0}};
  std::vector<double> L;
  // A 2 x 1 rectangle: its best triangulation's longest edge is a diagonal, sqrt(5).
  EXPECT_NEAR(loop_width(P, {0, 1, 2, 3}, with_limit(L, 4, 1.0)), std::sqrt(5.0), 1e-12);
  EXPECT_NEAR(loop_width(P, {0, 1, 2, 3}, with_limit(L, 4, 2.0)), std::sqrt(5.0) / 2, 1e-12);
  // Each edge counts in units of its own limit (the mean of its ends'): with limits 1 at the
  // left and 3 at the right, the diagonals' limit is 2 and the right side's (length 1) is 3.
  L = {1, 3, 3, 1};
  FillOptions o;
  o.max_edge = &L;
  EXPECT_NEAR(loop_width(P, {0, 1, 2, 3}, o), std::sqrt(5.0) / 2, 1e-12);
}

TEST(HoleFill, HolesWithinTheEdgeLimitCloseWiderOnesStayOpen) {
  const test::Sheet s(7, 7);
  // One missing point: a 6-edge loop around it (its six triangles), spanned by diagonals of
  // sqrt(2) and 2.
  {
    EditableSurface e(s.P, s.frames, s.without(block(s, 1)));
    std::vector<double> L;
    FillOptions o = with_limit(L, s.P.size(), 1.5);  // fill limit 1.5 x 1.5 = 2.25: fillable
    FillStats st;
    EXPECT_EQ(fill_loops(e, 100, o, st), 1u);
    EXPECT_EQ(e.trace_loops().size(), 1u);  // only the outline is left
    EXPECT_EQ(st.holes_filled, 1u);
    EXPECT_EQ(st.hole_triangles, 4u);       // 6 - 2
    for (const Triangle& t : e.take())     // the patch winds as the sheet does
      EXPECT_GT(cross(s.P[t[1]] - s.P[t[0]], s.P[t[2]] - s.P[t[0]]).z, 0);
  }
  // A missing 3 x 3 block: a loop whose narrowest span is 4.
  {
    EditableSurface e(s.P, s.frames, s.without(block(s, 3)));
    std::vector<double> L;
    FillOptions o = with_limit(L, s.P.size(), 2.0);  // fill limit 3: narrower than the opening
    FillStats st;
    EXPECT_EQ(fill_loops(e, 100, o, st), 0u);
    ASSERT_EQ(e.trace_loops().size(), 2u);
    EXPECT_NEAR(loop_width(s.P, e.trace_loops()[1], o), 2.0, 1e-12);  // 4 / L
    o = with_limit(L, s.P.size(), 3.0);  // fill limit 4.5: wide enough
    EXPECT_EQ(fill_loops(e, 100, o, st), 1u);
    EXPECT_EQ(e.trace_loops().size(), 1u);
    // Every fill edge is within the limit.
    for (const Triangle& t : e.take())
      for (int k = 0; k < 3; ++k) EXPECT_LE(distance(s.P[t[k]], s.P[t[(k + 1) % 3]]), 4.5);
  }
  // Loops longer than max_size are left.
  {
    EditableSurface e(s.P, s.frames, s.without(block(s, 1)));
    std::vector<double> L;
    const FillOptions o = with_limit(L, s.P.size(), 1.5);
    FillStats st;
    EXPECT_EQ(fill_loops(e, 5, o, st), 0u);
  }
}

TEST(HoleFill, AnIsolatedPatchIsNotCappedIntoAPillow) {
  // A lone square (two triangles): its outline is its outside. Capping it would fold 180
  // degrees back onto it.
  const test::Sheet s(2, 2);
  EditableSurface e(s.P, s.frames, s.tris);
  std::vector<double> L;
  const FillOptions o = with_limit(L, s.P.size(), 2.0);
  FillStats st;
  EXPECT_EQ(fill_loops(e, 100, o, st), 0u);
  EXPECT_EQ(fill_folded_loops(e, 100, o, st), 0u);
  EXPECT_EQ(e.take().size(), 2u);
}
