#include "particlemesh/spatial/spacing.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <numeric>
#include <random>
#include <tuple>

#include "core/disjoint_sets.h"
#include "core/parallel.h"
#include "core/progress_tracker.h"
#include "particlemesh/core/error.h"
#include "particlemesh/sample/shapes.h"
#include "spatial/spacing_impl.h"
#include "support/test_support.h"

using namespace particlemesh;

namespace {
double brute_force_median_nn(const std::vector<Vec3>& p) {
  std::vector<double> nn;
  std::vector<Vec3> distinct;
  for (size_t i = 0; i < p.size(); ++i)
    if (std::find(p.begin(), p.begin() + long(i), p[i]) == p.begin() + long(i)) distinct.push_back(p[i]);
  for (size_t i = 0; i < distinct.size(); ++i) {
    double best = std::numeric_limits<double>::infinity();
    for (size_t j = 0; j < distinct.size(); ++j)
      if (i != j) best = std::min(best, squared_distance(distinct[i], distinct[j]));
    nn.push_back(best);
  }
  std::sort(nn.begin(), nn.end());
  return std::sqrt(nn[(nn.size() - 1) / 2]);
}
}  // namespace

TEST(EstimateSpacing, ExactMedianOnRandomClouds) {
  for (uint64_t seed = 1; seed <= 5; ++seed) {
    PointCloud c = test::random_cloud(300 + 100 * seed, seed);
    const SpacingEstimate e = estimate_spacing(c.positions.data(), c.size());
    EXPECT_DOUBLE_EQ(e.spacing, brute_force_median_nn(c.positions)) << "seed " << seed;
    EXPECT_EQ(e.duplicate_points, 0u);
  }
}

TEST(EstimateSpacing, ExactWithOutliersClustersAndDuplicates) {
  PointCloud c = test::random_cloud(400, 11);
  c.positions.push_back({1000, 0, 0});          // a far outlier
  c.positions.push_back({-500, 3, 1});          // another
  for (int i = 0; i < 50; ++i) c.positions.push_back({5 + 1e-4 * i, 5, 5});  // a dense cluster
  c.positions.push_back(c.positions[3]);        // exact duplicates
  c.positions.push_back(c.positions[3]);
  const SpacingEstimate e = estimate_spacing(c.positions.data(), c.size());
  EXPECT_DOUBLE_EQ(e.spacing, brute_force_median_nn(c.positions));
  EXPECT_EQ(e.duplicate_points, 2u);
  EXPECT_EQ(e.distinct_points, c.size() - 2);
}

