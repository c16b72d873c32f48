#include "particlemesh/mesh/edges.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <set>
#include <thread>
#include <utility>

#include "particlemesh/core/error.h"
#include "particlemesh/sample/shapes.h"
#include "particlemesh/surface/triangulate.h"

using namespace particlemesh;

namespace {
std::pair<uint32_t, uint32_t> key(uint32_t a, uint32_t b) { return {std::min(a, b), std::max(a, b)}; }

/// The edges as a brute-force set, and a check of every corner's edge against it.
void expect_edges_of(const std::vector<Triangle>& tris, const MeshEdges& e) {
  std::set<std::pair<uint32_t, uint32_t>> want;
  for (const Triangle& t : tris)
    for (int k = 0; k < 3; ++k) want.insert(key(t[k], t[(k + 1) % 3]));
  ASSERT_EQ(e.edges.size(), want.size());
  size_t i = 0;
  for (const auto& [a, b] : want) {  // each once, a < b, ordered by a then b
    EXPECT_EQ(e.edges[i][0], a);
    EXPECT_EQ(e.edges[i][1], b);
    ++i;
  }
  ASSERT_EQ(e.corner_edges.size(), 3 * tris.size());
  for (size_t t = 0; t < tris.size(); ++t)
    for (int k = 0; k < 3; ++k) {
      const auto& edge = e.edges.at(e.corner_edges[3 * t + size_t(k)]);
      EXPECT_EQ(std::make_pair(edge[0], edge[1]), key(tris[t][k], tris[t][(k + 1) % 3]));
    }
}
}  // namespace

TEST(MeshEdges, ClosedSurfaceHasThreeHalvesAsManyEdgesAsTriangles) {
  const TriMesh m = icosphere_mesh(4);
  const MeshEdges e = mesh_edges(m.triangles, m.positions.size());
  EXPECT_EQ(2 * e.edges.size(), 3 * m.triangles.size());
  expect_edges_of(m.triangles, e);
}

TEST(MeshEdges, NonManifoldTrianglesAndAnyThreadCount) {
  // The seed's raw triangles: overlapping pairs, edges of three and more triangles.
  const TriangulateResult raw = triangulate_raw(fibonacci_sphere(3000));
  const MeshEdges one = mesh_edges(raw.mesh.triangles, raw.mesh.positions.size(), 1);
  expect_edges_of(raw.mesh.triangles, one);
  // The vertices are cut into one range per thread, each range's corners placed by its own
  // task: every count gives the brute-force edges, the same numbers as one thread.
  for (int threads : {0, 2, 3}) {
    const MeshEdges some = mesh_edges(raw.mesh.triangles, raw.mesh.positions.size(), threads);
    expect_edges_of(raw.mesh.triangles, some);
    EXPECT_EQ(some.edges, one.edges);
    EXPECT_EQ(some.corner_edges, one.corner_edges);
  }
  // Fewer vertices than threads: some ranges hold none.
  const std::vector<Triangle> one_triangle{{2, 0, 1}};
  expect_edges_of(one_triangle, mesh_edges(one_triangle, 3, 0));
  EXPECT_TRUE(mesh_edges({}, 5).edges.empty());
}

TEST(MeshEdges, BadTrianglesAreNamed) {
  auto message = [](const std::vector<Triangle>& t, size_t n) {
    try {
      mesh_edges(t, n);
    } catch (const Error& e) {
      EXPECT_EQ(e.status(), Status::InvalidArgument);
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_NE(message({{0, 1, 2}, {1, 2, 7}}, 5).find("triangle 1 has vertex index 7"), std::string::npos);
  EXPECT_NE(message({{0, 1, 1}}, 5).find("triangle 0 repeats a vertex"), std::string::npos);
  // Checked in parallel blocks: the first bad triangle is named whichever block finds one first.
  std::vector<Triangle> many(100000, Triangle{0, 1, 2});
  many[90000] = {0, 1, 9};
  many[70001] = {4, 4, 2};
  many[20000] = {0, 7, 2};
  for (int threads : {1, 2, 3}) {
    try {
      mesh_edges(many, 5, threads);
      ADD_FAILURE() << "no error at " << threads << " threads";
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find("triangle 20000 has vertex index 7"), std::string::npos) << e.what();
    }
  }
}

TEST(MeshEdges, VerticesWithManyCornersAndRepeatedTriangles) {
  // A fan of 60 triangles about vertex 0 (its corners sorted the long way), the same fan
  // again reversed, and a strip whose vertices have a handful each.
  std::vector<Triangle> tris;
  for (uint32_t i = 1; i <= 60; ++i) tris.push_back({0, i, i % 60 + 1});
  for (uint32_t i = 1; i <= 60; ++i) tris.push_back({0, i % 60 + 1, i});
  for (uint32_t i = 61; i < 200; ++i) tris.push_back({i, i + 1, i + 2});
  for (int threads : {1, 2, 3}) expect_edges_of(tris, mesh_edges(tris, 202, threads));
}

TEST(MeshEdges, CallsAtOnceAndOfEverySizeReuseTheKeptSlots) {
  // The numbering's working memory is kept from one call to the next: a smaller mesh after a
  // larger one (the kept block reused), a larger one after (a block of its own), calls from
  // several threads at once (one of them gets the kept block), and an empty one between.
  const TriMesh big = icosphere_mesh(5), small = icosphere_mesh(2);
  const MeshEdges big_alone = mesh_edges(big.triangles, big.positions.size());
  const MeshEdges small_alone = mesh_edges(small.triangles, small.positions.size());
  expect_edges_of(big.triangles, big_alone);
  expect_edges_of(small.triangles, small_alone);
  EXPECT_TRUE(mesh_edges({}, 3).edges.empty());
  std::vector<MeshEdges> got(8);
  std::vector<std::thread> threads;
  for (size_t i = 0; i < got.size(); ++i)
    threads.emplace_back([&, i] {
      const TriMesh& m = i % 2 ? big : small;
      for (int round = 0; round < 3; ++round) got[i] = mesh_edges(m.triangles, m.positions.size(), 1);
    });
  for (std::thread& t : threads) t.join();
  for (size_t i = 0; i < got.size(); ++i) {
    const MeshEdges& want = i % 2 ? big_alone : small_alone;
    EXPECT_EQ(got[i].edges, want.edges) << i;
    EXPECT_EQ(got[i].corner_edges, want.corner_edges) << i;
  }
}
