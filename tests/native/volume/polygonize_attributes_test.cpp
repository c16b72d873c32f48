// polygonize_attributes: the particles' attributes at given points, bit for bit what
// polygonize gives its vertices, so a caller can mesh first and interpolate later.
#include "particlemesh/volume/polygonize_attributes.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <random>
#include <string>

#include "particlemesh/core/error.h"
#include "particlemesh/sample/shapes.h"
#include "support/test_support.h"

using namespace particlemesh;
using particlemesh::test::status_of;

namespace {

// Two channels (3 and 1 components) of values in [-0.5, 0.5) and [0, 10).
std::vector<VertexAttribute> channels(size_t n, uint64_t seed) {
  std::mt19937_64 rng(seed);
  auto u = [&] { return double(rng() >> 11) * 0x1.0p-53; };
  VertexAttribute a{"velocity", 3, {}}, b{"heat", 1, {}};
  for (size_t i = 0; i < n; ++i) {
    for (int k = 0; k < 3; ++k) a.values.push_back(float(u() - 0.5));
    b.values.push_back(float(10 * u()));
  }
  return {a, b};
}

// Bit for bit (== would let -0 equal 0).
bool same_bits(const std::vector<float>& a, const std::vector<float>& b) {
  return a.size() == b.size() && (a.empty() || std::memcmp(a.data(), b.data(), a.size() * sizeof(float)) == 0);
}

void expect_same_attributes(const std::vector<VertexAttribute>& got, const std::vector<VertexAttribute>& want,
                            const std::string& what) {
  ASSERT_EQ(got.size(), want.size()) << what;
  for (size_t k = 0; k < want.size(); ++k) {
    EXPECT_EQ(got[k].name, want[k].name) << what;
    EXPECT_EQ(got[k].components, want[k].components) << what;
    size_t differ = 0;
    for (size_t i = 0; i < std::min(got[k].values.size(), want[k].values.size()); ++i)
      differ += std::memcmp(&got[k].values[i], &want[k].values[i], sizeof(float)) != 0;
    EXPECT_TRUE(same_bits(got[k].values, want[k].values))
        << what << ": " << want[k].name << " differs at " << differ << " of " << want[k].values.size() << " values";
  }
}

}  // namespace

// Meshed without attributes, then interpolated at the mesh's vertices: the values polygonize
// gives when it interpolates them itself, bit for bit, at any thread count. Cases: the default
// radius (a spacing estimate) on a random cloud; a thin shell (the vertices' attributes summed
// from the particles gathered for their edges); per-particle radii with strengths, negative
// ones too; anisotropic kernels; a tile's domain_min with a larger domain radius.
TEST(PolygonizeAttributes, TheValuesPolygonizeGivesItsVertices) {
  struct Case {
    std::string name;
    PointCloud cloud;
    PolygonizeOptions options;
  };
  std::vector<Case> cases;
  {
    Case c{"default radius", test::random_cloud(4000, 31, 1.6), {}};
    cases.push_back(c);
  }
  {
    Case c{"shell, poly6", fibonacci_sphere(20000), {}};
    c.options.kernel = Kernel::Poly6;
    cases.push_back(c);
  }
  {
    Case c{"radii and strengths, blinn", test::random_cloud(3000, 5, 1.4), {}};
    std::mt19937_64 rng(9);
    auto u = [&] { return double(rng() >> 11) * 0x1.0p-53; };
    c.options.kernel = Kernel::Blinn;
    c.options.threshold = 0.8;
    for (size_t i = 0; i < c.cloud.positions.size(); ++i) {
      c.options.radii.push_back(0.12 + 0.08 * u());
      c.options.strengths.push_back(i % 50 == 0 ? -0.5 : 0.7 + 0.6 * u());
    }
    cases.push_back(c);
  }
  {
    Case c{"anisotropic", test::random_cloud(3000, 12, 1.2), {}};
    c.options.anisotropy.enabled = true;
    cases.push_back(c);
  }
  {
    Case c{"a tile's domain", test::random_cloud(3000, 3, 1.0), {}};
    c.options.kernel = Kernel::Poly4;
    c.options.radius = 0.12;
    c.options.domain_min = Vec3{-0.3, -0.2, -0.25};
    c.options.domain_max_radius = 0.2;
    cases.push_back(c);
  }
  for (Case& cs : cases) {
    PointCloud with = cs.cloud;
    with.attributes = channels(with.positions.size(), 17);
    cs.options.threads = 1;
    const PolygonizeResult r = polygonize(with, cs.options);
    ASSERT_GT(r.mesh.positions.size(), 500u) << cs.name;
    const PolygonizeResult plain = polygonize(cs.cloud, cs.options);
    ASSERT_TRUE(plain.mesh.positions == r.mesh.positions) << cs.name;
    EXPECT_TRUE(plain.mesh.attributes.empty());
    for (int threads : {1, 2, 3, 0}) {
      PolygonizeOptions o = cs.options;
      o.threads = threads;
      expect_same_attributes(polygonize_attributes(with, o, plain.mesh.positions.data(), plain.mesh.positions.size()),
                             r.mesh.attributes, cs.name + ", " + std::to_string(threads) + " threads");
    }
    // The field overload, on the field polygonize builds.
    FieldParams p{cs.options.kernel, cs.options.radius, cs.options.threshold, cs.options.radii, cs.options.strengths,
                  cs.options.anisotropy};
    if (!cs.options.domain_min) {
      const ParticleField f(with.positions, p);
      expect_same_attributes(polygonize_attributes(f, with.attributes, r.mesh.positions.data(), r.mesh.positions.size()),
                             r.mesh.attributes, cs.name + ", field overload");
    }
  }
}

