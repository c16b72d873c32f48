// The finished surface on unevenly sampled particles: each particle's edge limit from its
// own spacing (SurfaceOptions::local_spacing), and depth jumps seen from a scan's viewpoint.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>

#include "particlemesh/io/mesh_io.h"
#include "particlemesh/mesh/topology_report.h"
#include "particlemesh/sample/shapes.h"
#include "particlemesh/spatial/local_spacing.h"
#include "particlemesh/spatial/spacing.h"
#include "particlemesh/surface/reconstruct.h"
#include "particlemesh/surface/triangulate.h"
#include "support/test_support.h"

using namespace particlemesh;
using particlemesh::test::row_sheet;
using particlemesh::test::two_density_sphere;

namespace {

double longest_edge(const TriMesh& m) {
  double longest = 0;
  for (const Triangle& t : m.triangles)
    for (int k = 0; k < 3; ++k) longest = std::max(longest, distance(m.positions[t[k]], m.positions[t[(k + 1) % 3]]));
  return longest;
}

SurfaceOptions global() {
  SurfaceOptions o;
  o.local_spacing = false;
  return o;
}

}  // namespace

TEST(UnevenSampling, TwoDensitiesCloseWithLocalSpacingOnly) {
  // The upper half 2.8 times sparser: with one L (2 r0 of the dense half) its particles fall
  // out; with each particle's own, one closed sphere through every particle.
  const PointCloud c = two_density_sphere(20000, 2500);
  const SurfaceResult local = reconstruct_surface(c);
  const TopologyReport t = topology_report(local.mesh);
  EXPECT_TRUE(t.closed && t.manifold && t.consistently_oriented && t.outward);
  EXPECT_EQ(t.components, 1u);
  EXPECT_EQ(t.per_component[0].genus, 0);
  EXPECT_EQ(t.vertices_used, c.size());
  EXPECT_GT(local.surface.local_spacing.max, 2.0);
  EXPECT_NEAR(local.surface.local_spacing.min, 1.0, 0.02);
  const SurfaceResult one = reconstruct_surface(c, global());
  EXPECT_GT(one.surface.unused_points * 20, c.size());
  EXPECT_EQ(one.surface.local_spacing.max, 1.0);
}

TEST(UnevenSampling, ParticlesAtRandomCloseWithALongerReach) {
  // Points dropped uniformly at random (Blender's "Random" emission, a mesh sampled by area):
  // the triangles covering the surface reach much farther than the nearest neighbours (29 %
  // of a random sphere's Delaunay triangles have an edge over twice the local spacing). With
  // the limits of an even sampling the surface fell apart (a 3000-point sphere: 7 pieces,
  // 22 open loops); lengthened for the sampling's irregularity, it closes.
  const size_t n = particlemesh::test::kSanitized ? 3000 : 8000;
  const PointCloud sphere = particlemesh::test::random_sphere(n, 3);
  const PointCloud torus = particlemesh::test::random_surface_sample(torus_mesh(1.0, 0.4, 96, 48), n + n / 2, 4);
  for (const PointCloud* c : {&sphere, &torus}) {
    const SurfaceResult r = reconstruct_surface(*c);
    const TopologyReport t = topology_report(r.mesh);
    // About 0.48, past the 0.45 from which the reach is 1.75 x.
    EXPECT_GT(r.triangulation.sampling_irregularity, 0.45);
    EXPECT_EQ(r.triangulation.reach_factor, 1.75);
    EXPECT_TRUE(t.closed && t.manifold && t.consistently_oriented && t.outward);
    EXPECT_EQ(t.components, 1u);
    ASSERT_EQ(t.per_component.size(), 1u);
    EXPECT_EQ(t.per_component[0].genus, c == &torus ? 1 : 0);
    // At random some particles lie almost on top of another: at most 0.1 % passed by.
    EXPECT_GE(t.vertices_used * 1000, c->size() * 999);
    // Every triangle within the lengthened cap: 1.75 x 3 r0 x 2.
    EXPECT_LE(longest_edge(r.mesh), 1.75 * 6 * r.triangulation.spacing * (1 + 1e-12));
  }
  // One edge limit for the whole cloud stays the seed's L = 2 r0, however random the cloud.
  const SurfaceResult one = reconstruct_surface(sphere, global());
  EXPECT_EQ(one.triangulation.reach_factor, 1.0);
  EXPECT_EQ(one.triangulation.sampling_irregularity, 0.0);
}

