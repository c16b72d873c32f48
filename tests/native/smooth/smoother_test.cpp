// The refine-once Smoother (smooth/smoother.h): evaluate() gives what smooth_mesh() gives for
// the same triangles and the new positions, byte for byte, whatever the scheme, options,
// attributes, thread count; it refuses what smooth_mesh refuses.
#include "particlemesh/smooth/smoother.h"

#include <gtest/gtest.h>
#include <tbb/task_arena.h>

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

template <class T>
bool same_bytes(const std::vector<T>& a, const std::vector<T>& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(T)) == 0;
}

void expect_identical(const SmoothResult& got, const SmoothResult& want, const std::string& what) {
  SCOPED_TRACE(what);
  EXPECT_TRUE(same_bytes(got.mesh.positions, want.mesh.positions));
  EXPECT_TRUE(same_bytes(got.mesh.normals, want.mesh.normals));
  EXPECT_EQ(got.mesh.triangles, want.mesh.triangles);
  EXPECT_EQ(got.original_vertex, want.original_vertex);
  ASSERT_EQ(got.mesh.attributes.size(), want.mesh.attributes.size());
  for (size_t i = 0; i < got.mesh.attributes.size(); ++i) {
    EXPECT_EQ(got.mesh.attributes[i].name, want.mesh.attributes[i].name);
    EXPECT_EQ(got.mesh.attributes[i].components, want.mesh.attributes[i].components);
    EXPECT_TRUE(same_bytes(got.mesh.attributes[i].values, want.mesh.attributes[i].values));
  }
  EXPECT_EQ(got.stats.limit, want.stats.limit);
  EXPECT_EQ(got.stats.triangles, want.stats.triangles);
}

/// A closed sphere with irregular valences (random edge flips) and jitter.
TriMesh bumpy_sphere(uint64_t seed) {
  TriMesh m = icosphere_mesh(2);
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0.9, 1.1);
  for (auto& p : m.positions) p = p * u(rng);
  // Flip a few edges where both ends keep valence >= 4: valences 4..8.
  for (int k = 0; k < 12; ++k) {
    const size_t f = rng() % m.triangles.size();
    const uint32_t a = m.triangles[f][0], b = m.triangles[f][1];
    for (size_t g = 0; g < m.triangles.size(); ++g) {
      const Triangle t = m.triangles[g];
      for (int c = 0; c < 3; ++c)
        if (t[size_t(c)] == b && t[size_t((c + 1) % 3)] == a) {
          const uint32_t x = m.triangles[f][2], y = t[size_t((c + 2) % 3)];
          int va = 0, vb = 0;
          bool exists = false;
          for (const Triangle& q : m.triangles) {
            va += (q[0] == a) + (q[1] == a) + (q[2] == a);
            vb += (q[0] == b) + (q[1] == b) + (q[2] == b);
            for (int i = 0; i < 3; ++i)
              exists = exists || (q[size_t(i)] == x && q[size_t((i + 1) % 3)] == y) ||
                       (q[size_t(i)] == y && q[size_t((i + 1) % 3)] == x);
          }
          if (va > 4 && vb > 4 && !exists) {
            m.triangles[f] = {a, y, x};
            m.triangles[g] = {y, b, x};
          }
          g = m.triangles.size();
          break;
        }
    }
  }
  return m;
}

/// A bumpy open patch: boundary edges and corners.
TriMesh patch() {
  TriMesh m;
  const int nx = 9, ny = 7;
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) m.positions.push_back({i + 0.5 * (j % 2), j * 0.866, 0.3 * std::sin(1.7 * (i + nx * j))});
  auto id = [&](int i, int j) { return uint32_t(j * nx + i); };
  for (int j = 0; j + 1 < ny; ++j)
    for (int i = 0; i + 1 < nx; ++i) {
      m.triangles.push_back({id(i, j), id(i + 1, j), id(i, j + 1)});
      m.triangles.push_back({id(i + 1, j), id(i + 1, j + 1), id(i, j + 1)});
    }
  return m;
}

std::vector<VertexAttribute> attributes_for(size_t n, uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<float> u(-1, 1);
  VertexAttribute velocity{"velocity", 3, {}}, heat{"heat", 1, {}};
  for (size_t i = 0; i < n; ++i) {
    for (int c = 0; c < 3; ++c) velocity.values.push_back(u(rng));
    heat.values.push_back(u(rng));
  }
  return {velocity, heat};
}