// Clusters a million times their size apart (a particle flung far from a simulation, dead
// particles parked far away, objects far apart): cells fine enough for the clusters would not
// fit one grid's key, and cells that do put each cluster in one cell. Each is then searched on
// a grid of its own (split at the empty slabs between them; the middle of a cluster with
// strays scattered far and wide): the median must stay exactly the brute-force one, whole and
// sampled, at any thread count.
TEST(EstimateSpacing, ExactForClustersFarApart) {
  const std::vector<Vec3> sphere = fibonacci_sphere(2000).positions;
  auto with = [&](std::vector<Vec3> extra) {
    std::vector<Vec3> p = sphere;
    p.insert(p.end(), extra.begin(), extra.end());
    p.push_back(sphere[3]);  // and a copy in the cluster
    return p;
  };
  std::vector<Vec3> three = fibonacci_sphere(1000, 0.5, {0, 1e8, 0}).positions;
  for (const Vec3& q : fibonacci_sphere(700, 2.0, {0, 0, -3e8}).positions) three.push_back(q);
  std::vector<Vec3> scattered;
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> far(0, 1e7);
  for (int i = 0; i < 100; ++i) scattered.push_back({far(rng), far(rng), far(rng)});
  const struct {
    const char* what;
    std::vector<Vec3> points;
    size_t duplicates;
  } cases[] = {
      {"one stray", with({{1e9, 0, 0}}), 1},
      {"three clusters", with(three), 1},
      {"600 parked at one place", with(std::vector<Vec3>(600, Vec3{1e9, 1e9, 1e9})), 600},
      {"5 % scattered far and wide", with(scattered), 1},
      {"a stray on each side", with({{-4e9, 1, 2}, {0, 7e9, 0}}), 1},
  };
  for (const auto& c : cases) {
    SCOPED_TRACE(c.what);
    const double expected = brute_force_median_nn(c.points);
    for (int threads : {1, 3}) {
      const SpacingEstimate e = estimate_spacing(c.points.data(), c.points.size(), threads);
      EXPECT_DOUBLE_EQ(e.spacing, expected);
      EXPECT_EQ(e.duplicate_points, c.duplicates);
      EXPECT_EQ(e.distinct_points, c.points.size() - c.duplicates);
    }
    // Sampled: every 7th point's nearest neighbour among all (the clusters after the first
    // start at indices that are not multiples of 7).
    std::vector<double> nn;
    for (size_t i = 0; i < c.points.size(); i += 7) {
      double best = std::numeric_limits<double>::infinity();
      for (size_t j = 0; j < c.points.size(); ++j) {
        const double d = squared_distance(c.points[i], c.points[j]);
        if (d > 0) best = std::min(best, d);
      }
      nn.push_back(best);
    }
    std::sort(nn.begin(), nn.end());
    const size_t samples = (c.points.size() + 6) / 7;
    EXPECT_DOUBLE_EQ(estimate_spacing_sampled(c.points.data(), c.points.size(), samples).spacing,
                     std::sqrt(nn[(nn.size() - 1) / 2]));
  }
}

// Clusters far denser than the rest of the cloud (a close-up scan merged into a wide one, a
// lidar's near field, a cluster within a cluster): their cells crowd, and their points are
// searched on finer grids of their own, recursively. The median stays the brute-force one, with
// exact copies and near copies (twins) among the crowded points, at any thread count.
TEST(EstimateSpacing, ExactWhereClustersAreFarDenserThanTheRest) {
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  auto cube = [&](size_t n, Vec3 centre, double side, std::vector<Vec3>& out) {
    for (size_t i = 0; i < n; ++i)
      out.push_back(centre + Vec3{u(rng) - 0.5, u(rng) - 0.5, u(rng) - 0.5} * side);
  };
  std::vector<Vec3> nested, ball, twinned;
  cube(2500, {0.5, 0.5, 0.5}, 1.0, nested);
  cube(3000, {0.3, 0.6, 0.2}, 1e-2, nested);   // 10^6 times as dense
  cube(1500, {0.3, 0.6, 0.2}, 1e-5, nested);   // and 10^9 times within it
  for (int i = 0; i < 200; ++i) nested.push_back(nested[size_t(2600 + i)]);  // exact copies
  for (const Vec3& p : fibonacci_sphere(2500).positions) ball.push_back(p);
  for (const Vec3& p : fibonacci_sphere(4000, 0.004, {0, 0, 1}).positions) ball.push_back(p);
  cube(2000, {0, 0, 0}, 1.0, twinned);
  for (size_t i = 0; i < 2500; ++i) {           // a dense cluster of near copies
    const Vec3 p = Vec3{2, 2, 2} + Vec3{u(rng), u(rng), u(rng)} * 1e-3;
    twinned.push_back(p);
    twinned.push_back(p + Vec3{1e-9, 0, 0});
  }
  for (const auto* cloud : {&nested, &ball, &twinned}) {
    const double expected = brute_force_median_nn(*cloud);
    for (int threads : {1, 3}) {
      const SpacingEstimate e = estimate_spacing(cloud->data(), cloud->size(), threads);
      EXPECT_DOUBLE_EQ(e.spacing, expected) << cloud->size() << " points, " << threads << " threads";
    }
  }
}

