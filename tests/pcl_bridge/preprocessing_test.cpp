// particlemesh_pcl/preprocessing.h: PCL's outlier removal, uniform sampling / voxel grid and
// normal estimation, each keeping a subset of the input points with attributes in step, and
// moving least squares smoothing, which moves them.
#include "particlemesh_pcl/preprocessing.h"

#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <random>
#include <set>
#include <tuple>

#include "particlemesh/core/error.h"
#include "particlemesh/sample/shapes.h"
#include "support/test_support.h"

using namespace particlemesh;
using particlemesh::test::status_of;
using particlemesh_pcl::Downsampling;
using particlemesh_pcl::PreprocessOptions;

namespace {

// A sphere of radius 1 with an "index" attribute (so we can see which points survive) and
// a few strays far from it.
PointCloud sphere_with_strays(size_t n, std::vector<uint32_t>* strays) {
  PointCloud c = fibonacci_sphere(n);
  c.normals.clear();
  for (const Vec3& s : {Vec3(1.4, 0, 0), Vec3(0, -1.5, 0.1), Vec3(0.2, 0.2, 1.6)}) {
    strays->push_back(uint32_t(c.size()));
    c.positions.push_back(s);
  }
  VertexAttribute index{"index", 1, {}};
  for (size_t i = 0; i < c.size(); ++i) index.values.push_back(float(i));
  c.attributes.push_back(index);
  return c;
}


}  // namespace

TEST(Preprocessing, OffByDefaultChangesNothing) {
  std::vector<uint32_t> strays;
  PointCloud c = sphere_with_strays(500, &strays);
  const PointCloud before = c;
  std::vector<uint32_t> kept;
  PreprocessOptions o;
  EXPECT_FALSE(particlemesh_pcl::anyPreprocessing(o));
  const auto r = particlemesh_pcl::preprocess(c, o, &kept);
  EXPECT_EQ(c.positions, before.positions);
  EXPECT_EQ(r.output_points, before.size());
  EXPECT_EQ(kept.size(), before.size());
  EXPECT_EQ(kept.back(), before.size() - 1);
}

TEST(Preprocessing, OutlierRemovalDropsStrays) {
  std::vector<uint32_t> strays;
  PointCloud c = sphere_with_strays(3000, &strays);
  const PointCloud before = c;
  PreprocessOptions o;
  o.remove_outliers = true;
  o.outlier_mean_k = 20;
  o.outlier_stddev_mul = 3.0;
  std::vector<uint32_t> kept;
  const auto r = particlemesh_pcl::preprocess(c, o, &kept);
  for (uint32_t s : strays) EXPECT_EQ(std::count(kept.begin(), kept.end(), s), 0) << s;
  EXPECT_EQ(r.outliers_removed, before.size() - c.size());
  EXPECT_LE(r.outliers_removed, 3u + 30u);  // the strays, and hardly any sphere point
  ASSERT_EQ(kept.size(), c.size());
  for (size_t i = 0; i < kept.size(); ++i) {
    ASSERT_EQ(c.positions[i], before.positions[kept[i]]);
    ASSERT_EQ(c.attributes[0].values[i], float(kept[i]));  // attributes follow their points
    if (i > 0) {
      ASSERT_LT(kept[i - 1], kept[i]);             // input order kept
    }
  }
}

TEST(Preprocessing, UniformSamplingKeepsOneInputPointPerVoxel) {
  std::vector<uint32_t> strays;
  PointCloud c = sphere_with_strays(20000, &strays);
  const PointCloud before = c;
  PreprocessOptions o;
  o.downsampling = Downsampling::UniformSampling;
  o.leaf_size = 0.1;
  std::vector<uint32_t> kept;
  const auto r = particlemesh_pcl::preprocess(c, o, &kept);
  EXPECT_EQ(r.downsampled_away, before.size() - c.size());
  EXPECT_LT(c.size(), 3000u);
  EXPECT_GT(c.size(), 1000u);
  std::set<std::tuple<long, long, long>> voxels;
  for (size_t i = 0; i < c.size(); ++i) {
    ASSERT_EQ(c.positions[i], before.positions[kept[i]]);  // an input point, not a new one
    const Vec3& p = c.positions[i];
    ASSERT_TRUE(voxels.insert({long(std::floor(float(p.x) / 0.1f)), long(std::floor(float(p.y) / 0.1f)),
                               long(std::floor(float(p.z) / 0.1f))})
                    .second)
        << "two points in one voxel";
  }
  // Every input point has a kept point within a voxel diagonal.
  for (size_t i = 0; i < before.size(); i += 37) {
    double best = 1e9;
    for (const Vec3& q : c.positions) best = std::min(best, distance(before.positions[i], q));
    ASSERT_LT(best, 0.1 * std::sqrt(3.0) + 1e-6);
  }
}

