#include "particlemesh/mesh/topology_report.h"

#include <gtest/gtest.h>
#include <tbb/task_arena.h>

#include <array>
#include <cmath>
#include <cstring>
#include <numeric>
#include <random>
#include <string>

#include "particlemesh/sample/shapes.h"
#include "particlemesh/smooth/subdivide.h"
#include "support/test_support.h"
#include "topology_report_reference.h"

using namespace particlemesh;

namespace {
TriMesh tetrahedron() {
  TriMesh m;
  m.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  m.triangles = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};  // outward
  return m;
}
}  // namespace

TEST(TopologyReport, ClosedOutwardTetrahedron) {
  const TopologyReport r = topology_report(tetrahedron());
  EXPECT_EQ(r.edges, 6u);
  EXPECT_EQ(r.manifold_edges, 6u);
  EXPECT_EQ(r.euler_characteristic, 2);
  EXPECT_TRUE(r.closed);
  EXPECT_TRUE(r.manifold);
  EXPECT_TRUE(r.consistently_oriented);
  EXPECT_TRUE(r.outward);
  ASSERT_EQ(r.per_component.size(), 1u);
  EXPECT_EQ(r.per_component[0].genus, 0);
  EXPECT_NEAR(r.per_component[0].signed_volume, 1.0 / 6.0, 1e-12);
}

TEST(TopologyReport, InwardAndInconsistentWindingsAreSeen) {
  TriMesh m = tetrahedron();
  for (auto& t : m.triangles) std::swap(t[1], t[2]);
  TopologyReport r = topology_report(m);
  EXPECT_TRUE(r.consistently_oriented);
  EXPECT_FALSE(r.outward);
  EXPECT_LT(r.per_component[0].signed_volume, 0);
  std::swap(m.triangles[0][1], m.triangles[0][2]);  // flip one face back
  r = topology_report(m);
  EXPECT_FALSE(r.consistently_oriented);
  EXPECT_EQ(r.orientation_conflicts, 3u);
}

namespace {
// `part` appended to `m`, scaled and moved, its winding reversed if `inward`.
void append(TriMesh& m, const TriMesh& part, double scale, Vec3 offset, bool inward) {
  const uint32_t base = uint32_t(m.positions.size());
  for (const Vec3& p : part.positions) m.positions.push_back(p * scale + offset);
  for (Triangle t : part.triangles) {
    if (inward) std::swap(t[1], t[2]);
    m.triangles.push_back({t[0] + base, t[1] + base, t[2] + base});
  }
}

// An axis-aligned box whose six faces are fans of four triangles around their centres, wound
// outward; its first triangle's first corner is the top face's centre, (c.x, c.y, c.z + h).
TriMesh fan_box(Vec3 c, double h) {
  TriMesh m;
  const int axes[6][3] = {{2, 0, 1}, {2, 1, 0}, {0, 1, 2}, {0, 2, 1}, {1, 2, 0}, {1, 0, 2}};  // normal, u, v
  for (int f = 0; f < 6; ++f) {
    const int n = axes[f][0], u = axes[f][1], v = axes[f][2];
    const double side = f % 2 == 0 ? 1.0 : -1.0;
    auto at = [&](double a, double b) {
      double q[3];
      q[n] = side * h, q[u] = a * h, q[v] = b * h;
      return c + Vec3{q[0], q[1], q[2]};
    };
    const uint32_t centre = uint32_t(m.positions.size());
    m.positions.push_back(at(0, 0));
    const double corner[4][2] = {{1, 1}, {-1, 1}, {-1, -1}, {1, -1}};
    for (const auto& k : corner) m.positions.push_back(at(k[0], k[1]));
    for (uint32_t k = 0; k < 4; ++k) m.triangles.push_back({centre, centre + 1 + k, centre + 1 + (k + 1) % 4});
  }
  // Faces do not share their corner vertices here: weld them, and wind each face outward.
  std::vector<uint32_t> id(m.positions.size());
  TriMesh w;
  for (size_t i = 0; i < m.positions.size(); ++i) {
    size_t j = 0;
    while (j < w.positions.size() && !(w.positions[j] == m.positions[i])) ++j;
    if (j == w.positions.size()) w.positions.push_back(m.positions[i]);
    id[i] = uint32_t(j);
  }
  for (const Triangle& t : m.triangles) {
    Triangle u{id[t[0]], id[t[1]], id[t[2]]};
    const Vec3 a = w.positions[u[0]], b = w.positions[u[1]], d = w.positions[u[2]];
    if (dot(cross(b - a, d - a), a - c) < 0) std::swap(u[1], u[2]);
    w.triangles.push_back(u);
  }
  return w;
}
}  // namespace

