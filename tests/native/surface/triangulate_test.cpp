// The seed's test, exactly: the fast triangulation against a brute-force evaluation of the
// definition, the shapes the issue names, invariances, and bad input.
#include "particlemesh/surface/triangulate.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <numeric>

#include "particlemesh/core/error.h"
#include "particlemesh/io/mesh_io.h"
#include "particlemesh/mesh/topology_report.h"
#include "particlemesh/sample/shapes.h"
#include "support/test_support.h"
#include "surface/smallest_sphere.h"

using namespace particlemesh;
using test::canonical;

namespace {

// Does triangle (i, j, k) pass the seed's test against *every* point of the cloud?
bool passes_definition(const std::vector<Vec3>& P, uint32_t i, uint32_t j, uint32_t k, double L) {
  const double L2 = L * L;
  if (squared_distance(P[i], P[j]) > L2 || squared_distance(P[i], P[k]) > L2 ||
      squared_distance(P[j], P[k]) > L2)
    return false;
  const auto s = detail::smallest_sphere(P[i], P[j], P[k]);
  if (s.degenerate) return false;
  for (uint32_t q = 0; q < P.size(); ++q) {
    if (q == i || q == j || q == k) continue;
    if (detail::sphere_contains(s, P[q])) return false;
  }
  return true;
}

// Every triangle of the definition that has vertex i (neighbours found by brute force).
std::vector<Triangle> brute_force_at(const std::vector<Vec3>& P, uint32_t i, double L) {
  std::vector<uint32_t> near;
  for (uint32_t j = 0; j < P.size(); ++j)
    if (j != i && squared_distance(P[i], P[j]) <= L * L) near.push_back(j);
  std::vector<Triangle> out;
  for (size_t a = 0; a < near.size(); ++a)
    for (size_t b = a + 1; b < near.size(); ++b)
      if (passes_definition(P, i, near[a], near[b], L)) out.push_back({i, near[a], near[b]});
  return canonical(out);
}

std::vector<Triangle> brute_force(const std::vector<Vec3>& P, double L) {
  std::vector<Triangle> all;
  for (uint32_t i = 0; i < P.size(); ++i)
    for (const Triangle& t : brute_force_at(P, i, L))
      if (t[0] == i) all.push_back(t);
  return canonical(all);
}

std::vector<Triangle> triangles_with(const std::vector<Triangle>& tris, uint32_t v) {
  std::vector<Triangle> out;
  for (const auto& t : tris)
    if (t[0] == v || t[1] == v || t[2] == v) out.push_back(t);
  return canonical(out);
}

Vec3 rotate(const Vec3& p, double ax, double ay, double az) {
  Vec3 q = p;
  q = {q.x, std::cos(ax) * q.y - std::sin(ax) * q.z, std::sin(ax) * q.y + std::cos(ax) * q.z};
  q = {std::cos(ay) * q.x + std::sin(ay) * q.z, q.y, -std::sin(ay) * q.x + std::cos(ay) * q.z};
  q = {std::cos(az) * q.x - std::sin(az) * q.y, std::sin(az) * q.x + std::cos(az) * q.y, q.z};
  return q;
}

PointCloud hex_parallelogram(int n, double spacing) {
  PointCloud c;
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i)
      c.positions.push_back({(i + 0.5 * j) * spacing, j * spacing * std::sqrt(3.0) / 2, 0});
  return c;
}

}  // namespace

TEST(TriangulateRaw, EqualsBruteForceOnRandomClouds) {
  for (uint64_t seed = 1; seed <= 6; ++seed) {
    const PointCloud c = test::random_cloud(120 + 40 * seed, seed);
    const TriangulateResult r = triangulate_raw(c);
    const auto want = brute_force(c.positions, r.stats.max_edge);
    EXPECT_EQ(r.mesh.triangles, want) << "seed " << seed;
    EXPECT_GT(want.size(), 0u);
  }
}

TEST(TriangulateRaw, EqualsBruteForceWithLargerEdgeFactors) {
  const PointCloud c = test::random_cloud(150, 42);
  for (double f : {1.2, 3.0, 4.5}) {
    TriangulateOptions o;
    o.max_edge_factor = f;
    const TriangulateResult r = triangulate_raw(c, o);
    EXPECT_EQ(r.mesh.triangles, brute_force(c.positions, r.stats.max_edge)) << "factor " << f;
  }
}

