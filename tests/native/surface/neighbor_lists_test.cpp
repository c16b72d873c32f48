// The neighbour lists the smallest-sphere test reads: with a radius per point, every pair
// within the larger of its two radii is in both lists (so every blocker of a triangle is in
// the list of its corner with the largest L), also where crowded radii were shortened.
#include "surface/neighbor_lists.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>

#include "core/parallel.h"
#include "particlemesh/core/error.h"
#include "particlemesh/sample/shapes.h"
#include "spatial/grid_search.h"
#include "support/test_support.h"

using namespace particlemesh;

namespace {

// Points on a plane, a dense patch (spacing 0.002) inside a sparse field (spacing 0.03),
// each with the radius of its own spacing x 4: the sparse points beside the patch reach
// hundreds of its points, and the patch crowds the grid's cells (its points are searched on a
// finer grid).
struct Crowd {
  std::vector<Vec3> points;
  std::vector<double> radius;
};

Crowd dense_patch_in_sparse_field() {
  Crowd c;
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> jitter(-0.3, 0.3);
  for (int i = 0; i < 34; ++i)
    for (int j = 0; j < 34; ++j) {
      c.points.push_back({(i + jitter(rng)) * 0.03, (j + jitter(rng)) * 0.03, 0});
      c.radius.push_back(0.12);
    }
  for (int i = 0; i < 60; ++i)
    for (int j = 0; j < 60; ++j) {
      c.points.push_back({0.45 + (i + jitter(rng)) * 0.002, 0.45 + (j + jitter(rng)) * 0.002, 0});
      c.radius.push_back(0.008);
    }
  return c;
}

/// The crowd in a grid: every point its own representative, the radii in sorted order.
struct CrowdGrid {
  Crowd c = dense_patch_in_sparse_field();
  NeighborGrid grid{c.points.data(), c.points.size(), 0.05};
  std::vector<uint32_t> rep;
  std::vector<double> radius;
  CrowdGrid() {
    for (uint32_t s = 0; s < c.points.size(); ++s) {
      rep.push_back(s);
      radius.push_back(c.radius[grid.original_index(s)]);
    }
  }
};

}  // namespace

class NeighborLists : public ::testing::Test {
 protected:
  const CrowdGrid g;
  const NeighborGrid& grid = g.grid;
  const std::vector<uint32_t>& rep = g.rep;
  const std::vector<double>& radius = g.radius;
  const size_t n = g.rep.size();
  const ProgressCallback none;  // the tracker keeps a reference: a temporary would dangle
  detail::ProgressTracker tracker{none};
};

TEST_F(NeighborLists, ShortenedRadiiHoldEveryPairWithinEither) {

  // Without shortening the limit fails, naming the most any point holds.
  std::vector<double> unchanged = radius;
  try {
    detail::build_neighbor_lists(grid, rep, unchanged, 64, false, tracker);
    FAIL() << "no limit error";
  } catch (const Error& e) {
    EXPECT_EQ(e.status(), Status::LimitExceeded);
    EXPECT_NE(std::string(e.what()).find("more than the limit of 64"), std::string::npos) << e.what();
  }
  EXPECT_EQ(unchanged, radius);

  std::vector<double> shortened = radius;
  const detail::NeighborLists lists = detail::build_neighbor_lists(grid, rep, shortened, 64, true, tracker);
  size_t changed = 0;
  for (uint32_t s = 0; s < n; ++s) {
    EXPECT_LE(shortened[s], radius[s]);
    if (shortened[s] == radius[s]) continue;
    ++changed;
    // The longest radius that holds at most 64: exactly 64 within it (the plane's jittered
    // points have no ties), the 65th beyond it.
    std::vector<double> d;
    for (uint32_t t = 0; t < n; ++t)
      if (t != s) d.push_back(distance(grid.sorted_point(s), grid.sorted_point(t)));
    std::sort(d.begin(), d.end());
    EXPECT_LE(d[63], shortened[s] * (1 + 1e-15));
    EXPECT_GT(d[64], shortened[s]);
  }
  EXPECT_EQ(lists.shortened, changed);
  EXPECT_GT(changed, 50u);
  EXPECT_LT(changed, 34u * 34u);  // only the sparse points near the patch
  // Every pair within the larger of its shortened radii is in both lists, and nothing else.
  size_t pairs = 0;
  for (uint32_t s = 0; s < n; ++s) {
    std::vector<uint32_t> want;
    for (uint32_t t = 0; t < n; ++t) {
      if (t == s) continue;
      const double d2 = squared_distance(grid.sorted_point(s), grid.sorted_point(t));
      const double r = std::max(shortened[s], shortened[t]);
      if (d2 <= r * r) want.push_back(t);
    }
    const std::vector<uint32_t> got(lists.begin(s), lists.end(s));
    ASSERT_EQ(got, want) << "point " << s;
    pairs += got.size();
  }
  // At most 64 of a point's own, so at most 2 x 64 per point on average.
  EXPECT_LE(pairs, 2 * 64 * n);
}