// A closed piece inside another bounds a cavity and faces into it; one inside that is a solid
// again: "outward" follows the nesting (a hollow ball with a marble in it), whatever the order
// of the pieces, and pieces side by side are each at depth 0.
TEST(TopologyReport, CavityWallsFaceIntoTheirCavities) {
  const TriMesh ball = icosphere_mesh(3);
  TriMesh m;
  append(m, ball, 0.3, {0.1, 0, 0}, false);  // the marble
  append(m, ball, 1.0, {}, false);           // the ball's outside
  append(m, ball, 0.8, {}, true);            // the cavity's wall, facing into it
  TopologyReport r = topology_report(m);
  ASSERT_EQ(r.closed_components, 3u);
  EXPECT_TRUE(r.outward);
  for (const ComponentReport& c : r.per_component) {
    const uint32_t expected = c.signed_volume > 4.0 ? 0 : c.signed_volume < 0 ? 1 : 2;
    EXPECT_EQ(c.nesting_depth, expected) << c.signed_volume;
  }
  TriMesh wrong;  // the cavity's wall facing into the solid
  append(wrong, ball, 1.0, {}, false);
  append(wrong, ball, 0.8, {}, false);
  EXPECT_FALSE(topology_report(wrong).outward);
  TriMesh apart;
  append(apart, ball, 1.0, {}, false);
  append(apart, ball, 1.0, {2.5, 0, 0}, false);
  append(apart, ball, 0.2, {5.0, 0.5, 0}, false);
  r = topology_report(apart);
  EXPECT_TRUE(r.outward);
  for (const ComponentReport& c : r.per_component) EXPECT_EQ(c.nesting_depth, 0u);
}

// The inside test counts a crossing once where the ray goes exactly through a vertex shared
// by four triangles or along an edge between two (a box's fans, axis-aligned): the inner box's
// test point lies straight below the outer box's top centre, then below one of its diagonals.
TEST(TopologyReport, NestingThroughVerticesAndEdgesOfTheOuterPiece) {
  for (const Vec3 inner : {Vec3{0, 0, 0}, Vec3{0.25, 0.25, 0}, Vec3{-0.25, 0.25, -0.3}, Vec3{0.3, 0, 0.2}}) {
    TriMesh m;
    append(m, fan_box(inner, 0.2), 1.0, {}, true);  // a cavity, facing into it
    append(m, fan_box({}, 1.0), 1.0, {}, false);
    ASSERT_EQ(m.positions[m.triangles[0][0]], (inner + Vec3{0, 0, 0.2}));
    const TopologyReport r = topology_report(m);
    ASSERT_EQ(r.closed_components, 2u) << inner.x;
    EXPECT_TRUE(r.outward) << inner.x << " " << inner.y;
    for (const ComponentReport& c : r.per_component)
      EXPECT_EQ(c.nesting_depth, c.signed_volume < 0 ? 1u : 0u) << inner.x << " " << inner.y;
  }
}

TEST(TopologyReport, TorusHasGenusOneAndIcosphereGenusZero) {
  const TopologyReport t = topology_report(torus_mesh(1, 0.3, 24, 12));
  EXPECT_EQ(t.euler_characteristic, 0);
  EXPECT_TRUE(t.closed);
  EXPECT_EQ(t.per_component[0].genus, 1);
  EXPECT_TRUE(t.outward);
  const TopologyReport s = topology_report(icosphere_mesh(3));
  EXPECT_EQ(s.euler_characteristic, 2);
  EXPECT_TRUE(s.closed && s.outward);
  EXPECT_EQ(s.triangles, 20u * 64u);
}

