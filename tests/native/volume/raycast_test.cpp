// Ray casting of the iso-surface of volume particles: exact hits on one particle,
// tangent rays, random configurations against dense brute-force sampling of F, agreement with
// the polygonized mesh, the root solvers on their own, cost, determinism, errors.
#include "particlemesh/volume/raycast.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <numbers>
#include <random>

#include "particlemesh/mesh/topology_report.h"
#include "particlemesh/volume/polygonize.h"
#include "support/test_support.h"
#include "volume/ray_roots.h"

using namespace particlemesh;

namespace {

constexpr Kernel kAll[] = {Kernel::Wyvill, Kernel::Poly4, Kernel::Poly6, Kernel::Blinn};

std::string kname(const ::testing::TestParamInfo<Kernel>& info) { return kernel_name(info.param); }

FieldParams params(Kernel k, double radius, double threshold) {
  FieldParams p;
  p.kernel = k;
  p.radius = radius;
  p.threshold = threshold;
  return p;
}

Vec3 random_unit(std::mt19937_64& rng) {
  std::normal_distribution<double> g;
  while (true) {
    const Vec3 v{g(rng), g(rng), g(rng)};
    if (norm(v) > 1e-3) return normalized(v);
  }
}

// A unit vector orthogonal to d.
Vec3 orthogonal(const Vec3& d, std::mt19937_64& rng) {
  const Vec3 r = random_unit(rng);
  return normalized(r - d * dot(r, d));
}

// Inside/outside along the ray from the hit list, checked against F at the middle of every
// stretch between hits (and before the first / after the last): the flags alternate and say
// what F says, except where F is within `tol` of T.
void expect_consistent(const ParticleField& f, const Vec3& o, const Vec3& d, const RayHits& h, double t_lo,
                       double t_hi, double tol) {
  bool inside = h.starts_inside;
  double prev = t_lo;
  for (size_t k = 0; k <= h.hits.size(); ++k) {
    const double next = k < h.hits.size() ? h.hits[k].t : t_hi;
    ASSERT_LE(prev, next);
    const double mid = 0.5 * (prev + next);
    const double v = f.value(o + d * mid) - f.threshold();
    if (std::abs(v) > tol) {
      EXPECT_EQ(v >= 0, inside) << "stretch " << k << " [" << prev << ", " << next << "] F - T = " << v;
    }
    if (k < h.hits.size()) {
      EXPECT_EQ(h.hits[k].entering, !inside) << "hit " << k;
      inside = !inside;
      prev = next;
    }
  }
  EXPECT_FALSE(inside) << "a ray ending far outside ends outside";
}

}  // namespace

// ---- the root solvers ----------------------------------------------------------------------

static std::vector<double> expand(const std::vector<double>& roots, const std::vector<double>& extra = {}) {
  std::vector<double> c{1.0};
  for (double r : roots) {
    std::vector<double> n(c.size() + 1, 0.0);
    for (size_t j = 0; j < c.size(); ++j) {
      n[j + 1] += c[j];
      n[j] -= r * c[j];
    }
    c = n;
  }
  if (!extra.empty()) {  // times a polynomial without real roots
    std::vector<double> n(c.size() + extra.size() - 1, 0.0);
    for (size_t i = 0; i < c.size(); ++i)
      for (size_t j = 0; j < extra.size(); ++j) n[i + j] += c[i] * extra[j];
    c = n;
  }
  return c;
}

TEST(RayRoots, SolversFindEverySimpleRootToFullPrecision) {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(0.02, 0.98);
  for (int trial = 0; trial < 500; ++trial) {
    const int m = 1 + trial % 4;
    std::vector<double> roots;
    for (int i = 0; i < m; ++i) roots.push_back(u(rng));
    std::sort(roots.begin(), roots.end());
    bool separated = true;
    for (int i = 1; i < m; ++i) separated &= roots[size_t(i)] - roots[size_t(i - 1)] > 1e-3;
    if (!separated) continue;
    // Degree 4 with m real roots in (0, 1) (+ roots outside / a complex pair), and degree 6.
    std::vector<double> outside = {-1.5, 2.5, 3.5, -4.0};
    std::vector<double> r4 = roots;
    while (r4.size() < 4) r4.push_back(outside[r4.size()]);
    const std::vector<double> c4 = expand(r4);
    const std::vector<double> c6 = expand(roots, m <= 2 ? std::vector<double>{1.0, 0.3, 2.0} : std::vector<double>{1.0});
    detail::IntervalCrossings a, b, c;
    detail::crossings_closed_form(c4.data(), 4, &a);
    detail::crossings_bernstein(c4.data(), 4, &b);
    detail::crossings_bernstein(c6.data(), int(c6.size()) - 1, &c);
    for (const auto* x : {&a, &b, &c}) {
      ASSERT_EQ(x->count, m) << "trial " << trial;
      for (int i = 0; i < m; ++i) {
        // Full precision up to the root's condition: the coefficients carry rounding of
        // ~1e-16, which moves a root by that over |p'(root)| (small for clustered roots).
        double slope = 1;
        for (double o : (x == &c ? roots : r4))
          if (o != roots[size_t(i)]) slope *= std::abs(roots[size_t(i)] - o);
        EXPECT_NEAR(x->c[i].u, roots[size_t(i)], 1e-13 + 1e-14 / slope) << "trial " << trial;
      }
      EXPECT_EQ(x->start_inside != x->end_inside, m % 2 == 1);
    }
  }
}

