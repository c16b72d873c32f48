// smooth_mesh(): Loop through OpenSubdiv and modified butterfly through OpenMesh.
//
// What is checked:
//  - counts after k levels on closed meshes: F * 4^k triangles, V' = V + E per level, Euler
//    characteristic unchanged, still a closed, consistently and outward oriented manifold;
//  - one Loop level on small meshes against the Loop masks computed here by hand (interior
//    vertex points with Loop's beta at valence 5 and 6, interior edge points 3/8-3/8-1/8-1/8,
//    boundary vertex points 1/8-3/4-1/8, boundary edge points 1/2-1/2, corners per boundary
//    rule), and against OpenMesh's own LoopT on a closed mesh;
//  - limit positions inside the (convex) control hull, exact across levels, and the refined
//    points converging to them; limit normals: the largest angle between adjacent faces'
//    normals shrinks per level on a sphere with irregular valences, and every normal points
//    outward;
//  - butterfly keeps every original vertex bit for bit;
//  - attributes: constant stays constant, linear stays linear on a flat patch;
//  - bad input, repairs (dropped vertices, orientation), creases, threads, cancellation.
#include "particlemesh/smooth/subdivide.h"
#include "particlemesh/smooth/smoother.h"

#include <gtest/gtest.h>

#include <OpenMesh/Core/Mesh/TriMesh_ArrayKernelT.hh>
#include <OpenMesh/Tools/Subdivider/Uniform/LoopT.hh>
#include <opensubdiv/far/primvarRefiner.h>
#include <opensubdiv/far/topologyDescriptor.h>
#include <opensubdiv/far/topologyRefinerFactory.h>

#include <cmath>
#include <limits>
#include <map>
#include <memory>
#include <random>
#include <set>
#include <string>
#include <vector>

#include "particlemesh/core/error.h"
#include "particlemesh/io/mesh_io.h"
#include "particlemesh/mesh/topology_report.h"
#include "particlemesh/sample/shapes.h"
#include "smooth/loop_limit.h"  // private: the rings built from the refined triangles, as a reference
#include "support/test_support.h"

using namespace particlemesh;
using particlemesh::test::status_of;

namespace {

constexpr double kPi = 3.14159265358979323846;

size_t edge_count(const std::vector<Triangle>& t) { return test::edge_counts(t).size(); }

/// Vertex adjacency of a triangle mesh.
std::vector<std::set<uint32_t>> adjacency(const TriMesh& m) {
  std::vector<std::set<uint32_t>> adj(m.positions.size());
  for (const auto& t : m.triangles)
    for (int c = 0; c < 3; ++c) {
      adj[t[c]].insert(t[(c + 1) % 3]);
      adj[t[(c + 1) % 3]].insert(t[c]);
    }
  return adj;
}

/// After one level, the edge point of control edge (a, b) is the only vertex adjacent to both
/// a and b (vertex i < V of the result is control vertex i).
uint32_t edge_point(const std::vector<std::set<uint32_t>>& adj, uint32_t a, uint32_t b) {
  std::vector<uint32_t> common;
  for (uint32_t x : adj[a])
    if (adj[b].count(x)) common.push_back(x);
  EXPECT_EQ(common.size(), 1u) << "edge (" << a << ", " << b << ")";
  return common.empty() ? UINT32_MAX : common[0];
}

void expect_near(const Vec3& got, const Vec3& want, double tol, const std::string& what) {
  EXPECT_LE(distance(got, want), tol) << what << ": got (" << got.x << ", " << got.y << ", " << got.z
                                      << "), want (" << want.x << ", " << want.y << ", " << want.z << ")";
}

Vec3 face_normal(const TriMesh& m, const Triangle& t) {
  return normalized(cross(m.positions[t[1]] - m.positions[t[0]], m.positions[t[2]] - m.positions[t[0]]));
}

/// Largest angle (radians) between the normals of two triangles sharing an edge.
double max_adjacent_normal_angle(const TriMesh& m) {
  std::map<std::pair<uint32_t, uint32_t>, std::vector<size_t>> faces;
  for (size_t f = 0; f < m.triangles.size(); ++f)
    for (int c = 0; c < 3; ++c) {
      uint32_t a = m.triangles[f][c], b = m.triangles[f][(c + 1) % 3];
      faces[{std::min(a, b), std::max(a, b)}].push_back(f);
    }
  double worst = 0;
  for (const auto& [e, fs] : faces) {
    if (fs.size() != 2) continue;
    const double d = dot(face_normal(m, m.triangles[fs[0]]), face_normal(m, m.triangles[fs[1]]));
    worst = std::max(worst, std::acos(std::clamp(d, -1.0, 1.0)));
  }
  return worst;
}

/// An icosphere with `flips` random edge flips (valences 4..8 instead of only 5 and 6) and
/// radial jitter: a closed, outward, sphere-like mesh with extraordinary vertices.
TriMesh irregular_sphere(int levels, int flips, double jitter, uint64_t seed) {
  TriMesh m = icosphere_mesh(levels);
  std::mt19937_64 rng(seed);
  int done = 0;
  for (int attempt = 0; done < flips && attempt < 100 * flips; ++attempt) {
    std::map<std::pair<uint32_t, uint32_t>, std::vector<size_t>> faces;
    std::vector<int> valence(m.positions.size(), 0);
    for (size_t f = 0; f < m.triangles.size(); ++f)
      for (int c = 0; c < 3; ++c) {
        uint32_t a = m.triangles[f][c], b = m.triangles[f][(c + 1) % 3];
        if (a < b) ++valence[a], ++valence[b];
        faces[{std::min(a, b), std::max(a, b)}].push_back(f);
      }
    auto it = faces.begin();
    std::advance(it, long(rng() % faces.size()));
    const auto [a0, b0] = it->first;
    size_t f = it->second[0], g = it->second[1];
    // Orient so f = (a, b, c) and g = (b, a, d).
    auto rot = [&](size_t face, uint32_t first) {
      Triangle t = m.triangles[face];
      while (t[0] != first) t = {t[1], t[2], t[0]};
      return t;
    };
    Triangle tf = rot(f, a0);
    uint32_t a = a0, b = b0;
    if (tf[1] != b0) {
      std::swap(f, g);
      tf = rot(f, a0);
    }
    const Triangle tg = rot(g, b);
    const uint32_t c = tf[2], d = tg[2];
    if (valence[a] <= 4 || valence[b] <= 4 || valence[c] >= 8 || valence[d] >= 8) continue;
    if (faces.count({std::min(c, d), std::max(c, d)})) continue;
    m.triangles[f] = {a, d, c};
    m.triangles[g] = {d, b, c};
    ++done;
  }
  std::uniform_real_distribution<double> u(1 - jitter, 1 + jitter);
  for (auto& p : m.positions) p = p * u(rng);
  return m;
}

/// A flat hexagonal patch (z = 0), Delaunay-triangulated rows: boundary, corners, valence 6.
TriMesh flat_patch(int nx, int ny) {
  TriMesh m;
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) m.positions.push_back({i + 0.5 * (j % 2), j * std::sqrt(3.0) / 2, 0});
  auto id = [&](int i, int j) { return uint32_t(j * nx + i); };
  for (int j = 0; j + 1 < ny; ++j)
    for (int i = 0; i + 1 < nx; ++i) {
      if (j % 2 == 0) {
        m.triangles.push_back({id(i, j), id(i + 1, j), id(i, j + 1)});
        m.triangles.push_back({id(i + 1, j), id(i + 1, j + 1), id(i, j + 1)});
      } else {
        m.triangles.push_back({id(i, j), id(i + 1, j + 1), id(i, j + 1)});
        m.triangles.push_back({id(i, j), id(i + 1, j), id(i + 1, j + 1)});
      }
    }
  return m;
}

/// Loop's vertex weight for each neighbour (original Loop 1987 beta, as OpenSubdiv uses it).
double loop_beta(int n) {
  const double c = 0.375 + 0.25 * std::cos(2 * kPi / n);
  return (0.625 - c * c) / n;
}

SmoothOptions loop(int levels, bool limit = false) {
  SmoothOptions o;
  o.levels = levels;
  o.limit = limit;
  return o;
}

SmoothOptions butterfly(int levels) {
  SmoothOptions o;
  o.scheme = SmoothScheme::Butterfly;
  o.levels = levels;
  return o;
}

