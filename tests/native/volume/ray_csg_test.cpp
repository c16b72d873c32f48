// CSG of two particle fields along rays: the identities A ∪ A = A, A − A = ∅,
// A ∩ B ⊆ A on sampled rays, membership of every combination against the two fields point
// by point, and the normals of a difference.
#include "particlemesh/volume/ray_csg.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "support/test_support.h"

using namespace particlemesh;

namespace {

FieldParams params(Kernel k, double radius, double threshold) {
  FieldParams p;
  p.kernel = k;
  p.radius = radius;
  p.threshold = threshold;
  return p;
}

Vec3 random_unit(std::mt19937_64& rng) {
  std::normal_distribution<double> g;
  return normalized(Vec3{g(rng), g(rng), g(rng)});
}

// Inside the result at t, according to its hit list.
bool inside_at(const RayHits& h, double t) {
  bool in = h.starts_inside;
  for (const RayHit& x : h.hits) {
    if (x.t > t) break;
    in = x.entering;
  }
  return in;
}

double distance_to_hits(const RayHits& h, double t) {
  double d = INFINITY;
  for (const RayHit& x : h.hits) d = std::min(d, std::abs(x.t - t));
  return d;
}

struct Pair {
  ParticleField a, b;
};

Pair two_clouds(uint64_t seed, Kernel k) {
  const PointCloud ca = test::random_cloud(30, seed, 2.0);
  PointCloud cb = test::random_cloud(30, seed + 100, 2.0);
  for (auto& p : cb.positions) p += Vec3{0.7, 0.2, 0.0};
  return {ParticleField(ca, params(k, 0.8, 0.5)), ParticleField(cb, params(k, 0.8, 0.5))};
}

}  // namespace

class CsgIdentities : public ::testing::TestWithParam<Kernel> {};

TEST_P(CsgIdentities, HoldOnSampledRays) {
  const Kernel k = GetParam();
  const Pair fields = two_clouds(3, k);
  const RayCaster A(fields.a), B(fields.b);
  std::mt19937_64 rng(17);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  int nonempty = 0;
  for (int r = 0; r < 60; ++r) {
    const Vec3 d = random_unit(rng);
    const Vec3 target{0.3 + 1.8 * u(rng), 0.2 + 1.6 * u(rng), 0.2 + 1.6 * u(rng)};
    const Vec3 o = target - d * 5.0;
    const RayHits ha = A.all_hits(o, d), hb = B.all_hits(o, d);
    nonempty += !ha.hits.empty();
    // A ∪ A = A, A ∩ A = A (the same hits), A − A = ∅.
    for (CsgOp op : {CsgOp::Union, CsgOp::Intersection}) {
      const RayHits aa = csg_hits(ha, ha, op);
      ASSERT_EQ(aa.hits.size(), ha.hits.size()) << csg_op_name(op);
      for (size_t i = 0; i < aa.hits.size(); ++i) {
        EXPECT_EQ(aa.hits[i].t, ha.hits[i].t);
        EXPECT_EQ(aa.hits[i].entering, ha.hits[i].entering);
        EXPECT_EQ(aa.hits[i].normal, ha.hits[i].normal);
      }
    }
    const RayHits empty = csg_hits(ha, ha, CsgOp::Difference);
    EXPECT_TRUE(empty.hits.empty());
    EXPECT_FALSE(empty.starts_inside);
    EXPECT_EQ(csg_all_hits(A, A, CsgOp::Difference, o, d).hits.size(), 0u);
    // A ∩ B ⊆ A and ⊆ B: every inside stretch of the intersection lies inside both.
    const RayHits ab = csg_hits(ha, hb, CsgOp::Intersection);
    ASSERT_EQ(ab.hits.size() % 2, 0u);
    for (size_t i = 0; i + 1 < ab.hits.size(); i += 2) {
      ASSERT_TRUE(ab.hits[i].entering);
      const double mid = 0.5 * (ab.hits[i].t + ab.hits[i + 1].t);
      EXPECT_TRUE(inside_at(ha, mid));
      EXPECT_TRUE(inside_at(hb, mid));
      EXPECT_GE(fields.a.value(o + d * mid), fields.a.threshold() - 1e-12);
    }
    // Every combination, point by point along the ray, against the two fields themselves.
    for (CsgOp op : {CsgOp::Union, CsgOp::Intersection, CsgOp::Difference}) {
      const RayHits c = csg_hits(ha, hb, op);
      for (size_t i = 1; i < c.hits.size(); ++i) EXPECT_LT(c.hits[i - 1].t, c.hits[i].t);
      for (int s = 0; s <= 400; ++s) {
        const double t = 10.0 * s / 400.0;
        if (distance_to_hits(ha, t) < 1e-9 || distance_to_hits(hb, t) < 1e-9) continue;
        const bool ia = fields.a.value(o + d * t) >= fields.a.threshold();
        const bool ib = fields.b.value(o + d * t) >= fields.b.threshold();
        const bool want = op == CsgOp::Union ? (ia || ib) : op == CsgOp::Intersection ? (ia && ib) : (ia && !ib);
        EXPECT_EQ(inside_at(c, t), want) << csg_op_name(op) << " ray " << r << " t " << t;
      }
    }
    const auto first = csg_first_hit(A, B, CsgOp::Union, o, d);
    const RayHits un = csg_hits(ha, hb, CsgOp::Union);
    ASSERT_EQ(first.has_value(), !un.hits.empty());
    if (first) {
      EXPECT_EQ(first->t, un.hits[0].t);
    }
  }
  EXPECT_GT(nonempty, 20);
}