TEST(UnevenSampling, ExactCopiesOfParticlesAtRandomMeshAsWithout) {
  // Every particle written three times: the copies are set aside, and the surface is the one
  // of the cloud without them (before, they filled the neighbourhoods the irregularity and the
  // local spacing are measured over: 53 pieces where the cloud alone closes).
  const PointCloud c = particlemesh::test::random_sphere(3000, 5);
  const SurfaceResult one = reconstruct_surface(c);
  const SurfaceResult three = reconstruct_surface(particlemesh::test::with_copies(c, 3));
  EXPECT_EQ(three.triangulation.duplicate_points, 2 * c.size());
  EXPECT_EQ(three.triangulation.sampling_irregularity, one.triangulation.sampling_irregularity);
  EXPECT_EQ(three.triangulation.reach_factor, 1.75);
  const TopologyReport t = topology_report(three.mesh);
  EXPECT_TRUE(t.closed && t.manifold && t.consistently_oriented && t.outward);
  EXPECT_EQ(t.components, 1u);
  // The same triangles, on the first copy of each particle.
  std::vector<Triangle> expected = one.mesh.triangles, got = three.mesh.triangles;
  for (Triangle& tri : expected)
    for (auto& v : tri) v *= 3;
  std::sort(expected.begin(), expected.end());
  std::sort(got.begin(), got.end());
  EXPECT_EQ(got, expected);
}

TEST(UnevenSampling, CrowdedPointsGetShorterLimitsInsteadOfAnError) {
  // With the spacing estimated, each particle's L is the cloud's measure, not the caller's: a
  // point whose reach holds more than max_neighbors others (a scanner's rows, a dense patch
  // beside a sparse one) gets a shorter L instead of failing the call. Particles at random
  // reach ~50 others at L = 2 x 1.75 x their spacing; a limit of 24 shortens most of them.
  const PointCloud c = particlemesh::test::random_sphere(3000, 7);
  SurfaceOptions o;
  o.max_neighbors = 24;
  const SurfaceResult r = reconstruct_surface(c, o);
  EXPECT_GT(r.triangulation.shortened_limits, c.size() / 4);
  EXPECT_LT(r.triangulation.shortened_limits, c.size());
  const TopologyReport t = topology_report(r.mesh);
  EXPECT_TRUE(t.manifold && t.consistently_oriented);
  EXPECT_GT(t.vertices_used * 10, c.size() * 9);
  // (The test stays exact for the shorter limits: NeighborLists.ShortenedRadiiHoldEveryPairWithinEither.)
  // The default limit shortens nothing here; the shortened limits show in the spread.
  const SurfaceResult plain = reconstruct_surface(c);
  EXPECT_EQ(plain.triangulation.shortened_limits, 0u);
  EXPECT_LT(r.surface.local_spacing.p10, plain.surface.local_spacing.p10 * 0.95);
  // A limit just as large as the most any point has: nothing shortened, the same surface.
  SurfaceOptions enough;
  enough.max_neighbors = plain.triangulation.max_neighbors_seen;
  const SurfaceResult same = reconstruct_surface(c, enough);
  EXPECT_EQ(same.triangulation.shortened_limits, 0u);
  EXPECT_EQ(same.mesh.triangles, plain.mesh.triangles);
  // With the spacing given (the caller's measure) or one L for all, the limit still fails.
  SurfaceOptions given = o;
  given.spacing = r.triangulation.spacing;
  EXPECT_THROW(
      {
        try {
          reconstruct_surface(c, given);
        } catch (const Error& e) {
          EXPECT_EQ(e.status(), Status::LimitExceeded);
          EXPECT_NE(std::string(e.what()).find("more than the limit of 24"), std::string::npos) << e.what();
          throw;
        }
      },
      Error);
  SurfaceOptions one = o;
  one.local_spacing = false;
  one.max_neighbors = 6;
  EXPECT_THROW(reconstruct_surface(c, one), Error);
}