template <class F>
std::string message_of(F&& f) {
  try {
    f();
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

}  // namespace

// ---- counts ------------------------------------------------------------------------------

struct CountCase {
  const char* name;
  TriMesh (*make)();
  int euler;
};

class SmoothCounts : public ::testing::TestWithParam<std::tuple<int, int>> {};

TEST_P(SmoothCounts, FacesTimesFourVerticesPlusEdgesEulerKept) {
  const auto [scheme, levels] = GetParam();
  const std::vector<std::pair<TriMesh, int>> meshes = {
      {icosphere_mesh(1), 2}, {torus_mesh(1, 0.35, 16, 9), 0}, {trefoil_tube_mesh(0.3, 0.1, 40, 8), 0},
      {irregular_sphere(1, 20, 0.05, 7), 2}};
  for (const auto& [m, euler] : meshes) {
    SmoothOptions o = scheme == 0 ? loop(levels, true) : butterfly(levels);
    const SmoothResult r = smooth_mesh(m, o);
    size_t v = m.positions.size(), e = edge_count(m.triangles), f = m.triangles.size();
    for (int l = 0; l < levels; ++l) {
      v += e;              // one new vertex per edge
      e = 2 * e + 3 * f;  // every edge split, three inner edges per triangle
      f *= 4;
    }
    EXPECT_EQ(r.mesh.triangles.size(), f);
    EXPECT_EQ(r.mesh.positions.size(), v);
    EXPECT_EQ(r.mesh.normals.size(), v);
    EXPECT_EQ(r.stats.triangles, f);
    EXPECT_EQ(r.stats.vertices, v);
    EXPECT_EQ(r.stats.control_edges, edge_count(m.triangles));
    const TopologyReport t = topology_report(r.mesh);
    EXPECT_EQ(t.edges, e);
    EXPECT_EQ(t.euler_characteristic, euler);
    EXPECT_EQ(t.euler_characteristic, topology_report(m).euler_characteristic);
    EXPECT_TRUE(t.closed);
    EXPECT_TRUE(t.manifold);
    EXPECT_TRUE(t.consistently_oriented);
    EXPECT_TRUE(t.outward);
    EXPECT_EQ(t.degenerate_triangles, 0u);
    EXPECT_EQ(r.original_vertex.size(), m.positions.size());
  }
}

INSTANTIATE_TEST_SUITE_P(LoopAndButterfly, SmoothCounts,
                         ::testing::Combine(::testing::Values(0, 1), ::testing::Values(1, 2, 3)),
                         [](const auto& info) {
                           return std::string(std::get<0>(info.param) == 0 ? "Loop" : "Butterfly") + "_levels" +
                                  std::to_string(std::get<1>(info.param));
                         });

TEST(Smooth, LevelZeroKeepsTheConnectivity) {
  const TriMesh m = irregular_sphere(1, 10, 0.05, 3);
  const SmoothResult b = smooth_mesh(m, butterfly(0));
  EXPECT_EQ(b.mesh.positions, m.positions);
  EXPECT_EQ(b.mesh.triangles, m.triangles);
  const SmoothResult l = smooth_mesh(m, loop(0, true));
  EXPECT_EQ(l.mesh.triangles, m.triangles);
  // Loop at level 0 with the limit moves every control vertex onto the limit surface: the
  // same points as the limit of any deeper level.
  const SmoothResult l3 = smooth_mesh(m, loop(3, true));
  for (size_t i = 0; i < m.positions.size(); ++i) expect_near(l.mesh.positions[i], l3.mesh.positions[i], 1e-12, "limit");
  EXPECT_GT(distance(l.mesh.positions[0], m.positions[0]), 1e-3);
}

// ---- Loop masks by hand --------------------------------------------------------------------

// A fan of n triangles around vertex 0 (interior, valence n), ring vertices 1..n on the
// boundary, z perturbed so nothing is accidentally symmetric:
//
//          2 ------ 1
//         /  \    /  \           edge points: interior (0, i) -> 3/8 (0 + i) + 1/8 (i-1 + i+1)
//        3 -- 0 ----- n          boundary (i, i+1) -> 1/2 (i + i+1)
//         \  /  \   /            vertex points: 0 -> (1 - n beta) 0 + beta sum(ring),
//          4 ---- ...            ring i (boundary) -> 3/4 i + 1/8 (i-1 + i+1)
TriMesh fan(int n) {
  TriMesh m;
  m.positions.push_back({0.1, -0.05, 0.3});
  for (int i = 0; i < n; ++i) {
    const double a = 2 * kPi * i / n;
    m.positions.push_back({std::cos(a), std::sin(a), 0.1 * std::sin(3.0 * i + 1)});
  }
  for (int i = 0; i < n; ++i) m.triangles.push_back({0, uint32_t(1 + i), uint32_t(1 + (i + 1) % n)});
  return m;
}

TEST(SmoothLoopMasks, OneLevelMatchesHandComputedMasks) {
  for (int n : {5, 6, 7}) {
    SCOPED_TRACE("valence " + std::to_string(n));
    const TriMesh m = fan(n);
    const SmoothResult r = smooth_mesh(m, loop(1));
    ASSERT_EQ(r.mesh.positions.size(), size_t(1 + n + 2 * n));
    const auto adj = adjacency(r.mesh);
    const auto& P = m.positions;
    auto ring = [&](int i) { return uint32_t(1 + ((i % n) + n) % n); };
    const double beta = loop_beta(n);
    if (n == 6) {
      EXPECT_DOUBLE_EQ(beta, 1.0 / 16);
    }
    Vec3 centre = P[0] * (1 - n * beta);
    for (int i = 0; i < n; ++i) centre += P[ring(i)] * beta;
    expect_near(r.mesh.positions[0], centre, 1e-14, "interior vertex point");
    for (int i = 0; i < n; ++i) {
      const Vec3 boundary_vertex = P[ring(i)] * 0.75 + (P[ring(i - 1)] + P[ring(i + 1)]) * 0.125;
      expect_near(r.mesh.positions[ring(i)], boundary_vertex, 1e-14, "boundary vertex point");
      const Vec3 interior_edge = (P[0] + P[ring(i)]) * 0.375 + (P[ring(i - 1)] + P[ring(i + 1)]) * 0.125;
      expect_near(r.mesh.positions[edge_point(adj, 0, ring(i))], interior_edge, 1e-14, "interior edge point");
      const Vec3 boundary_edge = (P[ring(i)] + P[ring(i + 1)]) * 0.5;
      expect_near(r.mesh.positions[edge_point(adj, ring(i), ring(i + 1))], boundary_edge, 1e-14,
                  "boundary edge point");
    }
  }
}

// Two triangles: every vertex is on the boundary; vertices 0 and 2 are in a single triangle
// (corners), 1 and 3 in both.
//
//     3 ------ 2
//     | \      |
//     |   \    |
//     0 ------ 1
TEST(SmoothLoopMasks, BoundaryRulesAtCorners) {
  TriMesh m;
  m.positions = {{0, 0, 0}, {1, 0, 0.2}, {1.1, 1, 0}, {0, 1, -0.1}};
  m.triangles = {{0, 1, 3}, {1, 2, 3}};
  const auto& P = m.positions;
  auto smooth_corner = [&](int v, int prev, int next) { return P[v] * 0.75 + (P[prev] + P[next]) * 0.125; };

  SmoothOptions o = loop(1);
  o.boundary = BoundaryRule::EdgeAndCorner;
  SmoothResult r = smooth_mesh(m, o);
  EXPECT_EQ(r.mesh.positions[0], P[0]);  // corners pinned
  EXPECT_EQ(r.mesh.positions[2], P[2]);
  expect_near(r.mesh.positions[1], smooth_corner(1, 0, 2), 1e-14, "boundary vertex 1");
  expect_near(r.mesh.positions[3], smooth_corner(3, 2, 0), 1e-14, "boundary vertex 3");
  // The limit of a pinned corner is the corner itself.
  o.limit = true;
  r = smooth_mesh(m, o);
  expect_near(r.mesh.positions[0], P[0], 1e-14, "corner at the limit");

  o = loop(1);
  o.boundary = BoundaryRule::EdgeOnly;
  r = smooth_mesh(m, o);
  expect_near(r.mesh.positions[0], smooth_corner(0, 3, 1), 1e-14, "corner, edge-only");
  expect_near(r.mesh.positions[2], smooth_corner(2, 1, 3), 1e-14, "corner, edge-only");
  expect_near(r.mesh.positions[1], smooth_corner(1, 0, 2), 1e-14, "boundary vertex 1, edge-only");
  const auto adj = adjacency(r.mesh);
  expect_near(r.mesh.positions[edge_point(adj, 0, 1)], (P[0] + P[1]) * 0.5, 1e-14, "boundary edge point");
  // The interior edge (1, 3) has its two triangles' third corners 0 and 2.
  expect_near(r.mesh.positions[edge_point(adj, 1, 3)], (P[1] + P[3]) * 0.375 + (P[0] + P[2]) * 0.125, 1e-14,
              "interior edge point");
}

// OpenSubdiv called directly (refined points of `levels` uniform levels, Loop, no limit).
std::vector<Vec3> far_loop(const TriMesh& m, int levels, OpenSubdiv::Sdc::Options::VtxBoundaryInterpolation rule) {
  namespace Far = OpenSubdiv::Far;
  using Factory = Far::TopologyRefinerFactory<Far::TopologyDescriptor>;
  std::vector<int> per_face(m.triangles.size(), 3), verts;
  for (const auto& t : m.triangles) verts.insert(verts.end(), {int(t[0]), int(t[1]), int(t[2])});
  Far::TopologyDescriptor desc;
  desc.numVertices = int(m.positions.size());
  desc.numFaces = int(m.triangles.size());
  desc.numVertsPerFace = per_face.data();
  desc.vertIndicesPerFace = verts.data();
  OpenSubdiv::Sdc::Options sdc;
  sdc.SetVtxBoundaryInterpolation(rule);
  std::unique_ptr<Far::TopologyRefiner> refiner(
      Factory::Create(desc, Factory::Options(OpenSubdiv::Sdc::SCHEME_LOOP, sdc)));
  refiner->RefineUniform(Far::TopologyRefiner::UniformOptions(levels));
  struct P {
    double x, y, z;
    void Clear() { x = y = z = 0; }
    void AddWithWeight(const P& s, double w) { x += w * s.x, y += w * s.y, z += w * s.z; }
  };
  std::vector<P> src;
  for (const auto& p : m.positions) src.push_back({p.x, p.y, p.z});
  Far::PrimvarRefinerReal<double> primvar(*refiner);
  for (int l = 1; l <= levels; ++l) {
    std::vector<P> dst(size_t(refiner->GetLevel(l).GetNumVertices()));
    P* d = dst.data();
    const P* s = src.data();
    primvar.Interpolate(l, s, d);
    src = std::move(dst);
  }
  std::vector<Vec3> out;
  for (const auto& p : src) out.push_back({p.x, p.y, p.z});
  return out;
}

TEST(SmoothLoopMasks, MatchesOpenSubdivCalledDirectly) {
  using Sdc = OpenSubdiv::Sdc::Options;
  const TriMesh m = flat_patch(5, 4);
  TriMesh bumpy = m;
  for (size_t i = 0; i < bumpy.positions.size(); ++i) bumpy.positions[i].z = 0.3 * std::sin(1.7 * double(i));
  for (int levels : {1, 2}) {
    SmoothOptions o = loop(levels);
    o.boundary = BoundaryRule::EdgeOnly;
    EXPECT_EQ(smooth_mesh(bumpy, o).mesh.positions, far_loop(bumpy, levels, Sdc::VTX_BOUNDARY_EDGE_ONLY));
    o.boundary = BoundaryRule::EdgeAndCorner;
    EXPECT_EQ(smooth_mesh(bumpy, o).mesh.positions, far_loop(bumpy, levels, Sdc::VTX_BOUNDARY_EDGE_AND_CORNER));
    // Why BoundaryRule has no "None": under uniform refinement OpenSubdiv's VTX_BOUNDARY_NONE
    // gives the EDGE_ONLY points (it only marks boundary faces as holes in patch tables).
    EXPECT_EQ(far_loop(bumpy, levels, Sdc::VTX_BOUNDARY_NONE), far_loop(bumpy, levels, Sdc::VTX_BOUNDARY_EDGE_ONLY));
    EXPECT_NE(far_loop(bumpy, levels, Sdc::VTX_BOUNDARY_EDGE_AND_CORNER),
              far_loop(bumpy, levels, Sdc::VTX_BOUNDARY_EDGE_ONLY));
  }
}

// The limit through OpenSubdiv itself: PrimvarRefiner::Limit on the full last level.
void far_loop_limit(const TriMesh& m, int levels, std::vector<Vec3>* pos, std::vector<Vec3>* normals) {
  namespace Far = OpenSubdiv::Far;
  using Factory = Far::TopologyRefinerFactory<Far::TopologyDescriptor>;
  std::vector<int> per_face(m.triangles.size(), 3), verts;
  for (const auto& t : m.triangles) verts.insert(verts.end(), {int(t[0]), int(t[1]), int(t[2])});
  Far::TopologyDescriptor desc;
  desc.numVertices = int(m.positions.size());
  desc.numFaces = int(m.triangles.size());
  desc.numVertsPerFace = per_face.data();
  desc.vertIndicesPerFace = verts.data();
  std::unique_ptr<Far::TopologyRefiner> refiner(
      Factory::Create(desc, Factory::Options(OpenSubdiv::Sdc::SCHEME_LOOP, OpenSubdiv::Sdc::Options())));
  Far::TopologyRefiner::UniformOptions uniform(levels);
  uniform.fullTopologyInLastLevel = true;
  refiner->RefineUniform(uniform);
  struct P {
    double x, y, z;
    void Clear() { x = y = z = 0; }
    void AddWithWeight(const P& s, double w) { x += w * s.x, y += w * s.y, z += w * s.z; }
  };
  std::vector<P> src;
  for (const auto& p : m.positions) src.push_back({p.x, p.y, p.z});
  Far::PrimvarRefinerReal<double> primvar(*refiner);
  for (int l = 1; l <= levels; ++l) {
    std::vector<P> dst(size_t(refiner->GetLevel(l).GetNumVertices()));
    P* d = dst.data();
    const P* s = src.data();
    primvar.Interpolate(l, s, d);
    src = std::move(dst);
  }
  std::vector<P> lim(src.size()), t1(src.size()), t2(src.size());
  P *lp = lim.data(), *t1p = t1.data(), *t2p = t2.data();
  const P* sp = src.data();
  primvar.Limit(sp, lp, t1p, t2p);
  pos->clear();
  normals->clear();
  for (size_t i = 0; i < lim.size(); ++i) {
    pos->push_back({lim[i].x, lim[i].y, lim[i].z});
    normals->push_back(normalized(cross(Vec3{t1[i].x, t1[i].y, t1[i].z}, Vec3{t2[i].x, t2[i].y, t2[i].z})));
  }
}

TEST(SmoothLimit, ClosedSurfacesMatchOpenSubdivsLimit) {
  // On a closed surface without creases smooth_mesh takes the limit itself, in parallel
  // (smooth/loop_limit.h), with OpenSubdiv's masks: the same points and normals as
  // PrimvarRefiner::Limit, to rounding, at irregular valences (3..9) too.
  const TriMesh m = irregular_sphere(2, 7, 0.05, 5);
  for (int levels : {0, 1, 2}) {
    std::vector<Vec3> want_pos, want_normals;
    far_loop_limit(m, levels, &want_pos, &want_normals);
    const SmoothResult r = smooth_mesh(m, loop(levels, true));
    ASSERT_EQ(r.mesh.positions.size(), want_pos.size());
    for (size_t i = 0; i < want_pos.size(); ++i) {
      ASSERT_LT(distance(r.mesh.positions[i], want_pos[i]), 1e-14) << "level " << levels << " vertex " << i;
      ASSERT_GT(dot(r.mesh.normals[i], want_normals[i]), 1 - 1e-12) << "level " << levels << " vertex " << i;
    }
  }
}

/// A closed bipyramid over a regular n-gon: two apexes of valence n, the rest of valence 4.
TriMesh bipyramid(int n) {
  TriMesh m;
  m.positions = {{0, 0, 1.3}, {0, 0, -0.9}};
  for (int i = 0; i < n; ++i)
    m.positions.push_back({std::cos(2 * kPi * i / n), std::sin(2 * kPi * i / n), 0.1 * (i % 3)});
  for (int i = 0; i < n; ++i) {
    const uint32_t a = uint32_t(2 + i), b = uint32_t(2 + (i + 1) % n);
    m.triangles.push_back({0, a, b});
    m.triangles.push_back({1, b, a});
  }
  return m;
}

TEST(SmoothLimit, OwnLimitIsTheLimitOverTheRefinedTrianglesRingsBitForBit) {
  // smooth_mesh reads each refined vertex's ring from the level before the last (OpenSubdiv's
  // parent faces and edges), never from the refined triangles. The reference here builds the
  // rings from the refined triangles themselves (build_loop_rings: every vertex's corners
  // bucketed and walked) and applies the same masks to the same refined points: the same
  // limit positions and normals, bit for bit, at every level, valence and thread count.
  for (const TriMesh& m : {irregular_sphere(1, 20, 0.05, 13), bipyramid(13)}) {
    for (int levels : {1, 2, 3})
      for (int threads : {1, 2, 3}) {
        SmoothOptions o = loop(levels, false);
        o.threads = threads;
        const SmoothResult refined = smooth_mesh(m, o);  // the last level's points, before the limit
        const size_t n = refined.mesh.positions.size();
        detail::LoopRings rings;
        ASSERT_TRUE(detail::build_loop_rings(refined.mesh.triangles, n, &rings));
        const detail::LoopLimitMasks masks(rings.max_valence);
        std::vector<Vec3> want_pos, want_normals;
        detail::loop_limit_positions(rings, masks, refined.mesh.positions, want_pos, want_normals);
        o.limit = true;
        const SmoothResult r = smooth_mesh(m, o);
        const std::string at = "level " + std::to_string(levels) + ", " + std::to_string(threads) + " threads";
        ASSERT_EQ(r.mesh.triangles, refined.mesh.triangles) << at;
        ASSERT_EQ(r.mesh.positions.size(), n) << at;
        for (size_t i = 0; i < n; ++i) {
          ASSERT_EQ(r.mesh.positions[i], want_pos[i]) << at << ", vertex " << i;
          ASSERT_NE(want_normals[i], Vec3{}) << at << ", vertex " << i;
          ASSERT_EQ(r.mesh.normals[i], want_normals[i]) << at << ", vertex " << i;
        }
      }
  }
}

TEST(SmoothLoopMasks, InfinitelySharpCreaseUsesTheCreaseRule) {
  // Crease the two edges 1-0-4 through the centre of a valence-6 fan: the centre becomes a
  // crease vertex (1/8-3/4-1/8 along the crease) and the crease edges split at their midpoints.
  const TriMesh m = fan(6);
  const auto& P = m.positions;
  SmoothOptions o = loop(1);
  o.creases = {{0, 1}, {4, 0}};
  const SmoothResult r = smooth_mesh(m, o);
  EXPECT_EQ(r.stats.creases, 2u);
  expect_near(r.mesh.positions[0], P[0] * 0.75 + (P[1] + P[4]) * 0.125, 1e-14, "crease vertex");
  const auto adj = adjacency(r.mesh);
  expect_near(r.mesh.positions[edge_point(adj, 0, 1)], (P[0] + P[1]) * 0.5, 1e-14, "crease edge point");
  expect_near(r.mesh.positions[edge_point(adj, 0, 4)], (P[0] + P[4]) * 0.5, 1e-14, "crease edge point");

  // Sharpness 0 is no crease at all; a semi-sharp crease lands in between.
  o.creases = {{0, 1, 0.0f}, {4, 0, 0.0f}};
  const SmoothResult smooth = smooth_mesh(m, o);
  const SmoothResult plain = smooth_mesh(m, loop(1));
  EXPECT_EQ(smooth.mesh.positions, plain.mesh.positions);
  o.creases = {{0, 1, 0.5f}, {4, 0, 0.5f}};
  const SmoothResult semi = smooth_mesh(m, o);
  const double d_sharp = distance(r.mesh.positions[0], plain.mesh.positions[0]);
  EXPECT_GT(d_sharp, 1e-3);
  EXPECT_NEAR(distance(semi.mesh.positions[0], plain.mesh.positions[0]) +
                  distance(semi.mesh.positions[0], r.mesh.positions[0]),
              d_sharp, 1e-12);  // on the segment between smooth and sharp
  EXPECT_GT(distance(semi.mesh.positions[0], plain.mesh.positions[0]), 1e-4);
  EXPECT_GT(distance(semi.mesh.positions[0], r.mesh.positions[0]), 1e-4);
}

// Far-vs-Hbr style: OpenSubdiv's Loop (limit off) against OpenMesh's LoopT on a closed mesh.
TEST(SmoothLoopMasks, MatchesOpenMeshLoopOnAClosedMesh) {
  struct Traits : OpenMesh::DefaultTraits {
    typedef OpenMesh::Vec3d Point;
    typedef OpenMesh::Vec3d Normal;
  };
  using OM = OpenMesh::TriMesh_ArrayKernelT<Traits>;
  const TriMesh m = irregular_sphere(1, 15, 0.05, 11);
  OM om;
  for (const auto& p : m.positions) om.add_vertex(OM::Point(p.x, p.y, p.z));
  for (const auto& t : m.triangles)
    ASSERT_TRUE(om.add_face(OM::VertexHandle(int(t[0])), OM::VertexHandle(int(t[1])), OM::VertexHandle(int(t[2])))
                    .is_valid());
  OpenMesh::Subdivider::Uniform::LoopT<OM, double> om_loop;
  om_loop.attach(om);
  om_loop(1);
  om_loop.detach();
  const SmoothResult r = smooth_mesh(m, loop(1));
  ASSERT_EQ(size_t(om.n_vertices()), r.mesh.positions.size());
  ASSERT_EQ(size_t(om.n_faces()), r.mesh.triangles.size());
  // Original vertices keep their index in both; match edge points by their control edge.
  for (size_t i = 0; i < m.positions.size(); ++i) {
    const auto& p = om.point(OM::VertexHandle(int(i)));
    expect_near(r.mesh.positions[i], {p[0], p[1], p[2]}, 1e-12, "vertex point " + std::to_string(i));
  }
  TriMesh om_mesh;
  for (size_t i = 0; i < om.n_vertices(); ++i) {
    const auto& p = om.point(OM::VertexHandle(int(i)));
    om_mesh.positions.push_back({p[0], p[1], p[2]});
  }
  for (const auto& f : om.faces()) {
    Triangle t{};
    int k = 0;
    for (const auto& v : om.fv_range(f)) t[k++] = uint32_t(v.idx());
    om_mesh.triangles.push_back(t);
  }
  const auto ours = adjacency(r.mesh), theirs = adjacency(om_mesh);
  for (const auto& [e, n] : test::edge_counts(m.triangles))
    expect_near(r.mesh.positions[edge_point(ours, e.first, e.second)],
                om_mesh.positions[edge_point(theirs, e.first, e.second)], 1e-12, "edge point");
}

// ---- limit ------------------------------------------------------------------------------

TEST(SmoothLimit, PositionsInsideTheControlHullExactAndConverging) {
  // The icosphere is convex, so its triangles' planes bound the control hull.
  const TriMesh m = icosphere_mesh(1);
  const SmoothResult lim1 = smooth_mesh(m, loop(1, true));
  for (const auto& p : lim1.mesh.positions)
    for (const auto& t : m.triangles) {
      const Vec3 n = face_normal(m, t);
      ASSERT_LE(dot(n, p - m.positions[t[0]]), 1e-12);
    }
  // Limit positions are exact: the control vertices' limit points agree at every level ...
  std::vector<double> gap;
  for (int levels = 1; levels <= 4; ++levels) {
    const SmoothResult lim = smooth_mesh(m, loop(levels, true));
    const SmoothResult ref = smooth_mesh(m, loop(levels, false));
    double g = 0;
    for (size_t i = 0; i < m.positions.size(); ++i) {
      EXPECT_LE(distance(lim.mesh.positions[i], lim1.mesh.positions[i]), 1e-12);
      g = std::max(g, distance(ref.mesh.positions[i], lim.mesh.positions[i]));
    }
    // ... and also for every vertex of the refined mesh, which must lie inside the hull too.
    for (const auto& p : lim.mesh.positions) ASSERT_LE(norm(p), 1.0 + 1e-12);
    gap.push_back(g);
  }
  // ... and the refined control points converge to them (Loop: about x1/4 per level).
  for (size_t k = 1; k < gap.size(); ++k) EXPECT_LT(gap[k], 0.3 * gap[k - 1]) << "level " << k + 1;
  EXPECT_GT(gap[0], 1e-3);
}

TEST(SmoothLimit, NormalsTurnSmootherPerLevelAndPointOutward) {
  const TriMesh m = irregular_sphere(2, 40, 0.04, 5);
  std::set<int> valences;
  for (const auto& s : adjacency(m)) valences.insert(int(s.size()));
  EXPECT_GE(valences.size(), 4u);  // really irregular: 4, 5, 6, 7, ...
  double previous = max_adjacent_normal_angle(m);
  for (int levels = 1; levels <= 3; ++levels) {
    const SmoothResult r = smooth_mesh(m, loop(levels, true));
    ASSERT_TRUE(r.stats.limit);
    const double worst = max_adjacent_normal_angle(r.mesh);
    EXPECT_LT(worst, 0.7 * previous) << "level " << levels;
    previous = worst;
    for (size_t i = 0; i < r.mesh.normals.size(); ++i) {
      EXPECT_NEAR(norm(r.mesh.normals[i]), 1.0, 1e-12);
      ASSERT_GT(dot(r.mesh.normals[i], normalized(r.mesh.positions[i])), 0.8) << "vertex " << i;
    }
    // The limit normal agrees with the faces around it, closer at every level.
    double off = 0;
    for (const auto& t : r.mesh.triangles)
      for (int c = 0; c < 3; ++c)
        off = std::max(off, std::acos(std::clamp(dot(face_normal(r.mesh, t), r.mesh.normals[t[c]]), -1.0, 1.0)));
    EXPECT_LT(off, 0.5 * kPi / 2 / levels);
  }
}

TEST(SmoothLimit, BoundaryNormalsAreUnitAndFaceTheWinding) {
  const TriMesh m = flat_patch(6, 5);  // flat, wound counter-clockwise seen from +z
  const SmoothResult r = smooth_mesh(m, loop(2, true));
  for (const auto& n : r.mesh.normals) {
    EXPECT_NEAR(n.x, 0, 1e-12);
    EXPECT_NEAR(n.y, 0, 1e-12);
    EXPECT_NEAR(n.z, 1, 1e-12);
  }
  for (const auto& p : r.mesh.positions) EXPECT_EQ(p.z, 0);
}

// ---- butterfly ---------------------------------------------------------------------------

TEST(SmoothButterfly, EveryOriginalVertexKeepsItsPositionExactly) {
  for (const TriMesh& m : {irregular_sphere(1, 20, 0.05, 9), flat_patch(7, 6), fan(5), trefoil_tube_mesh(0.3, 0.1, 40, 8)}) {
    for (int levels = 1; levels <= 3; ++levels) {
      const SmoothResult r = smooth_mesh(m, butterfly(levels));
      for (size_t i = 0; i < m.positions.size(); ++i) ASSERT_EQ(r.mesh.positions[i], m.positions[i]) << i;
      // New vertices really move off the flat triangles on a curved mesh.
      const TopologyReport t = topology_report(r.mesh);
      EXPECT_TRUE(t.manifold);
      EXPECT_TRUE(t.consistently_oriented);
    }
  }
  // The regular interior stencil (8-point: 1/2, 1/8, -1/16) on a valence-6 neighbourhood.
  const TriMesh m = irregular_sphere(2, 0, 0.05, 4);  // icosphere: edges between valence-6 vertices
  const SmoothResult r = smooth_mesh(m, butterfly(1));
  const auto adj_in = adjacency(m), adj_out = adjacency(r.mesh);
  std::map<std::pair<uint32_t, uint32_t>, std::vector<uint32_t>> opposite;  // edge -> third corners
  for (const auto& t : m.triangles)
    for (int c = 0; c < 3; ++c) {
      const uint32_t a = t[c], b = t[(c + 1) % 3];
      opposite[{std::min(a, b), std::max(a, b)}].push_back(t[(c + 2) % 3]);
    }
  auto third = [&](uint32_t a, uint32_t b, uint32_t not_this) {
    for (uint32_t x : opposite[{std::min(a, b), std::max(a, b)}])
      if (x != not_this) return x;
    return UINT32_MAX;
  };
  int checked = 0;
  for (const auto& [e, cs] : opposite) {
    const auto [a, b] = e;
    if (adj_in[a].size() != 6 || adj_in[b].size() != 6) continue;
    const uint32_t c = cs[0], d = cs[1];
    const Vec3 want = (m.positions[a] + m.positions[b]) * 0.5 + (m.positions[c] + m.positions[d]) * 0.125 -
                      (m.positions[third(a, c, b)] + m.positions[third(b, c, a)] + m.positions[third(a, d, b)] +
                       m.positions[third(b, d, a)]) * 0.0625;
    expect_near(r.mesh.positions[edge_point(adj_out, a, b)], want, 1e-12, "butterfly edge point");
    ++checked;
  }
  EXPECT_GT(checked, 50);
}

// ---- attributes --------------------------------------------------------------------------

TEST(SmoothAttributes, ConstantStaysConstantLinearStaysLinear) {
  // Flat patch (boundary, corners) and a curved closed mesh; channels of 1, 4 and 3
  // components so the butterfly packs them across meshes (3 per mesh).
  for (const TriMesh& base : {flat_patch(7, 6), irregular_sphere(1, 10, 0.05, 2)}) {
    TriMesh m = base;
    const bool flat = base.positions[0].z == 0 && base.positions[5].z == 0;
    auto linear = [](const Vec3& p) { return std::array<double, 3>{2 * p.x - p.y + 0.5, -p.x + 3 * p.z, 0.25 * p.y}; };
    VertexAttribute constant{"radius", 1, std::vector<float>(m.positions.size(), 0.125f)};
    VertexAttribute colour{"colour", 4, {}};
    VertexAttribute velocity{"velocity", 3, {}};
    for (const auto& p : m.positions) {
      colour.values.insert(colour.values.end(), {0.25f, 0.5f, 0.75f, 1.0f});
      const auto l = linear(p);
      velocity.values.insert(velocity.values.end(), {float(l[0]), float(l[1]), float(l[2])});
    }
    m.attributes = {constant, colour, velocity};
    for (const SmoothOptions& o : {loop(2, false), loop(2, true), butterfly(2)}) {
      SCOPED_TRACE(std::string(o.scheme == SmoothScheme::Loop ? (o.limit ? "loop limit" : "loop") : "butterfly") +
                   (flat ? " flat" : " sphere"));
      const SmoothResult r = smooth_mesh(m, o);
      ASSERT_EQ(r.mesh.attributes.size(), 3u);
      EXPECT_EQ(r.mesh.attributes[0].name, "radius");
      EXPECT_EQ(r.mesh.attributes[1].name, "colour");
      EXPECT_EQ(r.mesh.attributes[1].components, 4);
      EXPECT_EQ(r.mesh.attributes[2].name, "velocity");
      const size_t nv = r.mesh.positions.size();
      ASSERT_EQ(r.mesh.attributes[0].values.size(), nv);
      ASSERT_EQ(r.mesh.attributes[1].values.size(), 4 * nv);
      ASSERT_EQ(r.mesh.attributes[2].values.size(), 3 * nv);
      for (size_t i = 0; i < nv; ++i) {
        ASSERT_NEAR(r.mesh.attributes[0].values[i], 0.125f, 1e-6);
        for (int c = 0; c < 4; ++c) ASSERT_NEAR(r.mesh.attributes[1].values[4 * i + c], 0.25f * (c + 1), 1e-6);
        // The schemes are affine-invariant and attributes go through the same masks as the
        // positions, so a linear function of the position stays that function of the new
        // position (on the flat patch: stays linear over the plane).
        const auto l = linear(r.mesh.positions[i]);
        for (int c = 0; c < 3; ++c) ASSERT_NEAR(r.mesh.attributes[2].values[3 * i + c], l[c], 2e-5) << i;
      }
      if (flat) {
        for (const auto& p : r.mesh.positions) ASSERT_EQ(p.z, 0);
      }
    }
  }
}

// ---- input that the libraries would reject -----------------------------------------------

TEST(SmoothInput, UnreferencedVerticesAreDroppedAndMapped) {
  TriMesh m = icosphere_mesh(1);
  // Interleave unused vertices: new index = 2 * old + 1, even indices unused.
  TriMesh sparse;
  for (const auto& p : m.positions) sparse.positions.insert(sparse.positions.end(), {Vec3{9, 9, 9}, p});
  for (const auto& t : m.triangles) sparse.triangles.push_back({2 * t[0] + 1, 2 * t[1] + 1, 2 * t[2] + 1});
  sparse.positions.push_back({std::nan(""), 0, 0});  // unreferenced, so not an error
  std::vector<float> id;
  for (size_t i = 0; i < sparse.positions.size(); ++i) id.push_back(float(i));
  sparse.attributes = {{"id", 1, id}};
  const SmoothResult a = smooth_mesh(sparse, loop(2, true));
  const SmoothResult b = smooth_mesh(m, loop(2, true));
  EXPECT_EQ(a.stats.dropped_vertices, m.positions.size() + 1);
  EXPECT_EQ(a.stats.input_vertices, sparse.positions.size());
  EXPECT_EQ(a.mesh.positions, b.mesh.positions);
  EXPECT_EQ(a.mesh.triangles, b.mesh.triangles);
  ASSERT_EQ(a.original_vertex.size(), m.positions.size());
  for (size_t i = 0; i < m.positions.size(); ++i) EXPECT_EQ(a.original_vertex[i], 2 * i + 1);
  EXPECT_EQ(b.original_vertex[5], 5u);
}

TEST(SmoothInput, InconsistentOrientationIsRepairedOutward) {
  const TriMesh good = irregular_sphere(1, 10, 0.05, 21);
  const SmoothResult want = smooth_mesh(good, loop(1, true));
  // Sorted corners (as the raw triangulation writes them): about half the faces flip.
  TriMesh sorted = good;
  for (auto& t : sorted.triangles) std::sort(t.begin(), t.end());
  const SmoothResult r = smooth_mesh(sorted, loop(1, true));
  EXPECT_GT(r.stats.reoriented_triangles, 0u);
  EXPECT_TRUE(topology_report(r.mesh).outward);
  EXPECT_EQ(r.mesh.positions, want.mesh.positions);
  for (size_t i = 0; i < r.mesh.normals.size(); ++i) EXPECT_NEAR(dot(r.mesh.normals[i], want.mesh.normals[i]), 1, 1e-12);
  // A consistently inward mesh is the caller's choice: left alone.
  TriMesh inward = good;
  for (auto& t : inward.triangles) std::swap(t[1], t[2]);
  const SmoothResult in = smooth_mesh(inward, loop(1, true));
  EXPECT_EQ(in.stats.reoriented_triangles, 0u);
  EXPECT_FALSE(topology_report(in.mesh).outward);
  // An open patch: flood-filled from its first triangle.
  TriMesh patch = flat_patch(5, 4);
  std::swap(patch.triangles[3][0], patch.triangles[3][1]);
  const SmoothResult p = smooth_mesh(patch, butterfly(1));
  EXPECT_EQ(p.stats.reoriented_triangles, 1u);
  EXPECT_TRUE(topology_report(p.mesh).consistently_oriented);
}

// The layout smooth/subdivide.h promises for both schemes: the children of input triangle f
// are output triangles f * 4^levels onward, each level's four children of (a, b, c) being
// (a, ab, ca), (ab, b, bc), (ca, bc, c), (bc, ca, ab). Checked by each output corner's
// weights over its input triangle's corners (times 2^levels, so integers): one output vertex
// per point of the input triangle, and the input's own corners where the weights are a unit.
TEST(SmoothLayout, ChildrenOfEachInputTriangleFollowOneLayout) {
  TriMesh sphere = irregular_sphere(1, 6, 0.05, 5);
  const std::set<size_t> flipped{3, 10, 17};  // the repair turns these back: corners (a, c, b)
  for (size_t f : flipped) std::swap(sphere.triangles[f][1], sphere.triangles[f][2]);
  using Weights = std::array<int, 3>;
  using Corners = std::array<Weights, 3>;
  for (const bool closed : {true, false}) {
    const TriMesh m = closed ? sphere : flat_patch(5, 4);
    for (const SmoothOptions& o : {loop(1), loop(2, true), loop(3), butterfly(1), butterfly(2), butterfly(3)}) {
      SCOPED_TRACE(std::string(closed ? "sphere" : "patch") + (o.scheme == SmoothScheme::Loop ? " loop " : " butterfly ") +
                   std::to_string(o.levels));
      const SmoothResult r = smooth_mesh(m, o);
      EXPECT_EQ(r.stats.reoriented_triangles, closed ? flipped.size() : 0u);
      const size_t k = size_t(1) << (2 * o.levels);
      ASSERT_EQ(r.mesh.triangles.size(), m.triangles.size() * k);
      std::vector<Corners> layout{{Weights{1, 0, 0}, Weights{0, 1, 0}, Weights{0, 0, 1}}};
      for (int l = 0; l < o.levels; ++l) {
        std::vector<Corners> next;
        for (const Corners& t : layout) {
          auto sum = [&](int i, int j) { return Weights{t[i][0] + t[j][0], t[i][1] + t[j][1], t[i][2] + t[j][2]}; };
          const Weights a = sum(0, 0), b = sum(1, 1), c = sum(2, 2), ab = sum(0, 1), bc = sum(1, 2), ca = sum(2, 0);
          next.insert(next.end(), {Corners{a, ab, ca}, Corners{ab, b, bc}, Corners{ca, bc, c}, Corners{bc, ca, ab}});
        }
        layout.swap(next);
      }
      const int unit = 1 << o.levels;
      size_t mismatches = 0;
      for (size_t f = 0; f < m.triangles.size(); ++f) {
        Triangle corners = m.triangles[f];
        if (closed && flipped.count(f)) std::swap(corners[1], corners[2]);
        std::map<Weights, uint32_t> vertex_at;
        std::set<uint32_t> vertices;
        for (size_t c = 0; c < k; ++c)
          for (int j = 0; j < 3; ++j) {
            const Weights& w = layout[c][size_t(j)];
            const uint32_t v = r.mesh.triangles[f * k + c][size_t(j)];
            const auto [it, fresh] = vertex_at.emplace(w, v);
            if (fresh) vertices.insert(v);
            mismatches += it->second != v;
            for (int i = 0; i < 3; ++i)
              if (w[size_t(i)] == unit) mismatches += r.original_vertex.at(v) != corners[size_t(i)];
          }
        mismatches += vertices.size() != vertex_at.size();  // one vertex per point
      }
      EXPECT_EQ(mismatches, 0u);
    }
  }
}

// Values per triangle corner (texture coordinates) are linear over each input triangle. On a
// flat regular patch neither scheme moves a vertex off its place away from the border, so
// u = x, v = y there; a seam (every odd triangle's u moved by 10) stays on the input
// triangles' edges; a triangle the orientation repair turns back gives what it would have
// unturned; the Smoother carries them as smooth_mesh does; bad values are named.
TEST(SmoothCornerAttributes, LinearOverEachInputTriangleAndSeamsStay) {
  TriMesh m = flat_patch(8, 7);
  std::vector<float> uv, extra;
  for (size_t f = 0; f < m.triangles.size(); ++f)
    for (uint32_t v : m.triangles[f]) {
      uv.insert(uv.end(), {float(m.positions[v].x + 10 * double(f % 2)), float(m.positions[v].y)});
      extra.push_back(float(f));
    }
  m.corner_attributes = {{"uv", 2, uv}, {"face", 1, extra}};
  TriMesh turned = m;  // one triangle (and its corners' values) the other way round
  const size_t t = 11;
  std::swap(turned.triangles[t][1], turned.triangles[t][2]);
  for (auto& a : turned.corner_attributes)
    for (int j = 0; j < a.components; ++j)
      std::swap(a.values[size_t((3 * t + 1) * size_t(a.components) + size_t(j))],
                a.values[size_t((3 * t + 2) * size_t(a.components) + size_t(j))]);
  for (const SmoothOptions& o : {loop(2, true), butterfly(2)}) {
    const SmoothResult r = smooth_mesh(m, o);
    ASSERT_EQ(r.mesh.corner_attributes.size(), 2u);
    const VertexAttribute& u = r.mesh.corner_attributes[0];
    ASSERT_EQ(u.name, "uv");
    ASSERT_EQ(u.values.size(), 6 * r.mesh.triangles.size());
    const size_t k = 16;
    size_t checked = 0;
    for (size_t f = 0; f < r.mesh.triangles.size(); ++f)
      for (size_t c = 0; c < 3; ++c) {
        const Vec3& p = r.mesh.positions[r.mesh.triangles[f][c]];
        const float su = u.values[6 * f + 2 * c], sv = u.values[6 * f + 2 * c + 1];
        EXPECT_EQ(std::floor(su / 10), double((f / k) % 2));  // the seam: the parent's island
        EXPECT_EQ(r.mesh.corner_attributes[1].values[3 * f + c], float(f / k));
        if (p.x > 2.1 && p.x < 5.4 && p.y > 1.8 && p.y < 3.4) {
          EXPECT_NEAR(su - 10 * double((f / k) % 2), p.x, 1e-5);
          EXPECT_NEAR(sv, p.y, 1e-5);
          ++checked;
        }
      }
    EXPECT_GT(checked, r.mesh.triangles.size() / 5);
    const SmoothResult back = smooth_mesh(turned, o);
    EXPECT_EQ(back.stats.reoriented_triangles, 1u);
    EXPECT_EQ(back.mesh.triangles, r.mesh.triangles);
    EXPECT_EQ(back.mesh.corner_attributes[0].values, u.values);
    EXPECT_EQ(back.mesh.corner_attributes[1].values, r.mesh.corner_attributes[1].values);
    const Smoother smoother(m, o);
    EXPECT_EQ(smoother.evaluate(m.positions, {}).mesh.corner_attributes[0].values, u.values);
  }
  TriMesh bad = m;
  bad.corner_attributes[0].values.pop_back();
  EXPECT_NE(message_of([&] { smooth_mesh(bad, loop(1)); }).find("corner attribute 'uv' has 503 values, not 2 for each of the 3 x 84 triangle corners"),
            std::string::npos);
  bad = m;
  bad.corner_attributes[1].values[7] = std::nanf("");
  EXPECT_NE(message_of([&] { smooth_mesh(bad, butterfly(1)); }).find("corner attribute 'face' of triangle 2 is nan"),
            std::string::npos);
}

TEST(SmoothInput, BadMeshesGiveClearErrors) {
  const TriMesh tet = [] {
    TriMesh m;
    m.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
    m.triangles = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};
    return m;
  }();
  for (const SmoothOptions& o : {loop(1, true), butterfly(1)}) {
    TriMesh m;
    EXPECT_EQ(status_of([&] { smooth_mesh(m, o); }), Status::InvalidInput);  // empty
    m = tet;
    m.triangles[2] = {0, 3, 7};
    EXPECT_NE(message_of([&] { smooth_mesh(m, o); }).find("triangles[2] refers to vertex 7"), std::string::npos);
    m = tet;
    m.triangles[1] = {0, 1, 1};
    EXPECT_NE(message_of([&] { smooth_mesh(m, o); }).find("repeats a vertex"), std::string::npos);
    m = tet;
    m.positions[3].y = std::nan("");
    EXPECT_NE(message_of([&] { smooth_mesh(m, o); }).find("positions[3] is not finite"), std::string::npos);
    // Finite but near DBL_MAX: the schemes' sums overflowed to infinity (found by fuzzing).
    for (const double big : {1e300, -std::numeric_limits<double>::max()}) {
      m = tet;
      m.positions[2].z = big;
      EXPECT_EQ(status_of([&] { smooth_mesh(m, o); }), Status::InvalidInput);
      EXPECT_NE(message_of([&] { smooth_mesh(m, o); }).find("positions[2] = ("), std::string::npos);
      EXPECT_NE(message_of([&] { smooth_mesh(m, o); }).find("is too large to smooth"), std::string::npos);
    }
    m = tet;
    m.positions[2].z = kMaxSmoothCoordinate;  // the limit itself: positions and normals stay finite
    ASSERT_EQ(status_of([&] { smooth_mesh(m, o); }), Status::Ok);
    const TriMesh big = smooth_mesh(m, o).mesh;
    for (const Vec3& p : big.positions) EXPECT_TRUE(is_finite(p));
    for (const Vec3& n : big.normals) EXPECT_TRUE(is_finite(n));  // (0 where the sliver's tangents vanish in rounding)
    // A fin: a third triangle on edge (0, 1). Butterfly refuses it; Loop keeps it sharp
    // (SmoothInput.LoopKeepsNonManifoldEdgesSharp).
    const bool is_loop = o.scheme == SmoothScheme::Loop;
    m = tet;
    m.positions.push_back({0.5, -1, 0});
    m.triangles.push_back({0, 1, 4});
    EXPECT_EQ(status_of([&] { smooth_mesh(m, o); }), is_loop ? Status::Ok : Status::InvalidInput);
    if (!is_loop) {
      EXPECT_NE(message_of([&] { smooth_mesh(m, o); }).find("edge (0, 1) is shared by 3 triangles (non-manifold); the "
                                                             "butterfly scheme needs"),
                std::string::npos);
    }
    // Two tetrahedra sharing vertex 0 only: vertex 0 joins two fans.
    m = tet;
    for (int i = 1; i < 4; ++i) m.positions.push_back(m.positions[size_t(i)] * -1.0);
    for (auto t : tet.triangles) {
      for (auto& v : t)
        if (v != 0) v += 3;
      m.triangles.push_back(t);
    }
    EXPECT_EQ(status_of([&] { smooth_mesh(m, o); }), is_loop ? Status::Ok : Status::InvalidInput);
    if (!is_loop) {
      EXPECT_NE(message_of([&] { smooth_mesh(m, o); }).find("vertex 0 joins separate fans"), std::string::npos);
    }
    // The same triangle twice, facing both ways (a two-sided "pillow").
    m = TriMesh{};
    m.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
    m.triangles = {{0, 1, 2}, {0, 2, 1}};
    EXPECT_NE(message_of([&] { smooth_mesh(m, o); }).find("use the same three vertices"), std::string::npos);
    // A Moebius strip of 5 quads.
    m = TriMesh{};
    const int n = 5;
    for (int i = 0; i < n; ++i) {
      const double a = 2 * kPi * i / n, w = 0.3 * std::cos(a / 2), h = 0.3 * std::sin(a / 2);
      m.positions.push_back({(1 + w) * std::cos(a), (1 + w) * std::sin(a), h});
      m.positions.push_back({(1 - w) * std::cos(a), (1 - w) * std::sin(a), -h});
    }
    for (int i = 0; i < n; ++i) {
      uint32_t a = uint32_t(2 * i), b = a + 1, c = uint32_t(2 * ((i + 1) % n)), d = c + 1;
      if (i == n - 1) std::swap(c, d);  // the half twist
      m.triangles.push_back({a, c, b});
      m.triangles.push_back({b, c, d});
    }
    EXPECT_NE(message_of([&] { smooth_mesh(m, o); }).find("non-orientable"), std::string::npos);
    // Attributes of the wrong size or with NaN.
    m = tet;
    m.attributes = {{"v", 3, std::vector<float>(11, 0.f)}};
    EXPECT_NE(message_of([&] { smooth_mesh(m, o); }).find("attribute 'v'"), std::string::npos);
    m.attributes = {{"v", 1, {0.f, 1.f, std::nanf(""), 2.f}}};
    EXPECT_NE(message_of([&] { smooth_mesh(m, o); }).find("attribute 'v' of vertex 2 is not finite"),
              std::string::npos);
    m.attributes = {{"v", 1, {0.f, 1.f, 3e38f, 2.f}}};
    EXPECT_NE(message_of([&] { smooth_mesh(m, o); }).find("attribute 'v' of vertex 2 is 3"), std::string::npos);
    // Zero-area triangles with distinct corners are fine.
    m = tet;
    m.positions[3] = {0.5, 0.5, 0};
    EXPECT_EQ(status_of([&] { smooth_mesh(m, o); }), Status::Ok);
  }
}

