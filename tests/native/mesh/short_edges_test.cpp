// Short edges collapsed (mesh/short_edges.h): only where the surface stays a closed, oriented
// 2-manifold; and as polygonize's collapse_edges, marching cubes' slivers gone with the
// surface's topology, its vertices on the field's surface and its normals the field's.
#include "mesh/short_edges.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <random>

#include "particlemesh/core/error.h"
#include "particlemesh/mesh/topology_report.h"
#include "particlemesh/sample/shapes.h"
#include "particlemesh/volume/field.h"
#include "particlemesh/volume/polygonize.h"
#include "particlemesh/volume/polygonize_attributes.h"

using namespace particlemesh;
using detail::collapse_short_edges;

namespace {

Vec3 midpoint(const Vec3& a, const Vec3& b) { return (a + b) * 0.5; }

bool closed_oriented(const TriMesh& m) {
  const TopologyReport r = topology_report(m);
  return r.closed && r.manifold && r.consistently_oriented && r.outward && r.degenerate_triangles == 0 &&
         r.duplicate_triangles == 0;
}

// The smallest angle of each triangle, degrees.
std::vector<double> smallest_angles(const TriMesh& m) {
  std::vector<double> out;
  for (const Triangle& t : m.triangles) {
    double least = 180;
    for (int k = 0; k < 3; ++k) {
      const Vec3 p = m.positions[t[k]], u = m.positions[t[(k + 1) % 3]] - p, w = m.positions[t[(k + 2) % 3]] - p;
      least = std::min(least, std::acos(std::clamp(dot(u, w) / (norm(u) * norm(w)), -1.0, 1.0)) * 180 / std::numbers::pi);
    }
    out.push_back(least);
  }
  return out;
}

double share_below(const std::vector<double>& a, double x) {
  return double(std::count_if(a.begin(), a.end(), [&](double v) { return v < x; })) / double(a.size());
}

// A vertex of an icosphere pulled next to its neighbour: that one edge is short.
TriMesh sphere_with_a_short_edge(uint32_t* a, uint32_t* b) {
  TriMesh m = icosphere_mesh(3, 1.0);
  const Triangle t = m.triangles[17];
  *a = std::min(t[0], t[1]);
  *b = std::max(t[0], t[1]);
  m.positions[*b] = normalized(m.positions[*a] * 0.98 + m.positions[*b] * 0.02);
  m.normals.assign(m.positions.begin(), m.positions.end());
  return m;
}

}  // namespace

TEST(ShortEdges, TheShortEdgeOfAClosedSurfaceBecomesOneVertex) {
  uint32_t a, b;
  TriMesh m = sphere_with_a_short_edge(&a, &b);
  m.attributes.push_back({"heat", 1, std::vector<float>(m.positions.size(), 1.0f)});
  m.attributes[0].values[b] = 3.0f;
  const TriMesh before = m;
  const double shortest = norm(m.positions[a] - m.positions[b]);
  const detail::ShortEdgeCollapse c = collapse_short_edges(m, 2 * shortest, 0.5, midpoint);
  ASSERT_EQ(c.collapsed, 1u);
  EXPECT_EQ(m.positions.size(), before.positions.size() - 1);
  EXPECT_EQ(m.triangles.size(), before.triangles.size() - 2);
  EXPECT_TRUE(closed_oriented(m));
  EXPECT_EQ(topology_report(m).euler_characteristic, 2);
  // The earlier vertex took the place, at the midpoint; the later one is gone, the rest
  // shifted down by one past it; normals and attributes follow.
  ASSERT_EQ(c.moved, std::vector<uint32_t>{a});
  EXPECT_EQ(m.positions[a], midpoint(before.positions[a], before.positions[b]));
  EXPECT_NEAR(norm(m.normals[a]), 1.0, 1e-15);
  EXPECT_FLOAT_EQ(m.attributes[0].values[a], 2.0f);
  ASSERT_EQ(m.attributes[0].values.size(), m.positions.size());
  EXPECT_EQ(m.positions[b], before.positions[b + 1]);
  // Nothing shorter than the limit: nothing changes.
  TriMesh same = before;
  EXPECT_EQ(collapse_short_edges(same, 0.5 * shortest, 0.5, midpoint).collapsed, 0u);
  EXPECT_EQ(same.positions, before.positions);
  EXPECT_EQ(same.triangles, before.triangles);
}

