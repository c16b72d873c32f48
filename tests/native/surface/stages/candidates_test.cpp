// The extraction's candidates (surface/candidates.h): co-normality, orientation by the
// normals, the best-first rank, the corner lists; and the growth's rank queue.
#include "surface/candidates.h"

#include <gtest/gtest.h>

#include "stage_support.h"
#include "support/test_support.h"
#include "surface/rank_queue.h"
#include "surface/triangle_angles.h"

using namespace particlemesh;
using namespace particlemesh::detail;

TEST(RankQueue, TakesRanksSmallestFirstEachOnce) {
  RankQueue q(100000);
  EXPECT_TRUE(q.empty());
  for (uint32_t r : {70u, 5u, 99999u, 3u, 4097u, 70u}) q.push(r);
  std::vector<uint32_t> order;
  while (!q.empty()) order.push_back(q.pop());
  EXPECT_EQ(order, (std::vector<uint32_t>{3, 5, 70, 4097, 99999}));
  q.push(8);
  EXPECT_EQ(q.top(), 8u);
  EXPECT_FALSE(q.empty());
}

TEST(Candidates, CoNormalityOrientationRankAndCorners) {
  // A quad a b c d (not a square, so its triangles differ in quality), a point e beyond b
  // facing the other way, a point f nearly on the line a-b (a flat triangle a f b), a point g
  // with no normal and an inactive point h.
  const std::vector<Vec3> P = {{0, 0, 0}, {1, 0, 0}, {1.1, 1, 0}, {0, 0.9, 0}, {2, 0, 0},
                               {0.5, -0.05, 0}, {0, -1, 0}, {1, -1, 0}};
  std::vector<Vec3> N(P.size(), Vec3{0, 0, 1});
  N[4] = {0, 0, -1};
  N[6] = {0, 0, 0};
  std::vector<uint8_t> active(P.size(), 1);
  active[7] = 0;
  const std::vector<Triangle> raw = {{0, 1, 2}, {0, 1, 3}, {0, 1, 5}, {0, 2, 3}, {0, 5, 6},
                                     {1, 2, 3}, {1, 2, 4}, {1, 5, 7}};
  const std::vector<Frame> frames = tangent_frames(N);
  test::QuietTracker q;
  const CandidateSet c = rank_candidates(P, N, frames, active, raw, std::cos(120 * M_PI / 180), q.tracker);
  // {1,2,4}: corner normals 180 degrees apart; {0,5,6}: g has no normal; {1,5,7}: h inactive.
  EXPECT_EQ(c.rejected_conormal, 3u);
  ASSERT_EQ(c.cand.size(), 5u);
  // Every candidate winds counter-clockwise about +z, and the rank is by the largest angle.
  double previous = -2;
  for (const Triangle& t : c.cand) {
    EXPECT_GT(cross(P[t[1]] - P[t[0]], P[t[2]] - P[t[0]]).z, 0) << t[0] << t[1] << t[2];
    const double quality = -min_corner_cosine(P[t[0]], P[t[1]], P[t[2]]);
    EXPECT_GE(quality, previous);
    previous = quality;
  }
  // The flat triangle a f b (largest angle ~169 degrees) ranks last, from flat_from.
  EXPECT_EQ(c.flat_from, 4u);
  EXPECT_EQ(test::canonical({c.cand[4]})[0], (Triangle{0, 1, 5}));
  // Each candidate's corner is in its vertex's list once, with its winding's neighbours.
  ASSERT_EQ(c.corner_offset.size(), P.size() + 1);
  EXPECT_EQ(c.corner_offset.back(), 3 * c.cand.size());
  for (uint32_t r = 0; r < c.cand.size(); ++r)
    for (int k = 0; k < 3; ++k) {
      const uint32_t v = c.cand[r][k];
      int found = 0;
      for (uint32_t i = c.corner_offset[v]; i < c.corner_offset[v + 1]; ++i)
        if (c.corners[i].c == r) {
          ++found;
          EXPECT_EQ(c.corners[i].succ, c.cand[r][(k + 1) % 3]);
          EXPECT_EQ(c.corners[i].pred, c.cand[r][(k + 2) % 3]);
          EXPECT_GT(c.corners[i].arc.length, 0.0f);
        }
      EXPECT_EQ(found, 1);
    }
}