TEST(TopologyReport, OpenDiskHasOneBoundaryLoop) {
  TriMesh m;
  m.positions = {{0, 0, 0}};
  for (int i = 0; i < 6; ++i) m.positions.push_back({std::cos(i * 1.047), std::sin(i * 1.047), 0});
  for (uint32_t i = 0; i < 6; ++i) m.triangles.push_back({0, 1 + i, 1 + (i + 1) % 6});
  const TopologyReport r = topology_report(m);
  EXPECT_EQ(r.boundary_edges, 6u);
  EXPECT_EQ(r.boundary_loops, 1u);
  EXPECT_EQ(r.euler_characteristic, 1);
  EXPECT_TRUE(r.manifold);
  EXPECT_FALSE(r.closed);
  EXPECT_EQ(r.per_component[0].genus, 0);
}

TEST(TopologyReport, PinchedVertexAndFinAreNonManifold) {
  // Two triangles that share only vertex 0: a pinch. The boundary is traced as two loops.
  TriMesh pinch;
  pinch.positions = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {-1, 0, 0}, {-1, -1, 0}};
  pinch.triangles = {{0, 1, 2}, {0, 3, 4}};
  TopologyReport r = topology_report(pinch);
  EXPECT_EQ(r.nonmanifold_vertices, 1u);
  EXPECT_FALSE(r.manifold);
  EXPECT_EQ(r.components, 2u);
  EXPECT_EQ(r.boundary_loops, 2u);
  // Three triangles on one edge: a fin.
  TriMesh fin;
  fin.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}};
  fin.triangles = {{0, 1, 2}, {1, 0, 3}, {0, 1, 4}};
  r = topology_report(fin);
  EXPECT_EQ(r.nonmanifold_edges, 1u);
  EXPECT_FALSE(r.consistently_oriented);
  EXPECT_EQ(r.components, 1u);
}

TEST(TopologyReport, DegenerateDuplicateAndUnusedAreCounted) {
  TriMesh m = tetrahedron();
  m.positions.push_back({5, 5, 5});         // unused
  m.triangles.push_back({0, 1, 2});         // duplicate of {0, 2, 1} as a vertex set
  m.triangles.push_back({1, 1, 2});         // repeated index
  const TopologyReport r = topology_report(m);
  EXPECT_EQ(r.vertices, 5u);
  EXPECT_EQ(r.vertices_used, 4u);
  EXPECT_EQ(r.duplicate_triangles, 1u);
  EXPECT_EQ(r.degenerate_triangles, 1u);
}

namespace {
// An n x n grid of unit squares, two triangles each, consistently wound, without the squares
// of the given k x k blocks (lower-left square i, j): one hole of 4 k edges per block.
TriMesh grid_with_holes(uint32_t n, const std::vector<std::array<uint32_t, 3>>& blocks, Vec3 offset = {}) {
  TriMesh m;
  for (uint32_t j = 0; j <= n; ++j)
    for (uint32_t i = 0; i <= n; ++i) m.positions.push_back(offset + Vec3{double(i), double(j), 0});
  for (uint32_t j = 0; j < n; ++j)
    for (uint32_t i = 0; i < n; ++i) {
      bool cut = false;
      for (const auto& b : blocks) cut |= i >= b[0] && i < b[0] + b[2] && j >= b[1] && j < b[1] + b[2];
      if (cut) continue;
      const uint32_t a = j * (n + 1) + i, b = a + 1, c = a + n + 2, d = a + n + 1;
      m.triangles.push_back({a, b, c});
      m.triangles.push_back({a, c, d});
    }
  return m;
}
}  // namespace