// The crossings that remain once pairs with nothing above `eps` between them are dropped (the
// caster's tangent rule, applied here to one interval).
static std::vector<double> resolved(const detail::IntervalCrossings& x, double eps) {
  std::vector<std::pair<double, double>> kept;  // u, gap
  for (int k = 0; k < x.count; ++k) {
    if (!kept.empty() && x.c[k].gap <= eps) {
      kept.pop_back();
      continue;
    }
    kept.push_back({x.c[k].u, x.c[k].gap});
  }
  std::vector<double> u;
  for (const auto& k : kept) u.push_back(k.first);
  return u;
}

TEST(RayRoots, DoubleRootsAreNoCrossing) {
  // (u - 0.3)^2 (u - 0.7) (u + 2): one crossing, at 0.7; the touch at 0.3 is none (or, with
  // the coefficients rounded, a pair with nothing above rounding between them).
  const auto c1 = expand({0.3, 0.3, 0.7, -2.0});
  // (u - 0.25)^2 (u - 0.625)^2: two touches, no crossing.
  const auto c2 = expand({0.25, 0.25, 0.625, 0.625});
  // -(u - 0.5)^2 (u^2 + 1): touches 0 from below.
  const auto c3 = expand({0.5, 0.5}, {-1.0, 0.0, -1.0});
  for (const auto& [c, want] : {std::pair{c1, 1}, std::pair{c2, 0}, std::pair{c3, 0}}) {
    detail::IntervalCrossings a, b;
    detail::crossings_closed_form(c.data(), 4, &a);
    detail::crossings_bernstein(c.data(), 4, &b);
    for (const auto* x : {&a, &b}) {
      const auto u = resolved(*x, 1e-14);
      ASSERT_EQ(int(u.size()), want);
      if (want == 1) {
        EXPECT_NEAR(u[0], 0.7, 1e-13);
      }
      EXPECT_EQ(x->start_inside != x->end_inside, want == 1);
    }
  }
}

TEST(RayRoots, QuarticClosedFormMatchesKnownRoots) {
  double r[4];
  const auto c = expand({-3.0, -0.5, 0.25, 4.0});
  const int n = detail::solve_quartic(c.data(), r);
  ASSERT_EQ(n, 4);
  std::sort(r, r + 4);
  EXPECT_NEAR(r[0], -3.0, 1e-12);
  EXPECT_NEAR(r[1], -0.5, 1e-12);
  EXPECT_NEAR(r[2], 0.25, 1e-12);
  EXPECT_NEAR(r[3], 4.0, 1e-12);
  const auto q = expand({1.0, 2.0}, {1.0, 0.0, 1.0});  // (x-1)(x-2)(x^2+1)
  EXPECT_EQ(detail::solve_quartic(q.data(), r), 2);
}

// ---- one particle --------------------------------------------------------------------------

class OneParticleRay : public ::testing::TestWithParam<Kernel> {};

TEST_P(OneParticleRay, HitsTheAnalyticSphere) {
  const Kernel k = GetParam();
  std::mt19937_64 rng(11);
  for (const double R : {1.0, 1e-3, 250.0}) {
    for (const Vec3 c0 : {Vec3{0.013, -0.021, 0.007}, Vec3{1000.3, -2000.1, 500.7}}) {
      const Vec3 centre = c0 * R;
      const double T = 0.4;
      const RayCaster caster(ParticleField({centre}, params(k, R, T)));
      const double rs = R * std::sqrt(kernel_inverse(k, T));
      for (int i = 0; i < 40; ++i) {
        const Vec3 d = random_unit(rng);
        const Vec3 side = orthogonal(d, rng);
        const double b = rs * (i < 30 ? 0.99 * i / 30.0 : 1.0 + 1e-6 + 0.1 * (i - 30));  // impact parameter
        const double back = 3.0 * R + 0.37 * R * i;
        const Vec3 o = centre + side * b - d * back;
        const double len = 0.5 + 0.1 * i;  // direction of any length: t in its units
        const RayHits h = caster.all_hits(o, d * len);
        if (b >= rs) {
          EXPECT_TRUE(h.hits.empty()) << kernel_name(k) << " b/rs = " << b / rs;
          EXPECT_FALSE(caster.first_hit(o, d * len).has_value());
          continue;
        }
        ASSERT_EQ(h.hits.size(), 2u) << kernel_name(k) << " b/rs = " << b / rs;
        EXPECT_FALSE(h.starts_inside);
        const double half = std::sqrt(rs * rs - b * b);
        const double want[2] = {(back - half) / len, (back + half) / len};
        for (int j = 0; j < 2; ++j) {
          const RayHit& hit = h.hits[size_t(j)];
          EXPECT_EQ(hit.entering, j == 0);
          EXPECT_NEAR(hit.t, want[j], 1e-9 * rs / len) << kernel_name(k) << " R " << R;
          EXPECT_NEAR(distance(hit.position, centre), rs, 1e-9 * rs) << kernel_name(k) << " R " << R;
          EXPECT_GT(dot(hit.normal, normalized(hit.position - centre)), 1.0 - 1e-9);
        }
        const auto first = caster.first_hit(o, d * len);
        ASSERT_TRUE(first.has_value());
        EXPECT_EQ(first->t, h.hits[0].t);
        // From the centre: starts inside, leaves once at rs.
        const RayHits in = caster.all_hits(centre, d);
        EXPECT_TRUE(in.starts_inside);
        ASSERT_EQ(in.hits.size(), 1u);
        EXPECT_FALSE(in.hits[0].entering);
        EXPECT_NEAR(in.hits[0].t, rs, 1e-9 * rs);
      }
    }
  }
}