namespace {

// Every particle of `c` followed, after all of them, by a near copy of every `every`-th one:
// moved by `offset` x the spacing r0 in a direction of its own (an airborne scanner's first
// and last returns off hard ground).
PointCloud with_near_copies(const PointCloud& c, double r0, double offset, size_t every) {
  PointCloud out = c;
  std::mt19937 rng(3);
  std::normal_distribution<double> g;
  for (size_t i = 0; i < c.size(); i += every) {
    const Vec3 d = normalized(Vec3{g(rng), g(rng), g(rng)});
    out.positions.push_back(c.positions[i] + d * (offset * r0));
    if (c.has_normals()) out.normals.push_back(c.normals[i]);
  }
  return out;
}

}  // namespace

TEST(UnevenSampling, NearCopiesOfMostParticlesAreSetAside) {
  // Each particle with a copy 0.02 r0 away: the median nearest-neighbour distance is the
  // copies' offset, and each particle's neighbourhood ended at its copy (nothing was meshed).
  // The copies are set aside as exact duplicates are: the surface of the particles alone.
  const PointCloud sphere = fibonacci_sphere(3000);
  const double r0 = estimate_spacing(sphere.positions.data(), sphere.size()).spacing;
  const PointCloud twinned = with_near_copies(sphere, r0, 0.02, 1);
  const SurfaceResult alone = reconstruct_surface(sphere);
  const SurfaceResult r = reconstruct_surface(twinned);
  EXPECT_EQ(r.triangulation.near_duplicates, sphere.size());
  EXPECT_EQ(r.triangulation.duplicate_points, 0u);
  EXPECT_EQ(r.triangulation.points, twinned.size());
  EXPECT_DOUBLE_EQ(r.triangulation.spacing, alone.triangulation.spacing);
  EXPECT_EQ(r.mesh.triangles, alone.mesh.triangles);
  ASSERT_EQ(r.mesh.positions.size(), twinned.size());
  ASSERT_EQ(r.mesh.normals.size(), twinned.size());
  size_t differ = 0;  // a copy faces as its first
  for (size_t i = 0; i < sphere.size(); ++i)
    differ += r.mesh.normals[i] != alone.mesh.normals[i] || r.mesh.normals[sphere.size() + i] != alone.mesh.normals[i];
  EXPECT_EQ(differ, 0u);
  const TopologyReport t = topology_report(r.mesh);
  EXPECT_TRUE(t.closed && t.manifold && t.consistently_oriented && t.outward);
  EXPECT_EQ(t.components, 1u);
  EXPECT_EQ(t.vertices_used, sphere.size());
  // Exact copies of the twinned cloud's particles stay exact duplicates.
  const PointCloud copies = particlemesh::test::with_copies(twinned, 2);
  const SurfaceResult rc = reconstruct_surface(copies);
  EXPECT_EQ(rc.triangulation.duplicate_points, twinned.size());
  EXPECT_EQ(rc.triangulation.near_duplicates, sphere.size());
  EXPECT_EQ(topology_report(rc.mesh).vertices_used, sphere.size());
  // Copies of copies, 0.0005 r0 from each of the twinned cloud's particles: merged first, and
  // the rest, still twinned, in a second round.
  const PointCloud fours = with_near_copies(twinned, r0, 0.0005, 1);
  const SurfaceResult r4 = reconstruct_surface(fours);
  EXPECT_EQ(r4.triangulation.near_duplicates, 3 * sphere.size());
  EXPECT_EQ(r4.mesh.triangles, alone.mesh.triangles);
  size_t facing_otherwise = 0;
  for (size_t i = 0; i < fours.size(); ++i) facing_otherwise += r4.mesh.normals[i] != alone.mesh.normals[i % sphere.size()];
  EXPECT_EQ(facing_otherwise, 0u);
  // With the spacing given, the same: the local spacings are measured against it.
  SurfaceOptions given;
  given.spacing = r0;
  const SurfaceResult rg = reconstruct_surface(twinned, given);
  EXPECT_EQ(rg.triangulation.near_duplicates, sphere.size());
  EXPECT_EQ(rg.mesh.triangles, reconstruct_surface(sphere, given).mesh.triangles);
}