TEST_F(NeighborLists, NothingCrowdedNothingShortened) {
  std::vector<double> kept = radius;
  const detail::NeighborLists shortening = detail::build_neighbor_lists(grid, rep, kept, 100000, true, tracker);
  std::vector<double> same = radius;
  const detail::NeighborLists plain = detail::build_neighbor_lists(grid, rep, same, 100000, false, tracker);
  EXPECT_EQ(kept, radius);
  EXPECT_EQ(shortening.shortened, 0u);
  EXPECT_EQ(shortening.offset, plain.offset);
  EXPECT_EQ(shortening.index, plain.index);
}

// Radii that vary from point to point (three sizes, and a few far larger), over cells of a
// size between them (a point's query box spans 2 to 13 cells a side, and points of one cell
// have different boxes), with exact copies (not representatives: in no list, and no list
// holds them): each representative's list is, in order, every other representative within
// the larger of the two radii, as brute force finds them; with one and several threads.
TEST(NeighborListsPerPoint, MatchBruteForceWithVaryingRadiiAndCopies) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::vector<Vec3> points;
  for (int i = 0; i < 3000; ++i) {
    const double a = 6.283185307179586 * u(rng), b = u(rng);
    points.push_back({std::cos(a) * (0.5 + 0.2 * b), std::sin(a) * (0.5 + 0.2 * b), 0.3 * u(rng)});
  }
  for (int i = 0; i < 300; ++i) points.push_back(points[size_t(rng() % 3000)]);  // exact copies
  const NeighborGrid grid(points.data(), points.size(), 0.06);
  const size_t n = grid.point_count();
  const std::vector<uint32_t> rep = detail::find_duplicates(grid, nullptr);
  std::vector<double> radius(n);
  for (size_t s = 0; s < n; ++s) {
    const double sizes[] = {0.05, 0.08, 0.13};
    radius[s] = rng() % 100 == 0 ? 0.3 : sizes[rng() % 3];
  }
  for (size_t s = 0; s < n; ++s) radius[s] = radius[rep[s]];
  for (const int threads : {1, 3}) {
    const ProgressCallback none;
    detail::ProgressTracker tracker(none);
    std::vector<double> r = radius;
    const detail::NeighborLists lists = detail::with_threads(
        threads, [&] { return detail::build_neighbor_lists(grid, rep, r, 100000, false, tracker); });
    size_t copies = 0;
    for (uint32_t s = 0; s < n; ++s) {
      std::vector<uint32_t> expected;
      if (rep[s] == s)
        for (uint32_t t = 0; t < n; ++t) {
          if (t == s || rep[t] != t) continue;
          const double d2 = squared_distance(grid.sorted_point(t), grid.sorted_point(s));
          if (d2 <= radius[s] * radius[s] || d2 <= radius[t] * radius[t]) expected.push_back(t);
        }
      else
        ++copies;
      ASSERT_EQ(std::vector<uint32_t>(lists.begin(s), lists.end(s)), expected) << "point " << s << ", " << threads;
    }
    EXPECT_GE(copies, 250u);
  }
}