TEST(TriangulateRaw, EqualsBruteForceOnSampledSurfaces) {
  // Every candidate on a small sphere, then a sample of vertices on a larger one.
  const PointCloud small = poisson_disk_sample(icosphere_mesh(4), 0.12, 5);
  const TriangulateResult rs = triangulate_raw(small);
  EXPECT_EQ(rs.mesh.triangles, brute_force(small.positions, rs.stats.max_edge));

  const PointCloud big = fibonacci_sphere(20000);
  const TriangulateResult rb = triangulate_raw(big);
  for (uint32_t v = 0; v < big.size(); v += 997)
    EXPECT_EQ(triangles_with(rb.mesh.triangles, v), brute_force_at(big.positions, v, rb.stats.max_edge))
        << "vertex " << v;
}

TEST(TriangulateRaw, EqualsBruteForceOnRealPoissonSample) {
  PM_REQUIRE_DATA(path, "points/bunny_poisson.ply");
  const PointCloud c = read_point_cloud(path);
  const TriangulateResult r = triangulate_raw(c);
  for (uint32_t v = 0; v < c.size(); v += 181)
    EXPECT_EQ(triangles_with(r.mesh.triangles, v), brute_force_at(c.positions, v, r.stats.max_edge))
        << "vertex " << v;
}

TEST(TriangulateRaw, MatchesTheIndependentReferenceCounts) {
  // shared/notes/seed-test-behaviour.md, measured with an independent implementation.
  PM_REQUIRE_DATA(bunny, "points/bunny_poisson.ply");
  PM_REQUIRE_DATA(spot, "points/spot_poisson.ply");
  const TriangulateResult b = triangulate_raw(read_point_cloud(bunny));
  EXPECT_EQ(b.stats.candidates, 34924u);
  EXPECT_EQ(b.stats.kept, 21591u);
  EXPECT_EQ(topology_report(b.mesh).nonmanifold_edges, 6458u);
  const TriangulateResult s = triangulate_raw(read_point_cloud(spot));
  EXPECT_EQ(s.stats.candidates, 34325u);
  EXPECT_EQ(s.stats.kept, 21499u);
}

TEST(TriangulateRaw, RegularTetrahedronGivesItsFourFaces) {
  PointCloud c;
  c.positions = {{1, 1, 1}, {1, -1, -1}, {-1, 1, -1}, {-1, -1, 1}};
  const TriangulateResult r = triangulate_raw(c);
  EXPECT_EQ(r.mesh.triangles, (std::vector<Triangle>{{0, 1, 2}, {0, 1, 3}, {0, 2, 3}, {1, 2, 3}}));
}

TEST(TriangulateRaw, HexagonalSheetGivesOnlyItsEquilateralTriangles) {
  const int n = 25;
  const PointCloud c = hex_parallelogram(n, 0.5);
  const TriangulateResult r = triangulate_raw(c);
  EXPECT_NEAR(r.stats.spacing, 0.5, 1e-12);
  EXPECT_EQ(r.mesh.triangles.size(), size_t(2 * (n - 1) * (n - 1)));
  for (const auto& t : r.mesh.triangles)
    for (int e = 0; e < 3; ++e)
      EXPECT_NEAR(distance(c.positions[t[e]], c.positions[t[(e + 1) % 3]]), 0.5, 1e-9);
  const auto edges = test::edge_counts(r.mesh.triangles);
  size_t boundary = 0;
  for (const auto& [e, count] : edges) {
    EXPECT_LE(count, 2);
    boundary += count == 1;
  }
  EXPECT_EQ(boundary, size_t(4 * (n - 1)));  // only the outline has one triangle per edge
  const TopologyReport rep = topology_report(r.mesh);
  EXPECT_EQ(rep.euler_characteristic, 1);
  EXPECT_EQ(rep.boundary_loops, 1u);
}