TEST(UnevenSampling, FewNearCopiesOrOneLimitMergeNothing) {
  const PointCloud sphere = fibonacci_sphere(3000);
  const double r0 = estimate_spacing(sphere.positions.data(), sphere.size()).spacing;
  // A copy of every tenth particle: 18 % of the points are twins, under the quarter that
  // makes a cloud twinned (its median nearest-neighbour distance is still the sampling's).
  const SurfaceResult some = reconstruct_surface(with_near_copies(sphere, r0, 0.02, 10));
  EXPECT_EQ(some.triangulation.near_duplicates, 0u);
  // Particles at random: about 1 % have a neighbour ten times nearer than the next.
  const SurfaceResult random = reconstruct_surface(particlemesh::test::random_sphere(5000, 9));
  EXPECT_EQ(random.triangulation.near_duplicates, 0u);
  // One L for all (the seed's test as it is): nothing merged.
  SurfaceOptions one;
  one.local_spacing = false;
  EXPECT_EQ(reconstruct_surface(with_near_copies(sphere, r0, 0.02, 1), one).triangulation.near_duplicates, 0u);
}

TEST(UnevenSampling, EvenSamplingsKeepTheirLimits) {
  // The reach is lengthened only for particles at random: every even sampling measures far
  // below where it starts, and keeps the factor 1 exactly.
  for (const PointCloud& c : {fibonacci_sphere(10000), two_density_sphere(8000, 1500),
                              poisson_disk_sample(torus_mesh(1.0, 0.4, 96, 48), 0.05, 3),
                              row_sheet(60, 24, 1.0, 3.0, 5, true)}) {
    const SurfaceResult r = reconstruct_surface(c);
    EXPECT_EQ(r.triangulation.reach_factor, 1.0);
    EXPECT_LT(r.triangulation.sampling_irregularity, 0.25);
  }
}

TEST(UnevenSampling, RowsJoinAcross) {
  // A depth camera's rows on a surface seen at a grazing angle: 3 times farther apart across
  // than along. One L from the nearest-neighbour distance cannot reach across the rows.
  const PointCloud c = row_sheet(60, 24, 1.0, 3.0, 5, true);
  const SurfaceResult local = reconstruct_surface(c);
  const TopologyReport t = topology_report(local.mesh);
  EXPECT_TRUE(t.manifold && t.consistently_oriented);
  EXPECT_EQ(t.components, 1u);
  EXPECT_EQ(t.boundary_loops, 1u);  // the sheet's outline, no holes
  EXPECT_EQ(t.vertices_used, c.size());
  const TopologyReport g = topology_report(reconstruct_surface(c, global()).mesh);
  EXPECT_GT(g.components, 10u);
}

TEST(UnevenSampling, EvenSamplingsMeshAsWithOneSpacing) {
  // Within 15 % of r0 a particle's spacing is r0: even samplings give exactly the surface of
  // one spacing.
  for (const PointCloud& c : {fibonacci_sphere(10000), fibonacci_sphere(30000, 2.0, {1, 2, 3})}) {
    const SurfaceResult local = reconstruct_surface(c), one = reconstruct_surface(c, global());
    EXPECT_EQ(local.mesh.triangles, one.mesh.triangles);
    EXPECT_EQ(local.surface.local_spacing.median, 1.0);
  }
}