// Loop smooths non-manifold meshes as OpenSubdiv (and Blender's Subdivision Surface) does: an
// edge in more than two triangles is an infinitely sharp crease. A book of three pages at
// uneven angles keeps its spine on the z axis (a smooth rule would pull it towards the pages),
// the refined spine is still every page's edge, and the result does not depend on the thread
// count; a pinched vertex and closed parts sharing an edge are smoothed too.
TEST(SmoothInput, LoopKeepsNonManifoldEdgesSharp) {
  const std::vector<double> angles = {0.0, 1.5707963, 3.4906585};
  const TriMesh book = test::book_mesh(angles);
  for (bool limit : {true, false}) {
    const SmoothResult r = smooth_mesh(book, loop(2, limit));
    EXPECT_EQ(r.stats.nonmanifold_edges, 4u);
    EXPECT_EQ(r.stats.nonmanifold_vertices, 5u);
    const TopologyReport t = topology_report(r.mesh);
    EXPECT_EQ(t.nonmanifold_edges, 16u);  // the spine's 4 edges, halved twice
    EXPECT_EQ(t.triangles, 16 * book.triangles.size());
    std::map<std::pair<uint32_t, uint32_t>, int> count = test::edge_counts(r.mesh.triangles);
    size_t spine = 0;
    for (const auto& [e, n] : count)
      if (n > 2) {
        ++spine;
        for (uint32_t v : {e.first, e.second}) {
          EXPECT_NEAR(r.mesh.positions[v].x, 0.0, 1e-12) << v;
          EXPECT_NEAR(r.mesh.positions[v].y, 0.0, 1e-12) << v;
          EXPECT_EQ(n, 3);
        }
      }
    EXPECT_EQ(spine, 16u);
    // The pages stay flat: every vertex on one page's half-plane (a smooth rule at the spine
    // would bend each page towards the others).
    for (const Vec3& p : r.mesh.positions) {
      double off = 1e9;
      for (double a : angles)
        if (p.x * std::cos(a) + p.y * std::sin(a) >= -1e-12)
          off = std::min(off, std::abs(-p.x * std::sin(a) + p.y * std::cos(a)));
      EXPECT_LT(off, 1e-12) << p.x << " " << p.y << " " << p.z;
    }
    SmoothOptions one = loop(2, limit);
    one.threads = 1;
    const SmoothResult serial = smooth_mesh(book, one);
    ASSERT_EQ(serial.mesh.positions.size(), r.mesh.positions.size());
    for (size_t i = 0; i < r.mesh.positions.size(); ++i) ASSERT_EQ(serial.mesh.positions[i], r.mesh.positions[i]);
    EXPECT_EQ(serial.mesh.triangles, r.mesh.triangles);
  }
  // Closed tetrahedra sharing an edge (no boundary: the limit is OpenSubdiv's), and a pinched
  // vertex: smoothed, the sharing kept.
  const SmoothResult two = smooth_mesh(test::tetrahedra_sharing_an_edge(), loop(1, true));
  EXPECT_EQ(two.stats.nonmanifold_edges, 1u);
  EXPECT_EQ(topology_report(two.mesh).nonmanifold_edges, 2u);
  for (const Vec3& p : two.mesh.positions) EXPECT_TRUE(is_finite(p));
  for (const Vec3& n : two.mesh.normals) EXPECT_NEAR(norm(n), 1.0, 1e-9);
  // Butterfly refuses them, pointing to Loop.
  SmoothOptions bf = butterfly(1);
  EXPECT_NE(message_of([&] { smooth_mesh(book, bf); }).find("(the Loop scheme smooths such meshes)"), std::string::npos);
}