TEST(ShortEdges, NoCollapseThatWouldPinchFoldOrFlattenTheSurface) {
  // A tetrahedron: collapsing any edge leaves two triangles back to back.
  TriMesh tet;
  tet.positions = {{0, 0, 0}, {0.01, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  tet.triangles = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};
  ASSERT_TRUE(closed_oriented(tet));
  EXPECT_EQ(collapse_short_edges(tet, 0.1, 0.5, midpoint).collapsed, 0u);
  // A triangular bipyramid whose equator edge a-b is short: a and b share the third equator
  // vertex besides the two poles (the link condition fails: the collapse would pinch).
  TriMesh bi;
  bi.positions = {{0, 0, 0}, {0.02, 0, 0}, {0.01, 1, 0}, {0.01, 0.3, 1}, {0.01, 0.3, -1}};
  bi.triangles = {{0, 1, 3}, {1, 2, 3}, {2, 0, 3}, {1, 0, 4}, {2, 1, 4}, {0, 2, 4}};
  ASSERT_TRUE(closed_oriented(bi));
  EXPECT_EQ(collapse_short_edges(bi, 0.1, 0.5, midpoint).collapsed, 0u);
  // Two octahedra glued along a face (a, b, x): a, b and x form a triangle that is no face,
  // so every edge of it fails the link condition, however short. Whatever else collapses,
  // with no limit on turning, the surface stays closed and a sphere.
  TriMesh two;
  two.positions = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {-1, 0, 0}, {0, -1, 0}, {0, 0, -1}};
  two.triangles = {{1, 3, 2}, {3, 4, 2}, {4, 0, 2}, {1, 0, 5}, {3, 1, 5}, {4, 3, 5}, {0, 4, 5}};
  for (uint32_t i = 3; i < 6; ++i) {  // the mirror image through the glued face's plane
    const Vec3 p = two.positions[i], n{1, 1, 1};
    two.positions.push_back(p + n * (2 * (1 - dot(p, n)) / 3));
  }
  for (size_t f = 0, nf = two.triangles.size(); f < nf; ++f) {
    Triangle t = two.triangles[f];
    for (uint32_t& v : t) v = v < 3 ? v : v + 3;
    two.triangles.push_back({t[0], t[2], t[1]});
  }
  ASSERT_TRUE(closed_oriented(two));
  EXPECT_GT(collapse_short_edges(two, 1.5, -1.0, midpoint).collapsed, 0u);
  EXPECT_TRUE(closed_oriented(two));
  EXPECT_EQ(topology_report(two).euler_characteristic, 2);
  // The merged vertex placed far off the surface: the triangles around it would turn.
  uint32_t a, b;
  TriMesh m = sphere_with_a_short_edge(&a, &b);
  const double shortest = norm(m.positions[a] - m.positions[b]);
  auto off = [](const Vec3& p, const Vec3& q) { return midpoint(p, q) * 1.5; };
  EXPECT_EQ(collapse_short_edges(m, 2 * shortest, 0.5, off).collapsed, 0u);
  // The same edge on a boundary (a triangle of it removed), or one of its ends there: left.
  TriMesh open = sphere_with_a_short_edge(&a, &b);
  open.triangles.erase(open.triangles.begin() + 17);
  EXPECT_EQ(collapse_short_edges(open, 2 * shortest, 0.5, midpoint).collapsed, 0u);
}