// The attributes are taken where polygonize places a vertex, before the mesh is smoothed:
// dropping small pieces keeps the vertices' values, Taubin smoothing moves the vertices but
// not their values, so both equal the values at the unsmoothed vertices; at the smoothed
// positions they differ.
TEST(PolygonizeAttributes, AtTheVerticesBeforeSmoothing) {
  PointCloud c = test::random_cloud(3000, 41, 1.6);
  c.attributes = channels(c.positions.size(), 5);
  PolygonizeOptions o;
  o.radius = 0.15;
  const PolygonizeResult raw = polygonize(c, o);
  PolygonizeOptions smoothed = o;
  smoothed.surface_smoothing.iterations = 5;
  const PolygonizeResult s = polygonize(c, smoothed);
  ASSERT_EQ(s.mesh.positions.size(), raw.mesh.positions.size());
  ASSERT_FALSE(s.mesh.positions == raw.mesh.positions);
  expect_same_attributes(polygonize_attributes(c, smoothed, raw.mesh.positions.data(), raw.mesh.positions.size()),
                         s.mesh.attributes, "taubin, at the unsmoothed vertices");
  const auto moved = polygonize_attributes(c, smoothed, s.mesh.positions.data(), s.mesh.positions.size());
  EXPECT_FALSE(same_bits(moved[0].values, s.mesh.attributes[0].values));
  PolygonizeOptions dropped = o;
  dropped.min_component_particles = 30;
  const PolygonizeResult d = polygonize(c, dropped);
  ASSERT_GT(d.stats.components_removed, 0u);
  ASSERT_LT(d.mesh.positions.size(), raw.mesh.positions.size());
  expect_same_attributes(polygonize_attributes(c, dropped, d.mesh.positions.data(), d.mesh.positions.size()),
                         d.mesh.attributes, "small pieces dropped");
}

TEST(PolygonizeAttributes, PointsFarFromEveryParticleGetZeroAndNoAttributesGiveNone) {
  PointCloud c = test::random_cloud(500, 2, 1.0);
  c.attributes = channels(c.positions.size(), 3);
  const std::vector<Vec3> far{{100, 100, 100}, {-1e300, 0, 0}};
  const auto v = polygonize_attributes(c, {}, far.data(), far.size());
  ASSERT_EQ(v.size(), 2u);
  EXPECT_EQ(v[0].values, std::vector<float>(6, 0.0f));
  EXPECT_EQ(v[1].values, std::vector<float>(2, 0.0f));
  PointCloud bare = c;
  bare.attributes.clear();
  EXPECT_TRUE(polygonize_attributes(bare, {}, far.data(), far.size()).empty());
  EXPECT_EQ(polygonize_attributes(c, {}, nullptr, 0)[0].values.size(), 0u);
}

TEST(PolygonizeAttributes, BadInputGivesClearErrors) {
  PointCloud c = test::random_cloud(200, 4, 1.0);
  c.attributes = channels(c.positions.size(), 3);
  std::vector<Vec3> points{{0, 0, 0}, {0, std::numeric_limits<double>::quiet_NaN(), 0}};
  std::string msg;
  EXPECT_EQ(status_of([&] { polygonize_attributes(c, {}, points.data(), points.size()); }, &msg), Status::InvalidInput);
  EXPECT_NE(msg.find("points[1].y is NaN"), std::string::npos) << msg;
  points[1] = {std::numeric_limits<double>::infinity(), 0, 0};
  EXPECT_EQ(status_of([&] { polygonize_attributes(c, {}, points.data(), points.size()); }, &msg), Status::InvalidInput);
  EXPECT_NE(msg.find("points[1].x is infinite"), std::string::npos) << msg;
  points.pop_back();
  PointCloud short_values = c;
  short_values.attributes[1].values.pop_back();
  EXPECT_EQ(status_of([&] { polygonize_attributes(short_values, {}, points.data(), 1); }, &msg), Status::InvalidInput);
  EXPECT_NE(msg.find("attribute 'heat' has 199 values for 200 particles"), std::string::npos) << msg;
  PolygonizeOptions o;
  o.radius = -1;
  EXPECT_EQ(status_of([&] { polygonize_attributes(c, o, points.data(), 1); }, &msg), Status::InvalidArgument);
  EXPECT_NE(msg.find("radius"), std::string::npos) << msg;
  EXPECT_EQ(status_of([&] { polygonize_attributes(PointCloud{}, {}, points.data(), 1); }, &msg), Status::InvalidInput);
  o = {};
  o.progress = [](std::string_view, double) { return false; };
  EXPECT_EQ(status_of([&] { polygonize_attributes(c, o, points.data(), 1); }, &msg), Status::Cancelled);
}