TEST(Candidates, FacingNormalsAreSeparatedAtAnyAngle) {
  // Two parallel sheets 0.5 apart with normals facing each other: the triangles across the
  // gap have corners 180 degrees apart, so even the loosest angle below 180 drops them.
  const std::vector<Vec3> P = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 0.5}, {1, 0, 0.5}, {0, 1, 0.5}};
  const std::vector<Vec3> N = {{0, 0, 1}, {0, 0, 1}, {0, 0, 1}, {0, 0, -1}, {0, 0, -1}, {0, 0, -1}};
  const std::vector<uint8_t> active(P.size(), 1);
  const std::vector<Triangle> raw = {{0, 1, 2}, {0, 1, 3}, {0, 3, 4}, {3, 4, 5}};
  test::QuietTracker q;
  const CandidateSet c = rank_candidates(P, N, tangent_frames(N), active, raw, std::cos(179 * M_PI / 180), q.tracker);
  EXPECT_EQ(test::canonical(c.cand), (std::vector<Triangle>{{0, 1, 2}, {3, 4, 5}}));
  // The upper sheet faces down: its triangle winds clockwise seen from +z.
  for (const Triangle& t : c.cand)
    if (t[0] >= 3) {
      EXPECT_LT(cross(P[t[1]] - P[t[0]], P[t[2]] - P[t[0]]).z, 0);
    }
}

TEST(Candidates, EdgesAlongTheViewRaysAreDepthJumps) {
  // Seen from the origin: a triangle on a plate facing it, and one joining the plate's edge to
  // a point 5 spacings behind it on nearly the same ray (a depth jump). Given the viewpoint,
  // only the second is dropped, and counted apart from co-normality.
  const std::vector<Vec3> P = {{0, 0, 10}, {1, 0, 10}, {0, 1, 10}, {1.2, 0.1, 15}};
  const std::vector<Vec3> N(P.size(), Vec3{0, 0, -1});
  const std::vector<uint8_t> active(P.size(), 1);
  const std::vector<Triangle> raw = {{0, 1, 2}, {0, 1, 3}};
  test::QuietTracker q;
  ViewRays view;
  EXPECT_EQ(rank_candidates(P, N, tangent_frames(N), active, raw, -1.0, q.tracker, view).cand.size(), 2u);
  view.active = true;
  const CandidateSet c = rank_candidates(P, N, tangent_frames(N), active, raw, -1.0, q.tracker, view);
  EXPECT_EQ(test::canonical(c.cand), (std::vector<Triangle>{{0, 1, 2}}));
  EXPECT_EQ(c.rejected_shadow, 1u);
  EXPECT_EQ(c.rejected_conormal, 0u);
  EXPECT_TRUE(view.along_ray(P[1], P[3]));
  EXPECT_FALSE(view.along_ray(P[0], P[1]));
}

TEST(Candidates, ViewpointPlausibleWhereThePlanesFaceIt) {
  // A plate facing the origin is plausibly scanned from there; seen from its own plane (every
  // plane edge-on), or from one of its points, it is not.
  std::vector<Vec3> P, N;
  for (int i = -5; i <= 5; ++i)
    for (int j = -5; j <= 5; ++j) {
      P.push_back({double(i), double(j), 10});
      N.push_back({0, 0, 1});  // either sense
    }
  const std::vector<uint8_t> active(P.size(), 1);
  EXPECT_TRUE(plausible_viewpoint(P, N, active, {0, 0, 0}));
  EXPECT_TRUE(plausible_viewpoint(P, N, active, {3, -2, 40}));
  EXPECT_FALSE(plausible_viewpoint(P, N, active, {100, 0, 10}));
  EXPECT_FALSE(plausible_viewpoint(P, N, active, P[7]));
}