TEST(TriangulateRaw, SquareLatticeGetsExactlyTwoTrianglesPerSquare) {
  for (double angle : {0.0, 0.3}) {  // axis-aligned (exact ties) and rotated (rounded ties)
    const int n = 30;
    PointCloud c = square_lattice(n, n, 1.0);
    for (auto& p : c.positions) p = rotate(p, angle, 0.5 * angle, 0.7 * angle) + Vec3{0.25, -3, 7};
    const TriangulateResult r = triangulate_raw(c);
    EXPECT_EQ(r.mesh.triangles.size(), size_t(2 * (n - 1) * (n - 1))) << "angle " << angle;
    EXPECT_GT(r.stats.ties, 0u);
    // Each unit square holds exactly one diagonal and its two triangles do not overlap.
    const auto edges = test::edge_counts(r.mesh.triangles);
    size_t diagonals = 0;
    for (const auto& [e, count] : edges) {
      EXPECT_LE(count, 2);
      const double len = distance(c.positions[e.first], c.positions[e.second]);
      if (len > 1.2) {
        ++diagonals;
        EXPECT_NEAR(len, std::sqrt(2.0), 1e-9);
        EXPECT_EQ(count, 2);
      }
    }
    EXPECT_EQ(diagonals, size_t((n - 1) * (n - 1)));
    const TopologyReport rep = topology_report(r.mesh);
    EXPECT_EQ(rep.nonmanifold_edges, 0u);
    EXPECT_EQ(rep.euler_characteristic, 1);
  }
}

TEST(TriangulateRaw, SpheresFartherApartThanLStayApart) {
  PointCloud a = fibonacci_sphere(1500, 1.0, {0, 0, 0});
  const PointCloud b = fibonacci_sphere(1500, 1.0, {2.5, 0, 0});  // gap 0.5 >> L ~ 0.2
  a.positions.insert(a.positions.end(), b.positions.begin(), b.positions.end());
  a.normals.insert(a.normals.end(), b.normals.begin(), b.normals.end());
  const TriangulateResult r = triangulate_raw(a);
  EXPECT_LT(r.stats.max_edge, 0.5);
  const TopologyReport rep = topology_report(r.mesh);
  EXPECT_EQ(rep.components, 2u);
  for (const auto& t : r.mesh.triangles) EXPECT_EQ(t[0] < 1500, t[2] < 1500);
}

TEST(TriangulateRaw, InvariantUnderRigidMotionScalingPermutationAndThreads) {
  const PointCloud c = poisson_disk_sample(torus_mesh(1.0, 0.4, 120, 48), 0.06, 9);
  TriangulateOptions o;
  o.spacing = 0.06;
  const TriangulateResult base = triangulate_raw(c, o);
  ASSERT_GT(base.mesh.triangles.size(), 1000u);

  PointCloud moved = c;
  for (auto& p : moved.positions) p = rotate(p, 0.7, -1.1, 2.3) + Vec3{12.5, -3.25, 100};
  EXPECT_EQ(triangulate_raw(moved, o).mesh.triangles, base.mesh.triangles);

  for (double scale : {1e-4, 1e5}) {
    PointCloud scaled = c;
    for (auto& p : scaled.positions) p = p * scale;
    TriangulateOptions os = o;
    os.spacing = o.spacing * scale;
    EXPECT_EQ(triangulate_raw(scaled, os).mesh.triangles, base.mesh.triangles) << scale;
  }

  std::vector<uint32_t> perm(c.size());
  std::iota(perm.begin(), perm.end(), 0u);
  std::shuffle(perm.begin(), perm.end(), std::mt19937_64(5));
  PointCloud shuffled;
  for (uint32_t i = 0; i < c.size(); ++i) shuffled.positions.push_back(c.positions[perm[i]]);
  std::vector<Triangle> back = triangulate_raw(shuffled, o).mesh.triangles;
  for (auto& t : back)
    for (auto& v : t) v = perm[v];
  EXPECT_EQ(canonical(back), base.mesh.triangles);

  for (int threads : {1, 2, 3, 8}) {
    TriangulateOptions ot = o;
    ot.threads = threads;
    ot.spacing = 0;  // the estimate too must not depend on threads
    const TriangulateResult r = triangulate_raw(c, ot);
    static const std::vector<Triangle> first = r.mesh.triangles;
    EXPECT_EQ(r.mesh.triangles, first) << threads << " threads";
  }
}