TEST(SmoothInput, BadOptionsGiveClearErrors) {
  const TriMesh m = icosphere_mesh(2);  // 320 triangles
  SmoothOptions o;
  o.levels = -1;
  EXPECT_EQ(status_of([&] { smooth_mesh(m, o); }), Status::InvalidArgument);
  o.levels = kMaxSmoothLevels + 1;
  EXPECT_NE(message_of([&] { smooth_mesh(m, o); }).find("levels must be in [0, 10]"), std::string::npos);
  // 320 * 4^10 = 335 544 320 > 2^25: refused before any work, naming the limit.
  o.levels = 10;
  EXPECT_EQ(status_of([&] { smooth_mesh(m, o); }), Status::LimitExceeded);
  EXPECT_NE(message_of([&] { smooth_mesh(m, o); }).find("335544320 triangles, more than max_triangles = 33554432"),
            std::string::npos);
  o.levels = 2;
  o.max_triangles = 320 * 16 - 1;
  EXPECT_EQ(status_of([&] { smooth_mesh(m, o); }), Status::LimitExceeded);
  o.max_triangles = 320 * 16;
  EXPECT_EQ(status_of([&] { smooth_mesh(m, o); }), Status::Ok);
  o.max_triangles = 0;
  EXPECT_EQ(status_of([&] { smooth_mesh(m, o); }), Status::InvalidArgument);
  o = SmoothOptions{};
  o.threads = -2;
  EXPECT_EQ(status_of([&] { smooth_mesh(m, o); }), Status::InvalidArgument);
  o = SmoothOptions{};
  o.scheme = static_cast<SmoothScheme>(7);
  EXPECT_EQ(status_of([&] { smooth_mesh(m, o); }), Status::InvalidArgument);
  o = SmoothOptions{};
  o.boundary = static_cast<BoundaryRule>(2);
  EXPECT_EQ(status_of([&] { smooth_mesh(m, o); }), Status::InvalidArgument);
  o = SmoothOptions{};
  o.creases = {{0, 1}};
  EXPECT_NE(message_of([&] { smooth_mesh(m, o); }).find("creases[0] = (0, 1) is not an edge"), std::string::npos);
  o.creases = {{m.triangles[0][0], m.triangles[0][1], -1.0f}};
  EXPECT_NE(message_of([&] { smooth_mesh(m, o); }).find("creases[0].sharpness"), std::string::npos);
  o.creases = {{m.triangles[0][0], m.triangles[0][1]}};
  EXPECT_EQ(status_of([&] { smooth_mesh(m, o); }), Status::Ok);
  o.scheme = SmoothScheme::Butterfly;
  EXPECT_NE(message_of([&] { smooth_mesh(m, o); }).find("creases are supported by the Loop scheme only"),
            std::string::npos);
}