TEST(TopologyReport, BoundaryLoopSizesComeSmallestFirst) {
  // Holes of 4, 8 and 12 edges and the grid's rim of 4 x 12.
  TriMesh m = grid_with_holes(12, {{2, 2, 3}, {8, 8, 1}, {7, 2, 2}});
  TopologyReport r = topology_report(m);
  EXPECT_TRUE(r.consistently_oriented);
  EXPECT_EQ(r.boundary_loops, 4u);
  EXPECT_EQ(r.boundary_loop_edges, (std::vector<size_t>{4, 8, 12, 48}));
  EXPECT_EQ(r.per_component[0].genus, 0);
  // One triangle flipped: the loops are no longer traced around fans but taken as the
  // connected pieces of the boundary-edge graph, the same four here.
  std::swap(m.triangles[0][1], m.triangles[0][2]);
  r = topology_report(m);
  EXPECT_FALSE(r.consistently_oriented);
  EXPECT_EQ(r.boundary_loop_edges, (std::vector<size_t>{4, 8, 12, 48}));
  // Two holes touching at a corner: traced around the fans, the walk crosses at the shared
  // vertex (a figure eight), one loop of 8.
  m = grid_with_holes(6, {{1, 1, 1}, {2, 2, 1}});
  EXPECT_EQ(topology_report(m).boundary_loop_edges, (std::vector<size_t>{8, 24}));
  // Two triangles sharing one vertex: two traced loops of 3; with an inconsistently wound
  // pair elsewhere, one piece of 6 edges of the boundary graph (and the pair's 4).
  TriMesh pinch;
  pinch.positions = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {-1, 0, 0}, {-1, -1, 0}};
  pinch.triangles = {{0, 1, 2}, {0, 3, 4}};
  EXPECT_EQ(topology_report(pinch).boundary_loop_edges, (std::vector<size_t>{3, 3}));
  for (const Vec3& p : {Vec3{5, 0, 0}, Vec3{6, 0, 0}, Vec3{5, 1, 0}, Vec3{5, -1, 0}}) pinch.positions.push_back(p);
  pinch.triangles.push_back({5, 6, 7});
  pinch.triangles.push_back({5, 6, 8});
  r = topology_report(pinch);
  EXPECT_FALSE(r.consistently_oriented);
  EXPECT_EQ(r.boundary_loop_edges, (std::vector<size_t>{4, 6}));
  // A closed surface has none.
  EXPECT_TRUE(topology_report(torus_mesh(1, 0.3, 24, 12)).boundary_loop_edges.empty());
}

TEST(TopologyReport, EmptyMesh) {
  const TopologyReport r = topology_report(TriMesh{});
  EXPECT_EQ(r.triangles, 0u);
  EXPECT_EQ(r.components, 0u);
  EXPECT_FALSE(r.closed);
}

// ---- the parallel report against the serial reference it replaced -----------------------