TEST(Preprocessing, VoxelGridPicksTheInputPointNearestEachCentroid) {
  std::vector<uint32_t> strays;
  PointCloud c = sphere_with_strays(20000, &strays);
  const PointCloud before = c;
  PreprocessOptions o;
  o.downsampling = Downsampling::VoxelGrid;
  o.leaf_size = 0.1;
  std::vector<uint32_t> kept;
  particlemesh_pcl::preprocess(c, o, &kept);
  EXPECT_LT(c.size(), 3000u);
  EXPECT_GT(c.size(), 1000u);
  for (size_t i = 0; i < c.size(); ++i) {
    ASSERT_EQ(c.positions[i], before.positions[kept[i]]);
    if (i > 0) {
      ASSERT_LT(kept[i - 1], kept[i]);
    }
  }
  // The strays are alone in their voxels: their centroid is themselves, so they stay.
  for (uint32_t s : strays) EXPECT_EQ(std::count(kept.begin(), kept.end(), s), 1) << s;
}

TEST(Preprocessing, NormalsFaceTheViewpoint) {
  PointCloud c = fibonacci_sphere(3000);
  const std::vector<Vec3> truth = c.normals;  // outward
  c.normals.clear();
  PreprocessOptions o;
  o.estimate_normals = true;
  o.normal_k = 12;
  // From the centre every normal points inward ...
  PointCloud inside = c;
  auto r = particlemesh_pcl::preprocess(inside, o);
  ASSERT_TRUE(r.normals_estimated);
  ASSERT_EQ(inside.normals.size(), c.size());
  for (size_t i = 0; i < c.size(); ++i) {
    ASSERT_NEAR(norm(inside.normals[i]), 1.0, 1e-5);
    ASSERT_LT(dot(inside.normals[i], truth[i]), -0.99) << i;  // accurate and flipped inward
  }
  // ... from far above, toward +z; the thread count does not change them.
  o.viewpoint[2] = 100.f;
  o.threads = 1;
  PointCloud above = c;
  particlemesh_pcl::preprocess(above, o);
  o.threads = 3;
  PointCloud above3 = c;
  particlemesh_pcl::preprocess(above3, o);
  EXPECT_EQ(above.normals, above3.normals);
  for (size_t i = 0; i < c.size(); ++i) ASSERT_GT(dot(above.normals[i], Vec3(0, 0, 100) - c.positions[i]), 0) << i;
  // Georeferenced coordinates (PCL computes in float): the same normals.
  const Vec3 offset(512345.0, 4123456.0, 250.0);
  PointCloud far = c;
  for (Vec3& p : far.positions) p = p + offset;
  PreprocessOptions fo = o;
  fo.viewpoint[0] = float(offset.x), fo.viewpoint[1] = float(offset.y), fo.viewpoint[2] = float(offset.z + 100.0);
  particlemesh_pcl::preprocess(far, fo);
  ASSERT_EQ(far.normals.size(), c.size());
  for (size_t i = 0; i < c.size(); ++i) ASSERT_GT(dot(far.normals[i], above.normals[i]), 0.9999) << i;
  // Estimated normals replace the cloud's own.
  PointCloud with = fibonacci_sphere(3000);
  o.viewpoint[2] = 0;
  particlemesh_pcl::preprocess(with, o);
  EXPECT_LT(dot(with.normals[0], truth[0]), 0);
}