// ---- threads, progress ---------------------------------------------------------------------

TEST(Smooth, ThreadCountDoesNotChangeTheResult) {
  TriMesh m = torus_mesh(1, 0.4, 30, 14);
  std::vector<float> v;
  for (const auto& p : m.positions) v.insert(v.end(), {float(p.x), float(p.y * p.y), float(p.z)});
  m.attributes = {{"velocity", 3, v}, {"w", 1, std::vector<float>(m.positions.size(), 2.f)}};
  for (SmoothOptions o : {loop(2, true), butterfly(2)}) {
    o.threads = 1;
    const SmoothResult one = smooth_mesh(m, o);
    o.threads = 4;
    const SmoothResult four = smooth_mesh(m, o);
    EXPECT_EQ(one.mesh.positions, four.mesh.positions);
    EXPECT_EQ(one.mesh.normals, four.mesh.normals);
    EXPECT_EQ(one.mesh.triangles, four.mesh.triangles);
    EXPECT_EQ(one.mesh.attributes[0].values, four.mesh.attributes[0].values);
    EXPECT_EQ(one.mesh.attributes[1].values, four.mesh.attributes[1].values);
  }
}

TEST(Smooth, ProgressReportsStagesAndCancels) {
  const TriMesh m = icosphere_mesh(3);
  for (const SmoothOptions& base : {loop(2, true), butterfly(2)}) {
    SmoothOptions o = base;
    std::vector<std::string> stages;
    double last = -1;
    bool monotone = true;
    o.progress = [&](std::string_view s, double f) {
      if (stages.empty() || stages.back() != s) stages.emplace_back(s);
      monotone &= f >= last;
      last = f;
      return true;
    };
    smooth_mesh(m, o);
    EXPECT_TRUE(monotone);
    EXPECT_DOUBLE_EQ(last, 1.0);
    EXPECT_GE(stages.size(), 4u);
    int calls = 0;
    o.progress = [&](std::string_view, double) { return ++calls < 3; };
    EXPECT_EQ(status_of([&] { smooth_mesh(m, o); }), Status::Cancelled);
  }
}