// Near copies (twins: a point whose nearest distinct neighbour is at most a tenth as far as
// every other one) inside a cluster far denser than the rest, which crowds a few of the
// estimate's cells: pairs, triples that are not twins (the third a little too near), points of
// the cluster's lattice, exact copies, against the brute-force groups at 1 and 3 threads.
TEST(EstimateSpacing, TwinsInACrowdedClusterAreTheBruteForceOnes) {
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const auto direction = [&] {
    for (;;) {
      const Vec3 d{u(rng), u(rng), u(rng)};
      if (squared_norm(d) > 0.01 && squared_norm(d) <= 1) return normalized(d);
    }
  };
  std::vector<Vec3> p;
  // The rest: a jittered lattice of spacing 1/14 (no point of it is a twin).
  for (int i = 0; i < 14; ++i)
    for (int j = 0; j < 14; ++j)
      for (int k = 0; k < 14; ++k)
        p.push_back(Vec3{i + 0.5 + 0.1 * u(rng), j + 0.5 + 0.1 * u(rng), k + 0.5 + 0.1 * u(rng)} * (1.0 / 14));
  // The cluster: a jittered lattice of spacing a, 700 times denser; every second point with a
  // partner 0.05 a away (a twin pair), every fifth of the others with a partner and a third
  // point 0.4 a away (no twins: the second nearest is within ten times the nearest).
  const double a = 1e-4;
  const Vec3 corner{0.31, 0.52, 0.47};
  for (int i = 0; i < 16; ++i)
    for (int j = 0; j < 16; ++j)
      for (int k = 0; k < 16; ++k) {
        const Vec3 q = corner + Vec3{i + 0.1 * u(rng), j + 0.1 * u(rng), k + 0.1 * u(rng)} * a;
        p.push_back(q);
        const int n = (i * 16 + j) * 16 + k;
        if (n % 2 == 0) p.push_back(q + direction() * (0.05 * a));
        else if (n % 5 == 0) {
          p.push_back(q + direction() * (0.05 * a));
          p.push_back(q + direction() * (0.4 * a));
        }
      }
  for (int i = 0; i < 300; ++i) p.push_back(p[size_t(3000 + 7 * i)]);  // exact copies
  // Brute force: groups of twins and exact copies, as the lowest input index of each.
  const size_t n = p.size();
  std::vector<uint32_t> first(n);  // the first input index of each place
  {
    std::vector<uint32_t> order(n);
    std::iota(order.begin(), order.end(), 0u);
    const auto key = [&](uint32_t i) { return std::tuple(p[i].x, p[i].y, p[i].z, i); };
    std::sort(order.begin(), order.end(), [&](uint32_t x, uint32_t y) { return key(x) < key(y); });
    for (size_t k = 0; k < n; ++k)
      first[order[k]] = k > 0 && p[order[k]] == p[order[k - 1]] ? first[order[k - 1]] : order[k];
  }
  detail::DisjointSets groups(n);
  for (size_t i = 0; i < n; ++i) {
    if (first[i] != i) {
      groups.unite(uint32_t(i), first[i]);
      continue;
    }
    double d1 = INFINITY, d2 = INFINITY;
    size_t nearest = i;
    for (size_t j = 0; j < n; ++j) {
      const double e = squared_distance(p[i], p[j]);
      if (!(e > 0) || first[j] != j) continue;
      if (e < d1) d2 = d1, d1 = e, nearest = j;
      else if (e < d2) d2 = e;
    }
    // (Every pair's offset is far below a tenth of the estimate's cells, 1/14 wide or more.)
    if (d2 >= d1 / (detail::kTwinRatio * detail::kTwinRatio)) groups.unite(uint32_t(i), uint32_t(nearest));
  }
  std::vector<uint32_t> expected(n);
  size_t twinned = 0;
  for (size_t i = 0; i < n; ++i) twinned += (expected[i] = groups.find(uint32_t(i))) != i;
  ASSERT_GT(twinned, 2000u);  // most pairs, and the copies
  for (int threads : {1, 3}) {
    const ProgressCallback none;
    detail::ProgressTracker tracker(none);
    std::vector<uint32_t> twin_of;
    detail::with_threads(threads, [&] { detail::estimate_spacing_impl(p.data(), n, tracker, 0.0, 1.0, 1, &twin_of); });
    ASSERT_EQ(twin_of.size(), n) << "the cloud should count as twinned";
    size_t wrong = 0;
    for (size_t i = 0; i < n; ++i) wrong += twin_of[i] != expected[i];
    EXPECT_EQ(wrong, 0u) << threads << " threads";
  }
}