TEST(Preprocessing, MovingLeastSquaresTakesOutNoise) {
  // A unit sphere of 8000 points (spacing ~0.04), each moved along its radius by noise of
  // half a spacing, and one stray with no neighbour within the radius.
  PointCloud c = fibonacci_sphere(8000);
  std::mt19937_64 rng(7);
  std::normal_distribution<double> noise(0.0, 0.02);
  for (Vec3& p : c.positions) p = p * (1.0 + noise(rng));
  c.positions.push_back({3, 0, 0});
  c.normals.push_back({1, 0, 0});
  VertexAttribute index{"index", 1, {}};
  for (size_t i = 0; i < c.size(); ++i) index.values.push_back(float(i));
  c.attributes.push_back(index);
  auto rms = [](const PointCloud& x) {
    double sum = 0;
    for (size_t i = 0; i + 1 < x.size(); ++i) sum += std::pow(norm(x.positions[i]) - 1.0, 2);
    return std::sqrt(sum / double(x.size() - 1));
  };
  PreprocessOptions o;
  o.mls_radius = 0.12;
  EXPECT_TRUE(particlemesh_pcl::anyPreprocessing(o));
  o.threads = 1;
  PointCloud one = c;
  std::vector<uint32_t> kept;
  const auto r = particlemesh_pcl::preprocess(one, o, &kept);
  // Every point is still there, in its place, with its normal and attributes; the noise is
  // down to less than 40 % (2.7 x less, measured).
  ASSERT_EQ(one.size(), c.size());
  EXPECT_EQ(kept.size(), c.size());
  EXPECT_EQ(kept.back(), c.size() - 1);
  EXPECT_EQ(one.normals, c.normals);
  EXPECT_EQ(one.attributes[0].values, c.attributes[0].values);
  EXPECT_NEAR(rms(c), 0.02, 0.002);
  EXPECT_LT(rms(one), 0.4 * rms(c));
  EXPECT_EQ(r.smoothed, c.size() - 1);
  EXPECT_EQ(r.smoothing_skipped, 1u);  // the stray, left where it was
  EXPECT_EQ(one.positions.back(), Vec3(3, 0, 0));
  EXPECT_GT(r.smoothing_mean_shift, 0.01);
  EXPECT_LT(r.smoothing_max_shift, 0.12);
  // The same for any thread count.
  o.threads = 3;
  PointCloud three = c;
  particlemesh_pcl::preprocess(three, o);
  EXPECT_EQ(three.positions, one.positions);
  // Georeferenced coordinates (PCL computes in float): the same smoothing, moved along.
  const Vec3 offset(512345.0, 4123456.0, 250.0);
  PointCloud far = c;
  for (Vec3& p : far.positions) p = p + offset;
  particlemesh_pcl::preprocess(far, o);
  for (size_t i = 0; i < c.size(); ++i) ASSERT_LT(distance(far.positions[i] - offset, one.positions[i]), 1e-5) << i;
}

TEST(Preprocessing, BadParametersAreErrors) {
  PointCloud c = fibonacci_sphere(200);
  PreprocessOptions o;
  o.downsampling = Downsampling::UniformSampling;
  EXPECT_EQ(status_of([&] { PointCloud d = c; particlemesh_pcl::preprocess(d, o); }), Status::InvalidArgument);
  o.leaf_size = 1e-9;  // 2^31 voxels would not fit PCL's int voxel index
  EXPECT_EQ(status_of([&] { PointCloud d = c; particlemesh_pcl::preprocess(d, o); }), Status::InvalidArgument);
  o = {};
  o.remove_outliers = true;
  o.outlier_mean_k = 0;
  EXPECT_EQ(status_of([&] { PointCloud d = c; particlemesh_pcl::preprocess(d, o); }), Status::InvalidArgument);
  o = {};
  o.estimate_normals = true;
  o.normal_k = 2;
  EXPECT_EQ(status_of([&] { PointCloud d = c; particlemesh_pcl::preprocess(d, o); }), Status::InvalidArgument);
  for (double radius : {-1.0, double(NAN), double(INFINITY)}) {
    o = {};
    o.mls_radius = radius;
    EXPECT_EQ(status_of([&] { PointCloud d = c; particlemesh_pcl::preprocess(d, o); }), Status::InvalidArgument);
  }
  o = {};
  o.mls_radius = 0.3;
  o.mls_order = 6;
  EXPECT_EQ(status_of([&] { PointCloud d = c; particlemesh_pcl::preprocess(d, o); }), Status::InvalidArgument);
}