// ---- real meshes (shared data) --------------------------------------------------------------

TEST(SmoothSharedData, BunnyWithHolesAndUnusedVerticesAndGenusOneRockerArm) {
  PM_REQUIRE_DATA(bunny_path, "meshes/bunny.obj");
  PM_REQUIRE_DATA(rocker_path, "meshes/rocker_arm.obj");
  const TriMesh bunny = read_mesh(bunny_path);
  const TopologyReport before = topology_report(bunny);
  for (const SmoothOptions& o : {loop(1, true), butterfly(1)}) {
    const SmoothResult r = smooth_mesh(bunny, o);
    EXPECT_EQ(r.stats.dropped_vertices, 1113u);  // DATA.md: 1113 unreferenced vertices
    EXPECT_EQ(r.stats.reoriented_triangles, 0u);
    EXPECT_EQ(r.mesh.triangles.size(), 4 * bunny.triangles.size());
    EXPECT_EQ(r.mesh.positions.size(), before.vertices_used + before.edges);
    const TopologyReport t = topology_report(r.mesh);
    EXPECT_EQ(t.boundary_loops, 5u);
    EXPECT_EQ(t.euler_characteristic, before.euler_characteristic);
    EXPECT_TRUE(t.manifold);
    EXPECT_TRUE(t.consistently_oriented);
    EXPECT_EQ(t.vertices_used, t.vertices);
    if (o.scheme == SmoothScheme::Butterfly) {
      for (size_t i = 0; i < r.original_vertex.size(); ++i)
        ASSERT_EQ(r.mesh.positions[i], bunny.positions[r.original_vertex[i]]);
    }
  }
  const TriMesh rocker = read_mesh(rocker_path);
  const SmoothResult r = smooth_mesh(rocker, loop(1, true));
  const TopologyReport t = topology_report(r.mesh);
  EXPECT_TRUE(t.closed);
  EXPECT_TRUE(t.outward);
  ASSERT_EQ(t.per_component.size(), 1u);
  EXPECT_EQ(t.per_component[0].genus, 1);
  // Limit normals agree with the surface: outward like its faces.
  double agree = 0;
  for (const auto& tri : r.mesh.triangles) agree += dot(face_normal(r.mesh, tri), r.mesh.normals[tri[0]]);
  EXPECT_GT(agree / double(r.mesh.triangles.size()), 0.95);
}