TEST(UnevenSampling, SpacingGivenScalesTheLocalSpacings) {
  // --spacing R: the local spacings keep their ratios, scaled so that the cloud's median
  // nearest-neighbour distance is R: twice the measured r0 gives twice the edge limits.
  const PointCloud c = two_density_sphere(8000, 1500);
  SurfaceOptions o;
  const SurfaceResult a = reconstruct_surface(c, o);
  o.spacing = 2 * a.triangulation.spacing;
  o.max_edge_factor = 1.0;
  const SurfaceResult b = reconstruct_surface(c, o);
  EXPECT_EQ(a.mesh.triangles, b.mesh.triangles);
  EXPECT_NEAR(b.surface.local_spacing.max, a.surface.local_spacing.max, 1e-9);
}

TEST(UnevenSampling, NoEdgeBeyondThreeTimesTheLimitOfR0) {
  // A sparse stray cluster beside a dense sheet: local spacings stop at 3 r0, and no triangle,
  // whichever stage made it, has an edge over 3 x 2 r0.
  PointCloud c = row_sheet(50, 50, 1.0, 1.0, 3, true);
  const size_t sheet = c.size();
  for (int i = 0; i < 8; ++i)
    for (int j = 0; j < 8; ++j) c.positions.push_back({80.0 + 7.0 * i, 7.0 * j, 0});
  const SurfaceResult r = reconstruct_surface(c);
  EXPECT_NEAR(r.surface.local_spacing.max, 3.0, 1e-9);
  EXPECT_LE(longest_edge(r.mesh), 6.0 * r.triangulation.spacing * (1 + 1e-12));
  // The cluster's particles (7 apart, beyond 6 r0) stay out; the sheet is whole.
  const TopologyReport t = topology_report(r.mesh);
  EXPECT_EQ(t.vertices_used, sheet);
}

TEST(UnevenSampling, OneRowOfADepthCameraIsMeshed) {
  // No plane spans any particle's neighbours (they lie along the row), so no sector reach:
  // each particle's reach is then that of the shortest non-flat triangle it makes - across a
  // step to the next run, 2-4 times its nearest-neighbour distance. The row becomes a strip
  // of triangles through every particle, within the limits.
  const PointCloud c = test::one_depth_row(300, 0.002, 0.006);
  const SurfaceResult r = reconstruct_surface(c);
  const TopologyReport t = topology_report(r.mesh);
  EXPECT_TRUE(t.manifold && t.consistently_oriented);
  EXPECT_EQ(t.nonmanifold_edges, 0u);
  EXPECT_GE(double(t.vertices_used), 0.95 * double(c.size()));
  EXPECT_LE(longest_edge(r.mesh), 6.0 * r.triangulation.spacing * (1 + 1e-12));
  // The runs' steps are longer than 2 r0: one L = 2 r0 leaves the row out.
  EXPECT_LT(double(topology_report(reconstruct_surface(c, global()).mesh).vertices_used), 0.5 * double(c.size()));
}

TEST(UnevenSampling, ViewpointTakenWhereTheParticlesLookScannedFromIt) {
  // A plate 20 in front of the origin, and behind it, 6 spacings deeper, a wall sampled on the
  // same view rays around it (a depth camera sees no wall behind the plate), meshed with a long
  // edge limit (L = 7 spacings). Seen from the origin: the viewpoint is taken, and no triangle
  // joins the plate to the wall (the rule itself: candidates_test.cpp).
  PointCloud c;
  for (int i = -12; i <= 12; ++i)
    for (int j = -12; j <= 12; ++j) {
      if (std::abs(i) <= 4 && std::abs(j) <= 4) c.positions.push_back({double(i), double(j), 20.0});
      else c.positions.push_back({i * 26.0 / 20.0, j * 26.0 / 20.0, 26.0});
    }
  SurfaceOptions o = global();
  o.spacing = 1.0;
  o.max_edge_factor = 7.0;
  auto bridges = [&](const TriMesh& m) {
    size_t n = 0;
    for (const Triangle& t : m.triangles)
      n += std::abs(m.positions[t[0]].z - m.positions[t[1]].z) + std::abs(m.positions[t[1]].z - m.positions[t[2]].z) > 1;
    return n;
  };
  const SurfaceResult blind = reconstruct_surface(c, o);
  EXPECT_FALSE(blind.surface.viewpoint_used);
  o.has_viewpoint = true;
  o.viewpoint = {0, 0, 0};
  const SurfaceResult seen = reconstruct_surface(c, o);
  EXPECT_TRUE(seen.surface.viewpoint_used);
  EXPECT_EQ(bridges(seen.mesh), 0u);
  const TopologyReport t = topology_report(seen.mesh);
  EXPECT_TRUE(t.manifold && t.consistently_oriented);
  EXPECT_EQ(t.components, 2u);  // the plate, and the wall around it
  EXPECT_EQ(t.vertices_used, c.size());
  // A viewpoint the particles were not scanned from (beside them, seeing the plate and the
  // wall edge-on) is not taken.
  o.viewpoint = {100, 0, 23};
  const SurfaceResult side = reconstruct_surface(c, o);
  EXPECT_FALSE(side.surface.viewpoint_used);
  EXPECT_EQ(side.mesh.triangles, blind.mesh.triangles);
}