// A tangent ray touches the iso-sphere without crossing it: no hit, and never a single or a
// doubled hit for rays that come ever closer to it.
TEST_P(OneParticleRay, TangentRaysGiveNoSpuriousDoubleRoots) {
  const Kernel k = GetParam();
  const double R = 1.0, T = 0.4;
  const Vec3 centre{0.3, -0.2, 0.1};
  const RayCaster caster(ParticleField({centre}, params(k, R, T)));
  const double rs = std::sqrt(kernel_inverse(k, T));
  std::mt19937_64 rng(3);
  for (int i = 0; i < 50; ++i) {
    const Vec3 d = random_unit(rng), side = orthogonal(d, rng);
    // Exactly tangent (as far as doubles go), and a ladder of offsets to both sides.
    for (const double rel : {0.0, 1e-15, -1e-15, 1e-12, -1e-12, 1e-9, -1e-9, 1e-6, -1e-6, -1e-4}) {
      const double b = rs * (1.0 + rel);
      const Vec3 o = centre + side * b - d * 3.0;
      const RayHits h = caster.all_hits(o, d);
      ASSERT_TRUE(h.hits.size() == 0 || h.hits.size() == 2) << "rel " << rel;
      // Touching or missing: nothing. Crossing by 1e-9 of the radius: both hits, except for
      // Blinn, whose march resolves slivers down to kBlinnMinStep R only.
      if (rel >= 0) {
        EXPECT_TRUE(h.hits.empty()) << kernel_name(k) << " rel " << rel;
      }
      if (rel <= -1e-4 || (rel <= -1e-9 && k != Kernel::Blinn)) {
        EXPECT_EQ(h.hits.size(), 2u) << kernel_name(k) << " rel " << rel;
      }
      if (h.hits.size() == 2) {
        EXPECT_TRUE(h.hits[0].entering);
        EXPECT_FALSE(h.hits[1].entering);
        EXPECT_LT(h.hits[0].t, h.hits[1].t);  // never the same point twice
        const double want = std::sqrt(std::max(0.0, rs * rs - b * b));
        EXPECT_NEAR(h.hits[1].t - h.hits[0].t, 2 * want, 1e-6) << kernel_name(k) << " rel " << rel;
      }
    }
  }
}

INSTANTIATE_TEST_SUITE_P(Kernels, OneParticleRay, ::testing::ValuesIn(kAll), kname);

// ---- random configurations against brute force ----------------------------------------------

struct Config {
  Kernel kernel;
  bool varied;  // per-particle radii and strengths (some negative)
  uint64_t seed;
  bool anisotropic = false;  // ellipsoidal kernels (Yu and Turk), with smoothed centres
};

class RandomConfig : public ::testing::TestWithParam<Config> {};

// Dense sampling of F along the ray, then bisection of every sign change (the reference).
static std::vector<std::pair<double, bool>> brute_force(const ParticleField& f, const Vec3& o, const Vec3& d, double t0,
                                                 double t1, int samples) {
  std::vector<std::pair<double, bool>> out;
  auto in = [&](double t) { return f.value(o + d * t) >= f.threshold(); };
  bool prev = in(t0);
  double tp = t0;
  for (int i = 1; i <= samples; ++i) {
    const double t = t0 + (t1 - t0) * i / samples;
    const bool s = in(t);
    if (s != prev) {
      double lo = tp, hi = t;
      for (int it = 0; it < 80 && hi - lo > 1e-14; ++it) {
        const double m = 0.5 * (lo + hi);
        (in(m) == prev ? lo : hi) = m;
      }
      out.push_back({0.5 * (lo + hi), s});
    }
    prev = s;
    tp = t;
  }
  return out;
}