// Copies of one point ten and a hundred times as many as the rest (a scanner's invalid returns
// written as 0 0 0): the spacing is the rest's, as the brute-force median over the distinct
// points gives it, not an error; and with a single other point, the distance between the two.
TEST(EstimateSpacing, ManyCopiesOfOnePointLeaveTheRestMeasured) {
  std::mt19937_64 rng(2);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::vector<Vec3> random_cube(10000, Vec3{0, 0, 0});
  for (int i = 0; i < 100; ++i) random_cube.push_back({u(rng), u(rng), u(rng)});
  std::vector<Vec3> sphere_far(100000, Vec3{0, 0, 0});
  for (const Vec3& p : fibonacci_sphere(1000).positions) sphere_far.push_back(p * 2.0 + Vec3{3, 3, 3});
  for (const auto* cloud : {&random_cube, &sphere_far}) {
    const double expected = brute_force_median_nn(*cloud);
    const SpacingEstimate e = estimate_spacing(cloud->data(), cloud->size());
    EXPECT_DOUBLE_EQ(e.spacing, expected) << cloud->size() << " points";
    EXPECT_EQ(e.duplicate_points, cloud == &random_cube ? 9999u : 99999u);
  }
  // Copies of two points: their distance (each alone on its side of the gap between them).
  std::vector<Vec3> two(10000, Vec3{0, 0, 0});
  two.push_back({0.3, -0.4, 1.2});
  two.push_back({0.3, -0.4, 1.2});
  const SpacingEstimate e = estimate_spacing(two.data(), two.size());
  EXPECT_DOUBLE_EQ(e.spacing, 1.3);
  EXPECT_EQ(e.distinct_points, 2u);
  EXPECT_EQ(e.duplicate_points, 10000u);
}

TEST(EstimateSpacing, SurfaceSampleIsCloseToThePoissonRadius) {
  const PointCloud c = poisson_disk_sample(icosphere_mesh(5), 0.05, 3);
  const SpacingEstimate e = estimate_spacing(c.positions.data(), c.size());
  EXPECT_GE(e.spacing, 0.05);        // Poisson disk: no pair closer than r0
  EXPECT_LT(e.spacing, 0.05 * 1.3);  // and a maximal sample leaves no wide gaps
}

// Each point's nearest neighbour must be found exactly, also where it lies just across a cell
// face (a search that skips cells must not skip that one). A sample of one point (the
// first: max_samples 1) makes the estimate that point's own nearest distance, so every point
// is checked in turn: random clouds, and lattices (many points on or next to cell faces) at
// several scales and offsets (rounding), slightly jittered so that distances differ.
TEST(EstimateSpacing, EveryPointsNearestNeighbourExactly) {
  std::vector<std::vector<Vec3>> clouds;
  for (uint64_t seed = 1; seed <= 3; ++seed) clouds.push_back(test::random_cloud(300, seed).positions);
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> jitter(-1e-6, 1e-6);
  for (const double step : {1.0, 1e-3})
    for (const double offset : {0.0, 1e6}) {
      std::vector<Vec3> p;
      for (int i = 0; i < 7; ++i)
        for (int j = 0; j < 7; ++j)
          for (int k = 0; k < 7; ++k)
            p.push_back(Vec3{offset + (i + jitter(rng)) * step, offset + (j + jitter(rng)) * step,
                             offset + (k + jitter(rng)) * step});
      clouds.push_back(p);
    }
  for (size_t c = 0; c < clouds.size(); ++c) {
    const std::vector<Vec3>& p = clouds[c];
    size_t wrong = 0;
    for (size_t i = 0; i < p.size(); ++i) {
      double best = std::numeric_limits<double>::infinity();
      for (size_t j = 0; j < p.size(); ++j)
        if (j != i) best = std::min(best, squared_distance(p[i], p[j]));
      std::vector<Vec3> q = p;
      std::swap(q[0], q[i]);
      wrong += estimate_spacing_sampled(q.data(), q.size(), 1).spacing != std::sqrt(best);
    }
    EXPECT_EQ(wrong, 0u) << "cloud " << c;
  }
}