namespace {

void expect_same_report(const TopologyReport& a, const TopologyReport& b, const std::string& what) {
  SCOPED_TRACE(what);
  EXPECT_EQ(a.vertices, b.vertices);
  EXPECT_EQ(a.triangles, b.triangles);
  EXPECT_EQ(a.vertices_used, b.vertices_used);
  EXPECT_EQ(a.edges, b.edges);
  EXPECT_EQ(a.boundary_edges, b.boundary_edges);
  EXPECT_EQ(a.manifold_edges, b.manifold_edges);
  EXPECT_EQ(a.nonmanifold_edges, b.nonmanifold_edges);
  EXPECT_EQ(a.nonmanifold_vertices, b.nonmanifold_vertices);
  EXPECT_EQ(a.degenerate_triangles, b.degenerate_triangles);
  EXPECT_EQ(a.duplicate_triangles, b.duplicate_triangles);
  EXPECT_EQ(a.orientation_conflicts, b.orientation_conflicts);
  EXPECT_EQ(a.boundary_loops, b.boundary_loops);
  EXPECT_EQ(a.components, b.components);
  EXPECT_EQ(a.closed_components, b.closed_components);
  EXPECT_EQ(a.euler_characteristic, b.euler_characteristic);
  EXPECT_EQ(a.manifold, b.manifold);
  EXPECT_EQ(a.closed, b.closed);
  EXPECT_EQ(a.consistently_oriented, b.consistently_oriented);
  EXPECT_EQ(a.outward, b.outward);
  EXPECT_EQ(a.boundary_loop_edges, b.boundary_loop_edges);
  ASSERT_EQ(a.per_component.size(), b.per_component.size());
  for (size_t i = 0; i < a.per_component.size(); ++i) {
    const ComponentReport &x = a.per_component[i], &y = b.per_component[i];
    SCOPED_TRACE("component " + std::to_string(i));
    EXPECT_EQ(x.triangles, y.triangles);
    EXPECT_EQ(x.vertices, y.vertices);
    EXPECT_EQ(x.edges, y.edges);
    EXPECT_EQ(x.boundary_edges, y.boundary_edges);
    EXPECT_EQ(x.nonmanifold_edges, y.nonmanifold_edges);
    EXPECT_EQ(x.boundary_loops, y.boundary_loops);
    EXPECT_EQ(x.euler_characteristic, y.euler_characteristic);
    EXPECT_EQ(x.closed, y.closed);
    EXPECT_EQ(x.manifold, y.manifold);
    EXPECT_EQ(x.consistently_oriented, y.consistently_oriented);
    EXPECT_EQ(x.genus, y.genus);
    // Summed in the same (triangle) order: the same bits.
    EXPECT_EQ(std::memcmp(&x.signed_volume, &y.signed_volume, sizeof(double)), 0)
        << x.signed_volume << " vs " << y.signed_volume;
  }
}

// A messy mesh: pieces of a torus and an icosphere (some triangles flipped, some dropped,
// some repeated, some with a repeated corner), a few random triangles over the same vertices
// (fins, pinches), unused vertices, in a shuffled order.
TriMesh messy_mesh(uint64_t seed) {
  std::mt19937_64 rng(seed);
  TriMesh a = torus_mesh(1, 0.3, 40, 16), b = icosphere_mesh(3, 0.5);
  TriMesh m = a;
  const uint32_t offset = uint32_t(m.positions.size());
  for (const Vec3& p : b.positions) m.positions.push_back(p + Vec3{3, 0, 0});
  for (Triangle t : b.triangles) m.triangles.push_back({t[0] + offset, t[1] + offset, t[2] + offset});
  for (int i = 0; i < 7; ++i) m.positions.push_back({9.0 + i, 0, 0});  // unused
  const uint32_t nv = uint32_t(m.positions.size());
  std::vector<Triangle> out;
  for (Triangle t : m.triangles) {
    const uint64_t x = rng() % 100;
    if (x < 3) continue;                           // a hole
    if (x < 6) std::swap(t[1], t[2]);              // a flipped triangle
    out.push_back(t);
    if (x == 6) out.push_back(t);                  // a duplicate
    if (x == 7) out.push_back({t[0], t[0], t[1]}); // a repeated corner
  }
  for (int i = 0; i < 20; ++i) out.push_back({uint32_t(rng() % nv), uint32_t(rng() % nv), uint32_t(rng() % nv)});
  std::shuffle(out.begin(), out.end(), rng);
  m.triangles = out;
  return m;
}

}  // namespace