TEST_P(RandomConfig, AgreesWithDenseSamplingAndBisection) {
  const Config cfg = GetParam();
  std::mt19937_64 rng(cfg.seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const int n = 40;
  std::vector<Vec3> p;
  FieldParams fp = params(cfg.kernel, 1.0, 0.45);
  if (cfg.anisotropic) {
    // Few neighbours in a random cloud: let most particles get an ellipsoid, some stretched
    // to the limit, and move the centres.
    fp.anisotropy.enabled = true;
    fp.anisotropy.min_neighbors = 4;
    fp.anisotropy.max_stretch = 6;
    fp.anisotropy.smoothing = 0.4;
  }
  for (int i = 0; i < n; ++i) {
    p.push_back({3 * u(rng), 3 * u(rng), 3 * u(rng)});
    if (cfg.varied) {
      fp.radii.push_back(0.6 + 0.8 * u(rng));
      fp.strengths.push_back(i % 7 == 3 ? -0.5 : 0.5 + u(rng));
    }
  }
  const ParticleField field(p, fp);
  if (cfg.anisotropic) {
    ASSERT_GT(field.anisotropic_count(), size_t(n / 2));
  }
  const RayCaster caster(field);
  int total = 0;
  for (int r = 0; r < 30; ++r) {
    const Vec3 target{0.5 + 2 * u(rng), 0.5 + 2 * u(rng), 0.5 + 2 * u(rng)};
    const Vec3 d = random_unit(rng);
    const Vec3 o = target - d * 6.0;
    const RayHits h = caster.all_hits(o, d);
    const auto ref = brute_force(field, o, d, 0.0, 12.0, 24000);
    ASSERT_EQ(h.hits.size(), ref.size()) << kernel_name(cfg.kernel) << " ray " << r;
    EXPECT_FALSE(h.starts_inside);
    for (size_t k = 0; k < ref.size(); ++k) {
      EXPECT_NEAR(h.hits[k].t, ref[k].first, 1e-7) << kernel_name(cfg.kernel) << " ray " << r << " hit " << k;
      EXPECT_EQ(h.hits[k].entering, ref[k].second);
      // Positions on the surface, normals along -grad F.
      Vec3 g;
      const double v = field.value_and_gradient(h.hits[k].position, &g);
      EXPECT_NEAR(v, field.threshold(), 1e-9);
      EXPECT_GT(dot(h.hits[k].normal, normalized(-g)), 1 - 1e-9);
    }
    expect_consistent(field, o, d, h, 0.0, 12.0, 1e-9);
    // The first hit is the first of all hits, found by the early-stopping walk.
    const auto first = caster.first_hit(o, d);
    ASSERT_EQ(first.has_value(), !h.hits.empty());
    if (first) {
      EXPECT_EQ(first->t, h.hits[0].t);
      EXPECT_EQ(first->entering, h.hits[0].entering);
    }
    total += int(h.hits.size());
  }
  EXPECT_GT(total, 20);  // the configurations are not empty
}

INSTANTIATE_TEST_SUITE_P(Seeds, RandomConfig,
                         ::testing::Values(Config{Kernel::Wyvill, false, 1}, Config{Kernel::Poly4, false, 2},
                                           Config{Kernel::Poly6, false, 3}, Config{Kernel::Blinn, false, 4},
                                           Config{Kernel::Wyvill, true, 5}, Config{Kernel::Poly4, true, 6},
                                           Config{Kernel::Poly6, true, 7}, Config{Kernel::Blinn, true, 8},
                                           Config{Kernel::Wyvill, false, 9, true}, Config{Kernel::Poly4, false, 10, true},
                                           Config{Kernel::Poly6, true, 11, true}, Config{Kernel::Blinn, true, 12, true}),
                         [](const auto& info) {
                           return std::string(kernel_name(info.param.kernel)) + (info.param.varied ? "_varied_" : "_") +
                                  (info.param.anisotropic ? "anisotropic_" : "") + std::to_string(info.param.seed);
                         });

// Rays through saddles and necks: sweep a family of parallel rays across a random cluster in
// tiny steps, so that some graze the surface; every ray's hits must be consistent with F.
TEST(RayCaster, GrazingRaysStayConsistent) {
  std::mt19937_64 rng(42);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::vector<Vec3> p;
  for (int i = 0; i < 12; ++i) p.push_back({1.5 * u(rng), 1.5 * u(rng), 1.5 * u(rng)});
  for (Kernel k : {Kernel::Wyvill, Kernel::Poly4}) {
    const ParticleField field(p, params(k, 1.0, 0.8));
    const RayCaster caster(field);
    const Vec3 d = normalized(Vec3{1, 0.2, 0.1}), side = orthogonal(d, rng);
    // Find a hit/miss boundary by bisection on the offset, then probe around it.
    double hit = 0, miss = 3.0;
    const Vec3 base = Vec3{0.75, 0.75, 0.75} - d * 5.0;
    ASSERT_FALSE(caster.all_hits(base + side * hit, d).hits.empty());
    ASSERT_TRUE(caster.all_hits(base + side * miss, d).hits.empty());
    for (int it = 0; it < 200 && miss - hit > 1e-16; ++it) {
      const double m = 0.5 * (hit + miss);
      (caster.all_hits(base + side * m, d).hits.empty() ? miss : hit) = m;
    }
    for (int j = -20; j <= 20; ++j) {
      const double off = hit + j * 1e-13;
      const Vec3 o = base + side * off;
      const RayHits h = caster.all_hits(o, d);
      EXPECT_EQ(h.hits.size() % 2, 0u);
      for (size_t q = 1; q < h.hits.size(); ++q) EXPECT_LT(h.hits[q - 1].t, h.hits[q].t);
      expect_consistent(field, o, d, h, 0.0, 12.0, 1e-10);
    }
  }
}

// ---- agreement with the polygonized mesh ---------------------------------------------------

// Moller-Trumbore: the smallest t > 0 at which the ray meets a triangle of the mesh.
static std::optional<double> ray_mesh(const TriMesh& m, const Vec3& o, const Vec3& d) {
  std::optional<double> best;
  for (const Triangle& t : m.triangles) {
    const Vec3 a = m.positions[t[0]], b = m.positions[t[1]], c = m.positions[t[2]];
    const Vec3 e1 = b - a, e2 = c - a, pv = cross(d, e2);
    const double det = dot(e1, pv);
    if (std::abs(det) < 1e-300) continue;
    const Vec3 tv = o - a;
    const double uu = dot(tv, pv) / det;
    if (uu < 0 || uu > 1) continue;
    const Vec3 qv = cross(tv, e1);
    const double vv = dot(d, qv) / det;
    if (vv < 0 || uu + vv > 1) continue;
    const double tt = dot(e2, qv) / det;
    if (tt > 0 && (!best || tt < *best)) best = tt;
  }
  return best;
}

TEST(RayCaster, AgreesWithThePolygonizedMesh) {
  // A smooth blob of a few particles, polygonized on a fine grid. The mesh's error: vertices
  // on the surface (refined), triangles within the chord's sag; for cells below a quarter of
  // the surface's radius of curvature that is under 0.1 h (the bound polygonize's own tests
  // state for spheres). Along a ray meeting the surface at angle theta to its normal, the
  // first-hit distances may then differ by 0.1 h / cos(theta).
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  PointCloud c;
  for (int i = 0; i < 8; ++i) c.positions.push_back({1.2 * u(rng), 1.2 * u(rng), 1.2 * u(rng)});
  for (int variant = 0; variant < 5; ++variant) {
    // The four kernels, then Wyvill's with anisotropic kernels (stretched, smoothed centres).
    const Kernel k = variant < 4 ? kAll[variant] : Kernel::Wyvill;
    const bool aniso = variant == 4;
    PolygonizeOptions po;
    po.kernel = k;
    po.radius = 1.0;
    po.threshold = 0.5;
    if (aniso) {
      po.anisotropy.enabled = true;
      po.anisotropy.min_neighbors = 3;
      po.anisotropy.smoothing = 0.3;
    }
    // Blinn's exponential (k = 6.9) is much narrower than the polynomials at the same R: its
    // necks between the blobs curve more tightly, so it needs a finer grid for the cells to
    // stay below a quarter of the radius of curvature.
    po.cell_size = k == Kernel::Blinn ? 1.0 / 64 : 1.0 / 32;
    const PolygonizeResult mesh = polygonize(c, po);
    ASSERT_TRUE(topology_report(mesh.mesh).closed);
    FieldParams fp = params(k, 1.0, 0.5);
    fp.anisotropy = po.anisotropy;
    const ParticleField field(c.positions, fp);
    if (aniso) {
      ASSERT_EQ(field.anisotropic_count(), c.size());
    }
    const RayCaster caster(field);
    const double err = 0.1 * po.cell_size;
    int compared = 0;
    for (int r = 0; r < 150; ++r) {
      const Vec3 d = random_unit(rng);
      const Vec3 target{0.2 + 0.8 * u(rng), 0.2 + 0.8 * u(rng), 0.2 + 0.8 * u(rng)};
      const Vec3 o = target - d * 5.0;
      const auto ray = caster.first_hit(o, d);
      const auto tri = ray_mesh(mesh.mesh, o, d);
      ASSERT_EQ(ray.has_value(), tri.has_value()) << kernel_name(k) << " ray " << r;  // targets lie deep inside
      if (!ray) continue;
      const double cosv = std::abs(dot(ray->normal, d));
      if (cosv < 0.2) continue;
      EXPECT_LE(std::abs(ray->t - *tri), err / cosv) << kernel_name(k) << " ray " << r << " cos " << cosv;
      ++compared;
    }
    EXPECT_GT(compared, 100);
  }
}

// ---- the seed's worst case, cost, ranges --------------------------------------------------------

// N separate particles on the x axis: a ray along it meets 2N crossings (seed section 5.1.3),
// all found, in order; the first hit needs only the first particles.
TEST(RayCaster, ParticlesOnALineGiveTwoHitsEach) {
  const int n = 50;
  std::vector<Vec3> p;
  for (int i = 0; i < n; ++i) p.push_back({3.0 * i, 0, 0});
  const double rs = std::sqrt(kernel_inverse(Kernel::Wyvill, 0.5));
  const RayCaster caster(ParticleField(p, params(Kernel::Wyvill, 1.0, 0.5)));
  RayStats all, first;
  const RayHits h = caster.all_hits({-5, 1e-3, 0}, {1, 0, 0}, 0, 1e9, &all);
  ASSERT_EQ(h.hits.size(), size_t(2 * n));
  const double half = std::sqrt(rs * rs - 1e-6);
  for (int i = 0; i < n; ++i) {
    EXPECT_NEAR(h.hits[size_t(2 * i)].t, 5 + 3.0 * i - half, 1e-12);
    EXPECT_NEAR(h.hits[size_t(2 * i + 1)].t, 5 + 3.0 * i + half, 1e-12);
  }
  EXPECT_EQ(all.spheres_entered, uint64_t(n));
  EXPECT_EQ(all.intervals, uint64_t(n));  // one interval per sphere: linear in what the ray meets
  const auto f = caster.first_hit({-5, 1e-3, 0}, {1, 0, 0}, 0, 1e9, &first);
  ASSERT_TRUE(f.has_value());
  EXPECT_LE(first.spheres_entered, uint64_t(n / 5));  // one leaf or two, not the line
  EXPECT_LT(first.nodes_visited, all.nodes_visited / 3);
  // The t range cuts the list; a range starting inside reports it.
  const RayHits part = caster.all_hits({-5, 1e-3, 0}, {1, 0, 0}, 5.0, 8.2);
  EXPECT_TRUE(part.starts_inside);
  ASSERT_EQ(part.hits.size(), 2u);
  EXPECT_FALSE(part.hits[0].entering);
  EXPECT_TRUE(part.hits[1].entering);
  // Backwards along the axis, with negative t allowed.
  const RayHits back = caster.all_hits({-5, 1e-3, 0}, {-1, 0, 0}, -1e9, 0);
  EXPECT_EQ(back.hits.size(), size_t(2 * n));
  EXPECT_NEAR(back.hits.back().t, -(5 - half), 1e-12);
}

TEST(RayCaster, BatchesAreDeterministicAndMatchSingleQueries) {
  const PointCloud c = test::random_cloud(3000, 9, 3.0);
  const RayCaster caster(ParticleField(c, params(Kernel::Wyvill, 0.25, 0.6)));
  std::mt19937_64 rng(1);
  std::vector<Vec3> o, d;
  for (int i = 0; i < 2000; ++i) {
    const Vec3 dir = random_unit(rng);
    o.push_back(Vec3{1.5, 1.5, 1.5} - dir * 4.0 + orthogonal(dir, rng) * (1.5 * std::sqrt(double(i % 100) / 100.0)));
    d.push_back(dir * 2.0);
  }
  RaycastOptions o1, o2;
  o1.threads = 1;
  o2.threads = 2;
  const FirstHits a = cast_first_hits(caster, o.data(), d.data(), o.size(), o1);
  const FirstHits b = cast_first_hits(caster, o.data(), d.data(), o.size(), o2);
  EXPECT_EQ(a.t, b.t);
  EXPECT_EQ(a.entering, b.entering);
  EXPECT_GT(a.hit_count, 500u);
  const AllHits x = cast_all_hits(caster, o.data(), d.data(), o.size(), o1);
  const AllHits y = cast_all_hits(caster, o.data(), d.data(), o.size(), o2);
  ASSERT_EQ(x.offsets, y.offsets);
  ASSERT_EQ(x.hits.size(), y.hits.size());
  for (size_t i = 0; i < x.hits.size(); ++i) {
    EXPECT_EQ(x.hits[i].t, y.hits[i].t);
    EXPECT_EQ(x.hits[i].normal, y.hits[i].normal);
  }
  for (size_t i = 0; i < o.size(); i += 37) {
    const RayHits h = caster.all_hits(o[i], d[i]);
    ASSERT_EQ(h.hits.size(), x.offsets[i + 1] - x.offsets[i]);
    if (!h.hits.empty()) {
      EXPECT_EQ(h.hits[0].t, a.t[i]);
      EXPECT_EQ(h.hits[0].position, a.positions[i]);
    } else {
      EXPECT_TRUE(std::isinf(a.t[i]));
    }
  }
}

// The first crossing must be found wherever it lies, however small the part of the surface
// it belongs to: a caster may start a ray's exact sweep late only where it has proved F < T
// before the start. Small isolated blobs (one particle whose peak is just above T: a sphere of
// a tenth of the radius or less) and a thin, holed sheet in front of a big block, met head on
// and grazed, with every kernel, spheres and ellipsoids: the first hit is the blob's analytic
// sphere (when the ray meets it), the first sign change of densely sampled F, and all_hits'
// first, on the same ray.
TEST(RayCaster, FirstCrossingsOfSmallBlobsAndThinSheetsInFrontOfABlock) {
  for (const Kernel k : kAll) {
    for (const bool aniso : {false, true}) {
      const double T = 0.45;
      std::vector<Vec3> p;
      FieldParams fp = params(k, 1.0, T);
      // The block behind: 8 x 8 x 8 particles, spacing 0.5, from x = 3.
      for (int x = 0; x < 8; ++x)
        for (int y = 0; y < 8; ++y)
          for (int z = 0; z < 8; ++z) {
            p.push_back({3.0 + 0.5 * x, -1.75 + 0.5 * y, -1.75 + 0.5 * z});
            fp.strengths.push_back(1.0);
          }
      // Blobs: one particle each, peak w = T / 0.98, 0.96, 0.9, far from every other support.
      const double peaks[] = {0.98, 0.96, 0.9};
      const Vec3 blob[] = {{0, 0, 0}, {0, 2.6, 0}, {0, 0, 2.6}};
      for (int b = 0; b < 3; ++b) {
        p.push_back(blob[b]);
        fp.strengths.push_back(T / peaks[b]);
      }
      // A sheet at x = -4.5: 9 x 9 particles of spacing 0.5 whose summed peak barely reaches T
      // (holes between the particles for some kernels).
      for (int y = 0; y < 9; ++y)
        for (int z = 0; z < 9; ++z) {
          p.push_back({-4.5, -2.0 + 0.5 * y, -2.0 + 0.5 * z});
          fp.strengths.push_back(T / 3.0);
        }
      if (aniso) {
        fp.anisotropy.enabled = true;
        fp.anisotropy.min_neighbors = 3;
        fp.anisotropy.max_stretch = 4;
      }
      const ParticleField field(p, fp);
      const RayCaster caster(field);
      const std::string what = std::string(kernel_name(k)) + (aniso ? " anisotropic" : "");
      // The first hit of o + t d, checked against the reference on [0, t_end]; inf for none.
      auto check = [&](const Vec3& o, const Vec3& d, double t_end, const char* ray) {
        const auto first = caster.first_hit(o, d);
        const RayHits all = caster.all_hits(o, d);
        const auto ref = brute_force(field, o, d, 0.0, t_end, 16000);
        EXPECT_EQ(first.has_value(), !ref.empty()) << what << " " << ray;
        EXPECT_EQ(all.hits.empty(), ref.empty()) << what << " " << ray;
        if (!first || ref.empty() || all.hits.empty()) return std::numeric_limits<double>::infinity();
        EXPECT_NEAR(first->t, ref[0].first, 1e-7) << what << " " << ray;
        EXPECT_EQ(first->t, all.hits[0].t) << what << " " << ray;
        return first->t;
      };
      // Each blob met at offsets 0 .. 1.02 of its iso-sphere's radius, from the front and
      // obliquely, then the block.
      for (int b = 0; b < 3; ++b) {
        const double rs = std::sqrt(kernel_inverse(k, peaks[b]));  // the blob's iso-sphere (spheres)
        for (const double f : {0.0, 0.5, 0.9, 0.99, 1.02}) {
          for (const Vec3& dir : {Vec3{1, 0, 0}, normalized(Vec3{1, 0.3, -0.2})}) {
            const Vec3 side = normalized(cross(dir, Vec3{0, 0.6, 0.8}));
            const Vec3 o = blob[b] - dir * 2.5 + side * (f * rs);
            const double t = check(o, dir, 9.0, "blob ray");
            if (!aniso && f < 1) {
              EXPECT_NEAR(t, 2.5 - rs * std::sqrt(1 - f * f), 1e-9) << what << " blob " << b << " offset " << f;
            } else if (!aniso) {
              EXPECT_GT(t, 4.0) << what << " blob " << b << " offset " << f;  // missed: the block or none
            }
          }
        }
      }
      // The sheet, across and nearly along it.
      std::mt19937_64 rng(3);
      std::uniform_real_distribution<double> u(-1.0, 1.0);
      for (int r = 0; r < 16; ++r) {
        const Vec3 dir = normalized(Vec3{1, 0.15 * u(rng), 0.15 * u(rng)});
        const Vec3 o{-6.5, 0.8 * u(rng), 0.8 * u(rng)};
        check(o, dir, 12.0, "sheet ray");
      }
      for (int r = 0; r < 12; ++r) {
        const Vec3 dir = normalized(Vec3{0.05 * u(rng), 1, 0.3 * u(rng)});
        const Vec3 o{-4.5 + 0.4 * u(rng), -3.5, 0.5 * u(rng)};
        check(o, dir, 8.0, "ray along the sheet");
      }
    }
  }
}

// Outside the surface an interval is excluded without a loop over its particles where the
// bound of the last such loop, raised by the particles' steepest rise since, stays below T.
// Here the bound is nearly tight: one particle on the ray's line rises at the kernel's
// steepest (2 sqrt(s) |g'(s)| largest) over the interval [a, b] between two far, faint
// particles' events, and T is just below its value at b, so the crossing lies just before b.
// A slope 2 % too small would exclude the interval and move the hit to b.
TEST(RayCaster, TheRunningBoundHoldsWhereAParticleRisesAtItsSteepest) {
  for (const Kernel k : {Kernel::Wyvill, Kernel::Poly4, Kernel::Poly6}) {
    SCOPED_TRACE(kernel_name(k));
    // s* where a particle's value along a line through its centre changes fastest.
    double s_star = 0, steepest = 0;
    for (int i = 1; i < 100000; ++i) {
      const double s = i / 100000.0;
      const double h = 2 * std::sqrt(s) * std::abs(kernel_derivative(k, s));
      if (h > steepest) steepest = h, s_star = s;
    }
    // The particle at the origin (R = 1, w = 1), met along +x: F = g(x^2) for x in [-1, 0].
    const double delta = 0.04, a = -std::sqrt(s_star) - delta, b = -std::sqrt(s_star) + delta;
    ASSERT_GT(a, -1.0);
    ASSERT_LT(b, 0.0);
    auto F = [&](double x) { return kernel_value(k, x * x); };
    const double T = F(b) - 1e-4;
    // Two faint particles beside the line, whose supports end at a and begin at b.
    const double e = 0.95, c = std::sqrt(1 - e * e);
    const std::vector<Vec3> p{{0, 0, 0}, {a - c, e, 0}, {b + c, e, 0}};
    FieldParams fp = params(k, 1.0, T);
    fp.strengths = {1.0, 1e-3, 1e-3};
    const ParticleField field(p, fp);
    const RayCaster caster(field);
    // The crossing: g(x^2) = T on [a, b], by bisection (F rises there).
    double lo = a, hi = b;
    ASSERT_LT(F(lo), T);
    ASSERT_GT(F(hi), T);
    for (int it = 0; it < 200; ++it) {
      const double mid = 0.5 * (lo + hi);
      (F(mid) < T ? lo : hi) = mid;
    }
    const Vec3 origin{-3, 0, 0}, dir{1, 0, 0};
    const auto hit = caster.first_hit(origin, dir);
    ASSERT_TRUE(hit.has_value());
    EXPECT_NEAR(hit->t, lo + 3.0, 1e-9);
    EXPECT_TRUE(hit->entering);
    const RayHits all = caster.all_hits(origin, dir);
    ASSERT_FALSE(all.hits.empty());
    EXPECT_EQ(all.hits[0].t, hit->t);
  }
}

TEST(RayCaster, BadRaysGiveClearErrors) {
  const RayCaster caster(ParticleField({{0, 0, 0}}, params(Kernel::Poly4, 1, 0.5)));
  auto message = [&](auto&& f) {
    try {
      f();
    } catch (const Error& e) {
      EXPECT_EQ(e.status(), Status::InvalidArgument);
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_NE(message([&] { caster.all_hits({0, 0, 0}, {0, 0, 0}); }).find("directions is zero"), std::string::npos);
  EXPECT_NE(message([&] { caster.first_hit({NAN, 0, 0}, {1, 0, 0}); }).find("origins.x is"), std::string::npos);
  EXPECT_NE(message([&] { caster.all_hits({0, 0, 0}, {1, 0, 0}, 2, 1); }).find("empty"), std::string::npos);
  std::vector<Vec3> o(5, Vec3{0, 0, -3}), d(5, Vec3{0, 0, 1});
  d[3] = {0, INFINITY, 0};
  EXPECT_NE(message([&] { cast_first_hits(caster, o.data(), d.data(), 5); }).find("directions[3].y is inf"),
            std::string::npos);
  // Cancelling.
  RaycastOptions opt;
  int calls = 0;
  opt.progress = [&](std::string_view, double) { return ++calls < 1; };
  d[3] = {0, 0, 1};
  EXPECT_THROW(cast_first_hits(caster, o.data(), d.data(), 5, opt), Error);
  // A field with only zero-strength particles has no surface.
  FieldParams zp = params(Kernel::Wyvill, 1, 0.5);
  zp.strengths = {0.0};
  const RayCaster none(ParticleField({{0, 0, 0}}, zp));
  EXPECT_TRUE(none.all_hits({0, 0, -3}, {0, 0, 1}).hits.empty());
  EXPECT_EQ(none.node_count(), 0u);
}