/// The positions moved: a deterministic wobble, as a frame of an animation.
std::vector<Vec3> moved(const std::vector<Vec3>& p, double t) {
  std::vector<Vec3> out(p);
  for (size_t i = 0; i < out.size(); ++i)
    out[i] = out[i] * (1.0 + 0.05 * std::sin(t + 0.37 * double(i))) + Vec3{0.1 * t, 0, -0.05 * t};
  return out;
}

SmoothOptions levels(int n) {
  SmoothOptions o;
  o.levels = n;
  return o;
}

TriMesh with(const TriMesh& m, std::vector<Vec3> positions, std::vector<VertexAttribute> attributes) {
  TriMesh out = m;
  out.positions = std::move(positions);
  out.attributes = std::move(attributes);
  out.normals.clear();
  return out;
}

}  // namespace

TEST(Smoother, EvaluateIsSmoothMeshBitForBit) {
  struct Case {
    std::string name;
    TriMesh mesh;
    SmoothOptions options;
  };
  std::vector<Case> cases;
  const TriMesh sphere = bumpy_sphere(3), open = patch();
  for (int levels : {0, 1, 2})
    for (bool limit : {true, false}) {
      SmoothOptions o;
      o.levels = levels;
      o.limit = limit;
      cases.push_back({"closed sphere, level " + std::to_string(levels) + (limit ? ", limit" : ""), sphere, o});
      cases.push_back({"open patch, level " + std::to_string(levels) + (limit ? ", limit" : ""), open, o});
    }
  SmoothOptions creased;
  creased.levels = 2;
  creased.creases = {{sphere.triangles[0][0], sphere.triangles[0][1]}, {sphere.triangles[5][1], sphere.triangles[5][2], 1.5f}};
  cases.push_back({"closed sphere with creases", sphere, creased});
  SmoothOptions edge_only;
  edge_only.levels = 2;
  edge_only.boundary = BoundaryRule::EdgeOnly;
  cases.push_back({"open patch, edge-only boundary", open, edge_only});
  SmoothOptions bf;
  bf.scheme = SmoothScheme::Butterfly;
  bf.levels = 2;
  cases.push_back({"butterfly", sphere, bf});
  // Non-manifold meshes (Loop keeps their edges sharp): a book's spine, closed parts sharing an
  // edge (no boundary, so the limit is OpenSubdiv's after an attempt at the rings).
  cases.push_back({"a book of three pages", test::book_mesh({0.0, 1.5707963, 3.4906585}), levels(2)});
  cases.push_back({"tetrahedra sharing an edge", test::tetrahedra_sharing_an_edge(), levels(2)});
  TriMesh unused = sphere;  // unreferenced vertices are dropped (and may hold anything)
  unused.positions.push_back({std::numeric_limits<double>::quiet_NaN(), 0, 0});
  cases.push_back({"closed sphere with an unused vertex", unused, levels(2)});

  for (const Case& c : cases) {
    const std::vector<VertexAttribute> attrs0 = attributes_for(c.mesh.positions.size(), 1);
    const Smoother smoother(with(c.mesh, c.mesh.positions, attrs0), c.options);
    EXPECT_TRUE(smoother.matches(c.mesh.triangles, c.mesh.positions.size()));
    for (double t : {0.0, 0.7, 2.1}) {
      std::vector<Vec3> p = moved(c.mesh.positions, t);
      if (c.name.find("unused") != std::string::npos) p.back() = {1e300, 0, 0};
      const std::vector<VertexAttribute> attrs = attributes_for(c.mesh.positions.size(), uint64_t(10 * t) + 2);
      const SmoothResult want = smooth_mesh(with(c.mesh, p, attrs), c.options);
      expect_identical(smoother.evaluate(p, attrs), want, c.name + ", t = " + std::to_string(t));
      // Without attributes too.
      expect_identical(smoother.evaluate(p), smooth_mesh(with(c.mesh, p, {}), c.options), c.name + ", no attributes");
    }
  }
}

