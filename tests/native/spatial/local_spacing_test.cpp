// Each particle's own spacing (particlemesh/spatial/local_spacing.h).
#include "particlemesh/spatial/local_spacing.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <numeric>
#include <random>

#include "particlemesh/core/error.h"
#include "particlemesh/sample/shapes.h"
#include "particlemesh/spatial/spacing.h"
#include "support/test_support.h"

using namespace particlemesh;
using particlemesh::test::row_sheet;
using particlemesh::test::two_density_sphere;

namespace test_local {

double median(std::vector<double> v) {
  std::nth_element(v.begin(), v.begin() + long(v.size() / 2), v.end());
  return v[v.size() / 2];
}

}  // namespace test_local

using namespace test_local;

TEST(LocalSpacing, EvenSamplingsGetTheirMedianSpacingEverywhere) {
  for (const PointCloud& c : {fibonacci_sphere(20000), poisson_disk_sample(torus_mesh(1.0, 0.4, 96, 48), 0.03, 3)}) {
    const LocalSpacing ls = estimate_local_spacing(c.positions.data(), c.size());
    ASSERT_EQ(ls.spacing.size(), c.size());
    EXPECT_DOUBLE_EQ(ls.median_nn, estimate_spacing(c.positions.data(), c.size()).spacing);
    EXPECT_NEAR(median(ls.spacing) / ls.median_nn, 1.0, 0.03);
    for (double h : ls.spacing) {
      EXPECT_GT(h, 0.85 * ls.median_nn);
      EXPECT_LT(h, 1.3 * ls.median_nn);
    }
  }
}

TEST(LocalSpacing, FollowsTheDensity) {
  // Nearest neighbours sqrt(20000 / 3000) = 2.6 times farther apart on the upper half.
  const PointCloud c = two_density_sphere(20000, 3000);
  const LocalSpacing ls = estimate_local_spacing(c.positions.data(), c.size());
  std::vector<double> low, high;
  for (size_t i = 0; i < c.size(); ++i)
    if (std::abs(c.positions[i].z) > 0.2) (c.positions[i].z < 0 ? low : high).push_back(ls.spacing[i]);
  EXPECT_NEAR(median(high) / median(low), std::sqrt(20000.0 / 3000.0), 0.4);
  EXPECT_NEAR(median(low) / ls.median_nn, 1.0, 0.05);
}