TEST(EstimateSpacing, IndependentOfThreadsAndOrder) {
  PointCloud c = fibonacci_sphere(20000);
  const double a = estimate_spacing(c.positions.data(), c.size(), 1).spacing;
  const double b = estimate_spacing(c.positions.data(), c.size(), 3).spacing;
  std::reverse(c.positions.begin(), c.positions.end());
  const double d = estimate_spacing(c.positions.data(), c.size(), 0).spacing;
  EXPECT_EQ(a, b);
  EXPECT_EQ(a, d);
}

TEST(EstimateSpacing, RejectsDegenerateInput) {
  std::vector<Vec3> one = {{0, 0, 0}};
  EXPECT_THROW(estimate_spacing(one.data(), one.size()), Error);
  std::vector<Vec3> same(10, Vec3{1, 2, 3});
  try {
    estimate_spacing(same.data(), same.size());
    FAIL();
  } catch (const Error& e) {
    EXPECT_EQ(e.status(), Status::InvalidInput);
    EXPECT_NE(std::string(e.what()).find("coincide"), std::string::npos);
  }
  std::vector<Vec3> nan = {{0, 0, 0}, {1, std::nan(""), 0}};
  EXPECT_THROW(estimate_spacing(nan.data(), nan.size()), Error);
}

TEST(EstimateSpacing, SampledIsTheMedianOfTheStridedSample) {
  // Exactly the brute-force median over points 0, k, 2k, ... (each one's nearest neighbour
  // among all points), on a random cloud where a sample's median differs from the whole's.
  const PointCloud c = test::random_cloud(3000, 5);
  const size_t max_samples = 500, stride = 6;
  std::vector<double> nn;
  for (size_t i = 0; i < c.size(); i += stride) {
    double best = std::numeric_limits<double>::infinity();
    for (size_t j = 0; j < c.size(); ++j)
      if (j != i) best = std::min(best, squared_distance(c.positions[i], c.positions[j]));
    nn.push_back(best);
  }
  std::sort(nn.begin(), nn.end());
  const double expected = std::sqrt(nn[(nn.size() - 1) / 2]);
  for (int threads : {1, 3})
    EXPECT_DOUBLE_EQ(estimate_spacing_sampled(c.positions.data(), c.size(), max_samples, threads).spacing, expected);
  // Enough samples for every point: the exact estimate.
  EXPECT_EQ(estimate_spacing_sampled(c.positions.data(), c.size(), c.size()).spacing,
            estimate_spacing(c.positions.data(), c.size()).spacing);
}

TEST(EstimateSpacing, SampledIsCloseOnEvenSurfaces) {
  const PointCloud c = fibonacci_sphere(50000);
  const double exact = estimate_spacing(c.positions.data(), c.size()).spacing;
  EXPECT_NEAR(estimate_spacing_sampled(c.positions.data(), c.size(), 4096).spacing, exact, 0.01 * exact);
  EXPECT_THROW(estimate_spacing_sampled(c.positions.data(), c.size(), 0), Error);
  std::vector<Vec3> bad = c.positions;
  bad[3].x = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(estimate_spacing_sampled(bad.data(), bad.size(), 100), Error);
}