TEST(SmoothInput, TinyMeshesAndSeveralComponents) {
  TriMesh one;
  one.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  one.triangles = {{0, 1, 2}};
  TriMesh two = one;
  two.positions.push_back({1, 1, 0.5});
  two.triangles.push_back({1, 3, 2});
  TriMesh both = icosphere_mesh(0);  // a closed component and an open one, side by side
  for (const auto& p : two.positions) both.positions.push_back(p + Vec3{3, 0, 0});
  for (const auto& t : two.triangles) both.triangles.push_back({t[0] + 12, t[1] + 12, t[2] + 12});
  for (const TriMesh* m : {&one, &two, &both})
    for (const SmoothOptions& base : {loop(0, true), loop(3, true), loop(3, false), butterfly(3)})
      for (BoundaryRule rule : {BoundaryRule::EdgeAndCorner, BoundaryRule::EdgeOnly}) {
        SmoothOptions o = base;
        o.boundary = rule;
        const SmoothResult r = smooth_mesh(*m, o);
        EXPECT_EQ(r.mesh.triangles.size(), m->triangles.size() << (2 * o.levels));
        const TopologyReport t = topology_report(r.mesh);
        EXPECT_TRUE(t.manifold);
        EXPECT_TRUE(t.consistently_oriented);
        EXPECT_EQ(t.components, topology_report(*m).components);
        for (const auto& p : r.mesh.positions) ASSERT_TRUE(is_finite(p));
        for (const auto& n : r.mesh.normals) ASSERT_NEAR(norm(n), 1.0, 1e-9);
      }
  // A single triangle with pinned corners stays the same flat triangle (Loop, limit).
  const SmoothResult r = smooth_mesh(one, loop(2, true));
  for (const auto& p : r.mesh.positions) {
    EXPECT_EQ(p.z, 0);
    EXPECT_GE(p.x, -1e-15);
    EXPECT_GE(p.y, -1e-15);
    EXPECT_LE(p.x + p.y, 1 + 1e-15);
  }
}