TEST(TopologyReport, AgreesWithTheSerialReferenceForAnyThreadCount) {
  std::vector<std::pair<std::string, TriMesh>> meshes;
  meshes.push_back({"tetrahedron", tetrahedron()});
  meshes.push_back({"torus", torus_mesh(1, 0.3, 60, 20)});
  meshes.push_back({"icosphere", icosphere_mesh(5)});
  TriMesh open = icosphere_mesh(4);
  open.triangles.resize(open.triangles.size() * 2 / 3);  // an open cap, one boundary loop
  meshes.push_back({"open cap", open});
  for (uint64_t seed = 1; seed <= 6; ++seed) meshes.push_back({"messy " + std::to_string(seed), messy_mesh(seed)});
  TriMesh pinched = tetrahedron();  // two tetrahedra sharing a vertex, one open
  pinched.positions.push_back({-1, 0, 0});
  pinched.positions.push_back({0, -1, 0});
  pinched.positions.push_back({0, 0, -1});
  pinched.triangles.push_back({0, 4, 5});
  pinched.triangles.push_back({0, 5, 6});
  meshes.push_back({"pinched", pinched});
  TriMesh soup;  // random triangles over few vertices: many fins and duplicates
  std::mt19937_64 rng(11);
  for (int i = 0; i < 30; ++i) soup.positions.push_back({double(rng() % 7), double(rng() % 5), double(rng() % 3)});
  for (int i = 0; i < 400; ++i) soup.triangles.push_back({uint32_t(rng() % 30), uint32_t(rng() % 30), uint32_t(rng() % 30)});
  meshes.push_back({"soup", soup});
  meshes.push_back({"empty", TriMesh{}});
  // Loops of several sizes over several components, traced (consistent winding) and as
  // pieces of the boundary graph (a flipped triangle, a fin), two holes meeting at a corner.
  TriMesh holes = grid_with_holes(30, {{2, 2, 1}, {5, 5, 2}, {10, 3, 5}, {20, 20, 3}, {3, 3, 1}});
  const TriMesh second = grid_with_holes(9, {{1, 1, 1}, {4, 4, 4}}, Vec3{40, 0, 0});
  for (const Triangle& t : second.triangles) {
    const uint32_t o = uint32_t(holes.positions.size());
    holes.triangles.push_back({t[0] + o, t[1] + o, t[2] + o});
  }
  holes.positions.insert(holes.positions.end(), second.positions.begin(), second.positions.end());
  meshes.push_back({"holes", holes});
  TriMesh flipped = holes;
  std::swap(flipped.triangles[7][1], flipped.triangles[7][2]);
  meshes.push_back({"holes, one triangle flipped", flipped});
  TriMesh finned = holes;
  finned.positions.push_back({0.5, 0.5, 1});
  finned.triangles.push_back({finned.triangles[0][0], finned.triangles[0][1], uint32_t(finned.positions.size() - 1)});
  meshes.push_back({"holes and a fin", finned});
  TriMesh shuffled = holes;
  std::shuffle(shuffled.triangles.begin(), shuffled.triangles.end(), rng);
  meshes.push_back({"holes, triangles shuffled", shuffled});
  // Closed meshes with one flaw each, where most vertices are closed, consistently oriented
  // fans (the report's common case) and a few must fall back to the general pass: a flipped
  // triangle, a repeated triangle, a repeated triangle reversed, a triangle with a corner
  // repeated, two closed fans meeting at one vertex (a figure eight: both cones share the
  // apex), and a vertex of more corners than the fast test takes.
  const TriMesh sphere = icosphere_mesh(3);
  TriMesh flip = sphere;
  std::swap(flip.triangles[5][1], flip.triangles[5][2]);
  meshes.push_back({"icosphere, one triangle flipped", flip});
  TriMesh twice = sphere;
  twice.triangles.push_back(twice.triangles[9]);
  meshes.push_back({"icosphere, one triangle twice", twice});
  TriMesh reversed = sphere;
  reversed.triangles.push_back({sphere.triangles[9][0], sphere.triangles[9][2], sphere.triangles[9][1]});
  meshes.push_back({"icosphere, one triangle twice, reversed", reversed});
  TriMesh repeated = sphere;
  repeated.triangles[3] = {repeated.triangles[3][0], repeated.triangles[3][0], repeated.triangles[3][1]};
  meshes.push_back({"icosphere, one corner repeated", repeated});
  auto cone = [](TriMesh& m, uint32_t apex, int sides, double z) {
    const uint32_t ring = uint32_t(m.positions.size());
    for (int i = 0; i < sides; ++i)
      m.positions.push_back({std::cos(6.283185307179586 * i / sides), std::sin(6.283185307179586 * i / sides), z});
    m.positions.push_back({0, 0, 2 * z});  // the cap's centre
    const uint32_t cap = uint32_t(m.positions.size() - 1);
    for (int i = 0; i < sides; ++i) {
      const uint32_t a = ring + uint32_t(i), b = ring + uint32_t((i + 1) % sides);
      m.triangles.push_back(z > 0 ? Triangle{apex, a, b} : Triangle{apex, b, a});
      m.triangles.push_back(z > 0 ? Triangle{cap, b, a} : Triangle{cap, a, b});
    }
  };
  TriMesh eight;  // two closed double cones sharing their apex: a pinched vertex of two disks
  eight.positions.push_back({0, 0, 0});
  cone(eight, 0, 5, 1);
  cone(eight, 0, 7, -1);
  meshes.push_back({"figure eight at a vertex", eight});
  TriMesh wide;  // one closed cone of 40 sides: its apex and cap centre have 40 corners
  wide.positions.push_back({0, 0, 0});
  cone(wide, 0, 40, 1);
  meshes.push_back({"wide cone", wide});
  // Manifold at every vertex (the report then joins components over vertices): closed and
  // open pieces of equal triangle counts (their order in the report is their numbering, by
  // lowest triangle), vertices renumbered at random and triangles shuffled, so that a
  // component's lowest vertex is not in its lowest triangle.
  TriMesh pieces;
  for (int i = 0; i < 6; ++i) {
    TriMesh piece = icosphere_mesh(2, 0.5 + 0.1 * i);
    if (i % 3 == 2) piece.triangles.resize(piece.triangles.size() - 1);  // open: one boundary loop
    const uint32_t o = uint32_t(pieces.positions.size());
    for (const Vec3& p : piece.positions) pieces.positions.push_back(p + Vec3{3.0 * i, 0, 0});
    for (const Triangle& t : piece.triangles) pieces.triangles.push_back({t[0] + o, t[1] + o, t[2] + o});
  }
  TriMesh torus_piece = torus_mesh(1, 0.3, 10, 8);
  for (const Triangle& t : torus_piece.triangles) {
    const uint32_t o = uint32_t(pieces.positions.size());
    pieces.triangles.push_back({t[0] + o, t[1] + o, t[2] + o});
  }
  for (const Vec3& p : torus_piece.positions) pieces.positions.push_back(p + Vec3{0, 5, 0});
  {
    std::vector<uint32_t> renumber(pieces.positions.size());
    std::iota(renumber.begin(), renumber.end(), 0u);
    std::shuffle(renumber.begin(), renumber.end(), rng);
    std::vector<Vec3> moved(pieces.positions.size());
    for (size_t v = 0; v < moved.size(); ++v) moved[renumber[v]] = pieces.positions[v];
    pieces.positions = moved;
    for (Triangle& t : pieces.triangles)
      for (uint32_t& v : t) v = renumber[v];
    std::shuffle(pieces.triangles.begin(), pieces.triangles.end(), rng);
  }
  meshes.push_back({"manifold pieces, renumbered and shuffled", pieces});
  for (const auto& named : meshes) {
    const std::string& name = named.first;
    const TriMesh& m = named.second;  // not a structured binding: clang 14 cannot capture one
    const TopologyReport want = reference::topology_report(m);
    if (name.rfind("holes", 0) == 0) {
      EXPECT_GE(want.boundary_loop_edges.size(), 7u) << name;  // not vacuous
    }
    if (name.rfind("manifold pieces", 0) == 0) {  // not vacuous: many pieces, each vertex a fan
      EXPECT_EQ(want.components, 7u);
      EXPECT_EQ(want.nonmanifold_vertices, 0u);
      EXPECT_EQ(want.boundary_loops, 2u);
    }
    // Every thread count this machine has (more would only idle in the arena).
    std::vector<int> counts{1};
    for (int t = 2; t <= tbb::this_task_arena::max_concurrency(); t = t < 4 ? t + 1 : 2 * t) counts.push_back(t);
    if (counts.back() != tbb::this_task_arena::max_concurrency()) counts.push_back(tbb::this_task_arena::max_concurrency());
    for (int threads : counts) {
      tbb::task_arena arena(threads);
      const TopologyReport got = arena.execute([&] { return topology_report(m); });
      expect_same_report(got, want, name + ", " + std::to_string(threads) + " threads");
    }
  }
}