TEST(Smoother, TheThreadCountDoesNotChangeTheResult) {
  const TriMesh sphere = bumpy_sphere(7);
  SmoothOptions o;
  o.levels = 3;
  const Smoother smoother(sphere, o);
  const std::vector<Vec3> p = moved(sphere.positions, 1.3);
  const std::vector<VertexAttribute> attrs = attributes_for(sphere.positions.size(), 4);
  tbb::task_arena one(1), all(tbb::this_task_arena::max_concurrency());
  const SmoothResult a = one.execute([&] { return smoother.evaluate(p, attrs); });
  const SmoothResult b = all.execute([&] { return smoother.evaluate(p, attrs); });
  expect_identical(a, b, "1 thread vs all");
}

TEST(Smoother, RepairedOrientationStillAgreesWhenTheSurfaceTurnsInsideOut) {
  // Sorted corners: the orientation is repaired and turned outward by the signed volume.
  // Mirrored positions turn that volume negative: smooth_mesh would then orient the other
  // way, and so must evaluate().
  TriMesh sorted = bumpy_sphere(5);
  for (auto& t : sorted.triangles) std::sort(t.begin(), t.end());
  SmoothOptions o;
  o.levels = 2;
  const Smoother smoother(sorted, o);
  std::vector<Vec3> mirrored = sorted.positions;
  for (auto& q : mirrored) q.x = -q.x;
  const SmoothResult want = smooth_mesh(with(sorted, mirrored, {}), o);
  EXPECT_GT(want.stats.reoriented_triangles, 0u);
  expect_identical(smoother.evaluate(mirrored), want, "mirrored");
  expect_identical(smoother.evaluate(sorted.positions), smooth_mesh(sorted, o), "as made");
}

TEST(Smoother, RefusesWhatSmoothMeshRefuses) {
  const TriMesh sphere = bumpy_sphere(9);
  const Smoother smoother(sphere, levels(1));
  std::string message;
  std::vector<Vec3> short_positions(sphere.positions.begin(), sphere.positions.end() - 1);
  EXPECT_EQ(status_of([&] { smoother.evaluate(short_positions); }, &message), Status::InvalidInput);
  EXPECT_NE(message.find(std::to_string(sphere.positions.size())), std::string::npos) << message;
  std::vector<Vec3> bad = sphere.positions;
  bad[7].y = std::numeric_limits<double>::infinity();
  EXPECT_EQ(status_of([&] { smoother.evaluate(bad); }, &message), Status::InvalidInput);
  EXPECT_NE(message.find("positions[7]"), std::string::npos) << message;
  std::vector<VertexAttribute> attrs = attributes_for(sphere.positions.size(), 1);
  attrs[1].values[3] = std::numeric_limits<float>::quiet_NaN();
  EXPECT_EQ(status_of([&] { smoother.evaluate(sphere.positions, attrs); }, &message), Status::InvalidInput);
  EXPECT_NE(message.find("'heat' of vertex 3"), std::string::npos) << message;
  attrs[1].values.pop_back();
  EXPECT_EQ(status_of([&] { smoother.evaluate(sphere.positions, attrs); }), Status::InvalidInput);
  // matches(): other triangles, or another vertex count.
  TriMesh other = sphere;
  std::swap(other.triangles[0], other.triangles[1]);
  EXPECT_FALSE(smoother.matches(other.triangles, other.positions.size()));
  EXPECT_FALSE(smoother.matches(sphere.triangles, sphere.positions.size() + 1));
  EXPECT_TRUE(smoother.matches(sphere.triangles, sphere.positions.size()));
  // Construction refuses what smooth_mesh refuses, with its status.
  TriMesh fin = sphere;
  fin.positions.push_back({5, 5, 5});
  fin.triangles.push_back({sphere.triangles[0][0], sphere.triangles[0][1], uint32_t(sphere.positions.size())});
  SmoothOptions bf;
  bf.scheme = SmoothScheme::Butterfly;
  EXPECT_EQ(status_of([&] { Smoother s(fin, bf); }), Status::InvalidInput);
  EXPECT_EQ(status_of([&] { Smoother s(fin); }), Status::Ok);  // Loop keeps the fin sharp
  EXPECT_EQ(status_of([&] { Smoother s(sphere, levels(11)); }), Status::InvalidArgument);
}