// As polygonize's option, on a blob of jittered particles: a quarter fewer triangles, the
// slivers gone, the same closed surface, every vertex on it.
TEST(ShortEdges, PolygonizeCollapsesMarchingCubesSlivers) {
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> u(-1, 1);
  PointCloud c;
  while (c.positions.size() < 6000) {
    const Vec3 p{u(rng), u(rng), u(rng)};
    if (squared_norm(p) < 1) c.positions.push_back(p * 2.0);
  }
  c.attributes.push_back({"speed", 1, {}});
  for (const Vec3& p : c.positions) c.attributes[0].values.push_back(float(p.x));
  PolygonizeOptions o;
  o.radius = 0.35;
  o.threshold = 1.5;
  const PolygonizeResult raw = polygonize(c, o);
  o.collapse_edges = 0.3;
  const PolygonizeResult clean = polygonize(c, o);
  EXPECT_EQ(raw.stats.edges_collapsed, 0u);
  EXPECT_EQ(clean.stats.edges_collapsed, raw.mesh.positions.size() - clean.mesh.positions.size());
  EXPECT_EQ(clean.stats.edges_collapsed * 2, raw.mesh.triangles.size() - clean.mesh.triangles.size());
  EXPECT_LT(double(clean.mesh.triangles.size()), 0.95 * double(raw.mesh.triangles.size()));
  const TopologyReport r0 = topology_report(raw.mesh), r1 = topology_report(clean.mesh);
  EXPECT_TRUE(closed_oriented(clean.mesh));
  EXPECT_EQ(r1.components, r0.components);
  EXPECT_EQ(r1.euler_characteristic, r0.euler_characteristic);
  const std::vector<double> a0 = smallest_angles(raw.mesh), a1 = smallest_angles(clean.mesh);
  EXPECT_GT(share_below(a0, 10), 0.03);
  EXPECT_LT(share_below(a1, 10), 0.25 * share_below(a0, 10));
  // On the surface as every marching-cubes vertex is (their refinement's tolerance), with the
  // field's normal; the attributes one value per vertex.
  const ParticleField field(c, FieldParams{Kernel::Wyvill, o.radius, o.threshold, {}, {}, {}});
  double worst_raw = 0, least_dot_raw = 1;  // (marching cubes' normal: the gradient of its last Newton step)
  for (size_t v = 0; v < raw.mesh.positions.size(); ++v) {
    const Vec3& x = raw.mesh.positions[v];
    worst_raw = std::max(worst_raw, std::abs(field.value(x) - o.threshold));
    least_dot_raw = std::min(least_dot_raw, dot(raw.mesh.normals[v], normalized(field.gradient(x)) * -1.0));
  }
  EXPECT_GT(least_dot_raw, 0.99);
  ASSERT_EQ(clean.mesh.normals.size(), clean.mesh.positions.size());
  for (size_t v = 0; v < clean.mesh.positions.size(); ++v) {
    const Vec3& x = clean.mesh.positions[v];
    ASSERT_LE(std::abs(field.value(x) - o.threshold), std::max(worst_raw, 1e-9)) << "vertex " << v;
    ASSERT_GE(dot(clean.mesh.normals[v], normalized(field.gradient(x)) * -1.0), least_dot_raw) << "vertex " << v;
  }
  // The merged vertices' attributes are the particles' at their place, as polygonize_attributes
  // gives them at the mesh's vertices: all of them bit for bit.
  ASSERT_EQ(clean.mesh.attributes.size(), 1u);
  const std::vector<VertexAttribute> asked =
      polygonize_attributes(c, o, clean.mesh.positions.data(), clean.mesh.positions.size());
  ASSERT_EQ(asked.size(), 1u);
  EXPECT_EQ(asked[0].values, clean.mesh.attributes[0].values);
  // The same for any thread count.
  o.threads = 1;
  const PolygonizeResult one = polygonize(c, o);
  o.threads = 2;
  const PolygonizeResult two = polygonize(c, o);
  EXPECT_EQ(one.mesh.positions, clean.mesh.positions);
  EXPECT_EQ(two.mesh.positions, clean.mesh.positions);
  EXPECT_EQ(two.mesh.triangles, clean.mesh.triangles);
  EXPECT_EQ(two.mesh.normals, clean.mesh.normals);
  // Out of range, or on a tile: named.
  for (double bad : {-0.1, 0.6, std::numeric_limits<double>::quiet_NaN()}) {
    o.collapse_edges = bad;
    try {
      polygonize(c, o);
      ADD_FAILURE() << bad;
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find("collapse_edges"), std::string::npos) << e.what();
    }
  }
  o.collapse_edges = 0.3;
  o.cells = PolygonizeOptions::CellRange{{0, 0, 0}, {4, 4, 4}};
  EXPECT_THROW(polygonize(c, o), Error);
}