INSTANTIATE_TEST_SUITE_P(Kernels, CsgIdentities, ::testing::Values(Kernel::Wyvill, Kernel::Poly4, Kernel::Blinn),
                         [](const auto& info) { return std::string(kernel_name(info.param)); });

// A big ball minus a small one in front of it: the ray enters A, then leaves the result
// into B's ball (normal pointing into B, out of A − B), comes back out of B, leaves A.
TEST(Csg, DifferenceFlipsTheNormalsOfTheSubtractedSurface) {
  const RayCaster A(ParticleField({{0, 0, 0}}, params(Kernel::Poly4, 2.0, 0.25)));
  const RayCaster B(ParticleField({{-1.0, 0, 0}}, params(Kernel::Poly4, 1.0, 0.25)));
  // A: sphere of radius 2 sqrt(1 - 0.5) = 1.414; B: radius 0.707 around x = -1.
  const RayHits h = csg_all_hits(A, B, CsgOp::Difference, {-5, 0, 0}, {1, 0, 0});
  ASSERT_EQ(h.hits.size(), 2u);
  // B covers A's front from x = -1.707 to -0.293; A − B starts at B's back at x = -0.293.
  EXPECT_NEAR(h.hits[0].position.x, -1.0 + std::sqrt(0.5), 1e-12);
  EXPECT_TRUE(h.hits[0].entering);
  EXPECT_NEAR(h.hits[0].normal.x, -1.0, 1e-12);  // B's outward normal there is +x: flipped
  EXPECT_NEAR(h.hits[1].position.x, std::sqrt(2.0), 1e-12);
  EXPECT_FALSE(h.hits[1].entering);
  EXPECT_NEAR(h.hits[1].normal.x, 1.0, 1e-12);
  const RayHits un = csg_all_hits(A, B, CsgOp::Union, {-5, 0, 0}, {1, 0, 0});
  ASSERT_EQ(un.hits.size(), 2u);
  EXPECT_NEAR(un.hits[0].position.x, -1.0 - std::sqrt(0.5), 1e-12);
  EXPECT_NEAR(un.hits[0].normal.x, -1.0, 1e-12);
  EXPECT_THROW(csg_hits({}, {}, static_cast<CsgOp>(7)), Error);
  RayHits bad;
  bad.hits.resize(2);
  bad.hits[0].t = 2;
  bad.hits[1].t = 1;
  EXPECT_THROW(csg_hits(bad, {}, CsgOp::Union), Error);
}