TEST(UnevenSampling, RawTestKeepsOneSpacing) {
  // The raw test is the seed's exactly: one L, whatever the sampling.
  const PointCloud c = two_density_sphere(8000, 1500);
  TriangulateOptions o;
  const TriangulateResult raw = triangulate_raw(c, o);
  EXPECT_LE(longest_edge(raw.mesh), raw.stats.max_edge * (1 + 1e-12));
}

TEST(UnevenSampling, EvenModelsKeepTheirShapeAndShortEdges) {
  // Evenly sampled models: no triangle, whichever stage made it, over 3 r0; the right genus;
  // the bunny scan's five real openings stay five loops.
  PM_REQUIRE_DATA(spot, "points/spot_poisson.ply");
  PM_REQUIRE_DATA(bunny, "points/bunny_poisson.ply");
  for (const std::string& path : {spot, bunny}) {
    const PointCloud c = read_point_cloud(path);
    const SurfaceResult r = reconstruct_surface(c);
    const TopologyReport t = topology_report(r.mesh);
    EXPECT_LE(longest_edge(r.mesh), 3 * r.triangulation.spacing) << path;
    EXPECT_EQ(t.components, 1u) << path;
    EXPECT_EQ(t.per_component[0].genus, 0) << path;
    EXPECT_EQ(t.vertices_used, c.size()) << path;
    EXPECT_EQ(t.boundary_loops, path == bunny ? 5u : 0u) << path;
  }
}

// A sphere sampled in rings, six times closer along a ring than across: most local spacings
// lie past the 3 r0 cap, and the stats say where the cap cut them (the 90th percentile of the
// local spacings as estimate_local_spacing gives them, in units of r0); an even sampling's
// stay under it (0).
TEST(UnevenSampling, RowsFarApartReportTheSpacingBeforeTheCap) {
  PointCloud rings;
  for (int k = 0; k < 25; ++k) {
    const double t = (k + 0.5) / 25 * M_PI;
    const int m = std::max(6, int(std::lround(300 * std::sin(t))));
    for (int j = 0; j < m; ++j)
      rings.positions.push_back(
          {std::sin(t) * std::cos(2 * M_PI * j / m), std::sin(t) * std::sin(2 * M_PI * j / m), std::cos(t)});
  }
  const SurfaceResult r = reconstruct_surface(rings);
  const LocalSpacing ls = estimate_local_spacing(rings.positions.data(), rings.size());
  std::vector<double> v = ls.spacing;
  std::nth_element(v.begin(), v.begin() + ptrdiff_t(v.size() * 9 / 10), v.end());
  const double expected = v[v.size() * 9 / 10] / ls.median_nn;
  ASSERT_GT(expected, 3.5);
  EXPECT_DOUBLE_EQ(r.triangulation.uncapped_spacing_p90, expected);
  EXPECT_EQ(reconstruct_surface(fibonacci_sphere(5000)).triangulation.uncapped_spacing_p90, 0.0);
}