// The report of a Loop result derived from its control mesh's (what `particlemesh smooth`
// prints) is the full report of the result, bit for bit, wherever it is given; and it is not
// given where the control mesh is not one clean closed piece.
TEST(TopologyReport, SubdividedReportIsTheFullReportOfTheLoopResult) {
  TriMesh inward = icosphere_mesh(2);
  for (auto& t : inward.triangles) std::swap(t[1], t[2]);
  TriMesh collapsed = tetrahedron();  // every vertex at one point: every refined triangle has zero area
  for (auto& p : collapsed.positions) p = {0.5, 0.5, 0.5};
  struct Case {
    std::string name;
    TriMesh mesh;
    int levels;
    bool limit;
    std::vector<CreaseEdge> creases;
  };
  const TriMesh torus = torus_mesh(1, 0.3, 24, 12);
  const std::vector<Case> cases{
      {"icosphere, level 0", icosphere_mesh(1), 0, true, {}},
      {"icosphere, level 1", icosphere_mesh(1), 1, true, {}},
      {"icosphere, level 3", icosphere_mesh(1), 3, true, {}},
      {"torus, level 2", torus, 2, true, {}},
      {"torus, level 2, no limit", torus, 2, false, {}},
      {"torus, level 2, a crease", torus, 2, true, {{torus.triangles[0][0], torus.triangles[0][1]}}},
      {"icosphere wound inward, level 2", inward, 2, true, {}},
      {"tetrahedron collapsed to a point, level 1, no limit", collapsed, 1, false, {}},
  };
  for (const Case& c : cases) {
    SmoothOptions opt;
    opt.levels = c.levels;
    opt.limit = c.limit;
    opt.creases = c.creases;
    const TriMesh out = smooth_mesh(c.mesh, opt).mesh;
    const std::optional<TopologyReport> got = subdivided_topology_report(topology_report(c.mesh), out, c.levels);
    ASSERT_TRUE(got.has_value()) << c.name;
    const TopologyReport want = topology_report(out);
    expect_same_report(*got, want, c.name);
    if (c.name.rfind("tetrahedron", 0) == 0) {  // not vacuous: zero areas and no volume
      EXPECT_EQ(want.degenerate_triangles, want.triangles);
      EXPECT_FALSE(want.outward);
    }
    if (c.name.rfind("torus", 0) == 0) {
      EXPECT_EQ(want.per_component[0].genus, 1);
    }
    // Counts that are not those of `levels` splits: not a subdivision of this control mesh.
    EXPECT_FALSE(subdivided_topology_report(topology_report(c.mesh), out, c.levels + 1).has_value()) << c.name;
  }

  // Control meshes whose refinement the report is not derived for.
  auto not_derived = [](const TriMesh& control, const std::string& name) {
    SCOPED_TRACE(name);
    SmoothOptions opt;
    opt.levels = 1;
    const TriMesh out = smooth_mesh(control, opt).mesh;
    EXPECT_FALSE(subdivided_topology_report(topology_report(control), out, 1).has_value());
  };
  TriMesh two = icosphere_mesh(1);
  const uint32_t n = uint32_t(two.positions.size());
  for (uint32_t i = 0; i < n; ++i) two.positions.push_back(two.positions[i] + Vec3{3, 0, 0});
  for (size_t f = 0, nf = two.triangles.size(); f < nf; ++f)
    two.triangles.push_back({two.triangles[f][0] + n, two.triangles[f][1] + n, two.triangles[f][2] + n});
  not_derived(two, "two components");
  TriMesh open = icosphere_mesh(1);
  open.triangles.pop_back();
  not_derived(open, "a hole");
  TriMesh unused = icosphere_mesh(1);
  unused.positions.push_back({5, 5, 5});
  not_derived(unused, "an unused vertex");
  TriMesh flipped = icosphere_mesh(1);
  std::swap(flipped.triangles[3][1], flipped.triangles[3][2]);
  not_derived(flipped, "one triangle wound against its neighbours");

  // An index out of range in the refined triangles: the full report's business.
  TriMesh bad = smooth_mesh(icosphere_mesh(1), SmoothOptions{}).mesh;
  bad.triangles.back()[2] = uint32_t(bad.positions.size());
  EXPECT_FALSE(subdivided_topology_report(topology_report(icosphere_mesh(1)), bad, 1).has_value());
}