TEST(TriangulateRaw, DuplicatesAreSetAsideAndChangeNothing) {
  const PointCloud c = poisson_disk_sample(icosphere_mesh(4), 0.1, 2);
  PointCloud d = c;
  for (uint32_t i = 0; i < c.size(); i += 10) d.positions.push_back(c.positions[i]);
  for (uint32_t i = 0; i < c.size(); i += 10) d.normals.push_back(c.normals[i]);
  const TriangulateResult a = triangulate_raw(c), b = triangulate_raw(d);
  EXPECT_EQ(b.stats.duplicate_points, (c.size() + 9) / 10);
  EXPECT_DOUBLE_EQ(a.stats.spacing, b.stats.spacing);
  EXPECT_EQ(a.mesh.triangles, b.mesh.triangles);
  EXPECT_EQ(b.mesh.positions.size(), d.size());  // every input particle stays a vertex
}

TEST(TriangulateRaw, CollinearAndCoincidentTripletsAreSkipped) {
  PointCloud line;
  for (int i = 0; i < 20; ++i) line.positions.push_back({double(i), 0, 0});
  const TriangulateResult r = triangulate_raw(line);
  EXPECT_TRUE(r.mesh.triangles.empty());
  EXPECT_GT(r.stats.degenerate, 0u);
}

TEST(TriangulateRaw, BadInputGivesClearErrors) {
  auto expect_error = [](const PointCloud& c, const TriangulateOptions& o, Status status, const std::string& text) {
    try {
      triangulate_raw(c, o);
      ADD_FAILURE() << "no error for: " << text;
    } catch (const Error& e) {
      EXPECT_EQ(e.status(), status) << e.what();
      EXPECT_NE(std::string(e.what()).find(text), std::string::npos) << e.what();
    }
  };
  const TriangulateOptions def;
  expect_error(PointCloud{}, def, Status::InvalidInput, "empty");
  PointCloud one;
  one.positions = {{0, 0, 0}};
  expect_error(one, def, Status::InvalidInput, "three points");
  PointCloud same;
  same.positions.assign(50, Vec3{1, 1, 1});
  expect_error(same, def, Status::InvalidInput, "coincide");
  PointCloud nan = test::random_cloud(100, 1);
  nan.positions[57].y = std::nan("");
  expect_error(nan, def, Status::InvalidInput, "positions[57].y is NaN");
  PointCloud inf = test::random_cloud(100, 1);
  inf.positions[3].z = INFINITY;
  expect_error(inf, def, Status::InvalidInput, "positions[3].z is infinite");
  const PointCloud ok = test::random_cloud(100, 1);
  TriangulateOptions neg;
  neg.spacing = -1;
  expect_error(ok, neg, Status::InvalidArgument, "spacing");
  TriangulateOptions fac;
  fac.max_edge_factor = std::nan("");
  expect_error(ok, fac, Status::InvalidArgument, "max_edge_factor");
  TriangulateOptions thr;
  thr.threads = -2;
  expect_error(ok, thr, Status::InvalidArgument, "threads");
  TriangulateOptions dense;
  dense.spacing = 0.5;  // far larger than the real spacing: every point neighbours dozens
  dense.max_neighbors = 20;
  expect_error(ok, dense, Status::LimitExceeded, "more than the limit of 20");
  PointCloud mismatch = test::random_cloud(10, 1);
  mismatch.normals.resize(3);
  expect_error(mismatch, def, Status::InvalidInput, "normals");
}

TEST(TriangulateRaw, ProgressIsReportedAndCancellationStops) {
  const PointCloud c = fibonacci_sphere(200000);
  std::vector<double> fractions;
  TriangulateOptions o;
  o.progress = [&](std::string_view, double f) {
    fractions.push_back(f);
    return true;
  };
  triangulate_raw(c, o);
  ASSERT_GE(fractions.size(), 3u);
  EXPECT_TRUE(std::is_sorted(fractions.begin(), fractions.end()));
  EXPECT_DOUBLE_EQ(fractions.back(), 1.0);

  int calls = 0;
  o.progress = [&](std::string_view stage, double) { return ++calls < 2 || stage == "never"; };
  try {
    triangulate_raw(c, o);
    FAIL() << "not cancelled";
  } catch (const Error& e) {
    EXPECT_EQ(e.status(), Status::Cancelled);
  }
}