TEST(LocalSpacing, IrregularityTellsParticlesAtRandomFromEvenSamplings) {
  // Evenly spaced samplings, even where the density varies or the rows are far apart: well
  // below the 0.35 from which triangulation lengthens its limits.
  for (const PointCloud& c : {fibonacci_sphere(20000), poisson_disk_sample(torus_mesh(1.0, 0.4, 96, 48), 0.03, 3),
                              square_lattice(120, 120), two_density_sphere(20000, 3000),
                              row_sheet(60, 24, 1.0, 3.0, 5, true)}) {
    const LocalSpacing ls = estimate_local_spacing(c.positions.data(), c.size());
    EXPECT_GE(ls.irregularity, 0.0);
    EXPECT_LT(ls.irregularity, 0.25) << c.size();
    EXPECT_EQ(ls.reach_factor, 1.0);
  }
  // Particles at random (a Poisson process): their nearest-neighbour distances follow a
  // Rayleigh distribution, coefficient of variation 0.52; 17-point estimates come out lower.
  for (const PointCloud& c : {particlemesh::test::random_sphere(20000, 1),
                              particlemesh::test::random_surface_sample(torus_mesh(1.0, 0.4, 96, 48), 20000, 2)}) {
    const LocalSpacing ls = estimate_local_spacing(c.positions.data(), c.size());
    EXPECT_GT(ls.irregularity, 0.44);
    EXPECT_LT(ls.irregularity, 0.56);
    EXPECT_NEAR(ls.reach_factor, ls.irregularity >= 0.45 ? 1.75 : 1.0 + 0.75 * (ls.irregularity - 0.35) / 0.1, 1e-12);
  }
  // Too few points for any neighbourhood: 0.
  const std::vector<Vec3> three{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  EXPECT_EQ(estimate_local_spacing(three.data(), three.size()).irregularity, 0.0);
}

TEST(LocalSpacing, ThicknessTellsNoiseAndVolumesFromCleanSurfaces) {
  auto thickness = [](const PointCloud& c) { return estimate_local_spacing(c.positions.data(), c.size()).thickness; };
  // Clean surfaces: far below 0.2.
  EXPECT_LT(thickness(fibonacci_sphere(20000)), 0.05);
  EXPECT_LT(thickness(poisson_disk_sample(torus_mesh(1.0, 0.4, 96, 48), 0.03, 3)), 0.1);
  EXPECT_LT(thickness(square_lattice(60, 60)), 1e-6);  // flat
  // A sphere whose points are moved along the radius by noise of half, then a whole spacing.
  const PointCloud sphere = fibonacci_sphere(20000);
  const double spacing = std::sqrt(4 * std::numbers::pi / 20000);
  double previous = 0;
  for (double sigma : {0.5, 1.0}) {
    PointCloud noisy = sphere;
    std::mt19937_64 rng(11);
    std::normal_distribution<double> noise(0.0, sigma * spacing);
    for (Vec3& p : noisy.positions) p = p * (1.0 + noise(rng));
    const double t = thickness(noisy);
    EXPECT_GT(t, sigma == 0.5 ? 0.3 : 0.5) << sigma;
    EXPECT_LT(t, sigma == 0.5 ? 0.45 : 0.7) << sigma;
    EXPECT_GT(t, previous);
    previous = t;
  }
  // Particles filling a block: a volume, ~0.85.
  PointCloud block;
  for (int i = 0; i < 14; ++i)
    for (int j = 0; j < 14; ++j)
      for (int k = 0; k < 14; ++k) block.positions.push_back({double(i), double(j), double(k)});
  EXPECT_GT(thickness(block), 0.75);
}

TEST(LocalSpacing, ExactCopiesTakeTheirPlacesSpacing) {
  // Each point three times: the copies do not count as neighbours, so every copy gets exactly
  // the spacing of its place in the cloud without copies, and the irregularity is unchanged
  // (with them counted a random sphere measured 0.375 against 0.486, and its local spacing
  // halved).
  for (const PointCloud& c : {particlemesh::test::random_sphere(3000, 1), fibonacci_sphere(5000)}) {
    const PointCloud copied = particlemesh::test::with_copies(c, 3);
    const LocalSpacing one = estimate_local_spacing(c.positions.data(), c.size());
    const LocalSpacing three = estimate_local_spacing(copied.positions.data(), copied.size());
    EXPECT_EQ(three.median_nn, one.median_nn);
    EXPECT_EQ(three.irregularity, one.irregularity);
    EXPECT_EQ(three.thickness, one.thickness);
    ASSERT_EQ(three.spacing.size(), 3 * c.size());
    for (size_t i = 0; i < copied.size(); ++i) ASSERT_EQ(three.spacing[i], one.spacing[i / 3]) << i;
  }
}

TEST(LocalSpacing, RowsGiveTheSpacingAcrossThem) {
  // Rows 3 apart, points 1 apart along them: the nearest-neighbour distance is 1, but a
  // surface through the rows needs edges across them (3 and more).
  const PointCloud c = row_sheet(60, 20, 1.0, 3.0, 7, false);
  const LocalSpacing ls = estimate_local_spacing(c.positions.data(), c.size());
  EXPECT_NEAR(ls.median_nn, 1.0, 0.1);
  EXPECT_GT(median(ls.spacing), 1.6);  // x 2 = an edge limit past 3
  EXPECT_LT(median(ls.spacing), 3.5);
  // The same rows 1.2 apart are an even sampling.
  const PointCloud even = row_sheet(60, 20, 1.0, 1.2, 7, false);
  const LocalSpacing le = estimate_local_spacing(even.positions.data(), even.size());
  EXPECT_NEAR(median(le.spacing) / le.median_nn, 1.0, 0.15);
}

TEST(LocalSpacing, AFarClusterKeepsItsOwnSpacing) {
  // A dense sheet (spacing 1) and, 500 away, a small cluster of particles 10 apart: the
  // cluster's neighbourhood ends at the gap, so its spacing is its own, and the sheet's
  // is not raised by the cluster.
  PointCloud c = row_sheet(40, 40, 1.0, 1.0, 3, false);
  const size_t sheet = c.size();
  for (int i = 0; i < 5; ++i)
    for (int j = 0; j < 5; ++j) c.positions.push_back({500.0 + 10.0 * i, 10.0 * j, 0});
  const LocalSpacing ls = estimate_local_spacing(c.positions.data(), c.size());
  for (size_t i = sheet; i < c.size(); ++i) {
    EXPECT_GT(ls.spacing[i], 7.0) << i;
    EXPECT_LT(ls.spacing[i], 20.0) << i;
  }
  std::vector<double> own(ls.spacing.begin(), ls.spacing.begin() + long(sheet));
  EXPECT_LT(*std::max_element(own.begin(), own.end()), 2.0);
}

TEST(LocalSpacing, ACurveOfSamplesReachesItsShortestTriangle) {
  // One quantized row of a depth camera: runs of collinear points, a step between runs. No
  // plane spans any point's neighbours, so the spacing comes from the shortest triangle each
  // point makes with two of its neighbours with no angle over 150 degrees: twice the spacing
  // (the default edge limit) reaches across that triangle, where the nearest-neighbour
  // distance alone (twice it: 2 r0) falls short of the steps.
  const PointCloud c = test::one_depth_row(300, 0.002, 0.006);
  const std::vector<Vec3>& P = c.positions;
  const LocalSpacing ls = estimate_local_spacing(P.data(), P.size());
  const double min_cos = std::cos(150.0 * std::numbers::pi / 180.0);
  auto corner_ok = [&](const Vec3& a, const Vec3& b, const Vec3& o) {
    return dot(normalized(a - o), normalized(b - o)) >= min_cos;
  };
  size_t reached = 0, beyond_2r0 = 0;
  for (size_t p = 0; p < P.size(); ++p) {
    double shortest = INFINITY;
    for (size_t a = 0; a < P.size(); ++a)
      for (size_t b = a + 1; b < P.size(); ++b) {
        if (a == p || b == p) continue;
        const double longest = std::max({distance(P[p], P[a]), distance(P[p], P[b]), distance(P[a], P[b])});
        if (longest < shortest && corner_ok(P[a], P[b], P[p]) && corner_ok(P[p], P[b], P[a]) && corner_ok(P[p], P[a], P[b]))
          shortest = longest;
      }
    reached += 2 * ls.spacing[p] >= shortest;
    beyond_2r0 += shortest > 2 * ls.median_nn;
  }
  EXPECT_GT(beyond_2r0 * 2, P.size());        // most points need more than 2 r0
  EXPECT_GE(reached * 100, P.size() * 95);   // and get it
}

TEST(LocalSpacing, SameForAnyThreadCountAndInputOrder) {
  const PointCloud c = two_density_sphere(8000, 2000);
  const LocalSpacing a = estimate_local_spacing(c.positions.data(), c.size(), 1);
  const LocalSpacing b = estimate_local_spacing(c.positions.data(), c.size(), 0);
  EXPECT_EQ(a.spacing, b.spacing);
  std::vector<size_t> order(c.size());
  std::iota(order.begin(), order.end(), 0);
  std::shuffle(order.begin(), order.end(), std::mt19937_64(11));
  std::vector<Vec3> shuffled;
  for (size_t i : order) shuffled.push_back(c.positions[i]);
  const LocalSpacing s = estimate_local_spacing(shuffled.data(), shuffled.size());
  for (size_t k = 0; k < order.size(); ++k) ASSERT_EQ(s.spacing[k], a.spacing[order[k]]) << k;
}

TEST(LocalSpacing, BadInput) {
  std::vector<Vec3> p = {{0, 0, 0}, {1, 0, 0}, {0, std::nan(""), 0}};
  EXPECT_THROW(estimate_local_spacing(p.data(), p.size()), Error);
  EXPECT_THROW(estimate_local_spacing(nullptr, 3), Error);
  p = {{0, 0, 0}, {0, 0, 0}};
  EXPECT_THROW(estimate_local_spacing(p.data(), p.size()), Error);
}
