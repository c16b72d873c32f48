#include "particlemesh/mesh/ray_crossings.h"

#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <tuple>
#include <vector>

#include "particlemesh/core/error.h"
#include "particlemesh/sample/shapes.h"

using namespace particlemesh;

namespace {

// The surface of the cube [-1, 1]^3, each face a k x k grid of squares cut along a diagonal
// (alternating), vertices welded: rays straight up from points on a grid of step 1 / (2k)
// pass exactly through its vertices, along its edges and along its side faces.
TriMesh grid_cube(int k) {
  TriMesh m;
  std::map<std::tuple<long, long, long>, uint32_t> at;
  auto vertex = [&](Vec3 p) {
    const auto key = std::make_tuple(std::lround(p.x * k), std::lround(p.y * k), std::lround(p.z * k));
    auto [it, fresh] = at.emplace(key, uint32_t(m.positions.size()));
    if (fresh) m.positions.push_back(p);
    return it->second;
  };
  for (int axis = 0; axis < 3; ++axis)
    for (double side : {-1.0, 1.0}) {
      auto point = [&](int i, int j) {
        double q[3];
        q[axis] = side, q[(axis + 1) % 3] = -1 + 2.0 * i / k, q[(axis + 2) % 3] = -1 + 2.0 * j / k;
        return vertex({q[0], q[1], q[2]});
      };
      for (int i = 0; i < k; ++i)
        for (int j = 0; j < k; ++j) {
          const uint32_t a = point(i, j), b = point(i + 1, j), c = point(i + 1, j + 1), d = point(i, j + 1);
          if ((i + j) % 2 == 0) m.triangles.push_back({a, b, c}), m.triangles.push_back({a, c, d});
          else m.triangles.push_back({a, b, d}), m.triangles.push_back({b, c, d});
        }
    }
  return m;
}

// The triangles `keep` selects, over their own vertices numbered in the whole mesh's order.
TriMesh part(const TriMesh& m, const std::vector<bool>& keep) {
  std::vector<uint32_t> id(m.positions.size(), UINT32_MAX);
  for (size_t f = 0; f < m.triangles.size(); ++f)
    if (keep[f])
      for (uint32_t v : m.triangles[f]) id[v] = 0;
  TriMesh out;
  for (size_t v = 0; v < id.size(); ++v)
    if (id[v] == 0) id[v] = uint32_t(out.positions.size()), out.positions.push_back(m.positions[v]);
  for (size_t f = 0; f < m.triangles.size(); ++f)
    if (keep[f]) out.triangles.push_back({id[m.triangles[f][0]], id[m.triangles[f][1]], id[m.triangles[f][2]]});
  return out;
}

}  // namespace

// Rays through the cube's vertices, along its edges and its side faces each count once: a
// point inside crosses it once, one below it twice, one beside or above it never, and a ray
// along a side face (|x| or |y| = 1) an even number of times.
TEST(RayCrossings, EveryRayThroughVerticesAndEdgesCountsOnce) {
  const int k = 4;
  const TriMesh cube = grid_cube(k);
  std::vector<Vec3> q;
  std::vector<int> expected;  // -1: even
  for (int i = -12; i <= 12; ++i)
    for (int j = -12; j <= 12; ++j)
      for (double z : {-1.5, -0.3, 0.0, 0.7, 1.5}) {
        const double x = i / (2.0 * k) * 1.0, y = j / (2.0 * k) * 1.0;
        const bool beside = std::abs(x) > 1 || std::abs(y) > 1, rim = std::abs(x) == 1 || std::abs(y) == 1;
        if (rim && std::abs(z) < 1) continue;  // on the surface
        q.push_back({x, y, z});
        expected.push_back(beside ? 0 : rim ? -1 : z > 1 ? 0 : z < -1 ? 2 : 1);
      }
  for (int threads : {1, 2, 4}) {
    const std::vector<uint64_t> count = ray_crossings(cube, q, threads);
    ASSERT_EQ(count.size(), q.size());
    for (size_t i = 0; i < q.size(); ++i) {
      if (expected[i] < 0) EXPECT_EQ(count[i] % 2, 0u) << q[i].x << " " << q[i].y << " " << q[i].z;
      else EXPECT_EQ(count[i], uint64_t(expected[i])) << q[i].x << " " << q[i].y << " " << q[i].z;
    }
  }
}

// A surface cut into pieces, each numbered in the whole one's vertex order, gives counts that
// add up to the whole one's, also for rays through the vertices and edges on the cuts: what
// lets processes that each hold a piece decide together whether a point is inside.
TEST(RayCrossings, PiecesOfOneSurfaceAddUpToIt) {
  const int k = 4;
  TriMesh cube = grid_cube(k);
  // Winding plays no part: turn every third triangle.
  for (size_t f = 0; f < cube.triangles.size(); f += 3) std::swap(cube.triangles[f][1], cube.triangles[f][2]);
  std::vector<Vec3> q;
  for (int i = -10; i <= 10; ++i)
    for (int j = -10; j <= 10; ++j) q.push_back({i / (2.0 * k), j / (2.0 * k), i % 2 ? -1.25 : 0.1});
  const std::vector<uint64_t> whole = ray_crossings(cube, q);
  // Cut where the rays pass: the bottom face along x = 0 (rays at x = 0 run along its cut
  // edges), the top face along y = 0.25 (along and through the cut's vertices), the sides
  // along z = 0, so that many rays cross one piece at the bottom and the other at the top.
  std::vector<bool> first(cube.triangles.size()), second(cube.triangles.size());
  for (size_t f = 0; f < cube.triangles.size(); ++f) {
    const auto& t = cube.triangles[f];
    const Vec3 c = (cube.positions[t[0]] + cube.positions[t[1]] + cube.positions[t[2]]) / 3.0;
    first[f] = c.z < -0.99 ? c.x < 0 : c.z > 0.99 ? c.y > 0.25 : c.z < 0;
    second[f] = !first[f];
  }
  const std::vector<uint64_t> a = ray_crossings(part(cube, first), q), b = ray_crossings(part(cube, second), q);
  size_t shared = 0;
  for (size_t i = 0; i < q.size(); ++i) {
    EXPECT_EQ(a[i] + b[i], whole[i]) << q[i].x << " " << q[i].y << " " << q[i].z;
    shared += a[i] > 0 && b[i] > 0;
  }
  EXPECT_GT(shared, 10u);  // the pieces each count a crossing of many rays
}

TEST(RayCrossings, InsideASphereIsOdd) {
  const TriMesh ball = icosphere_mesh(3);
  std::vector<Vec3> q;
  for (int i = 0; i < 200; ++i) {
    const double t = i * 0.61803398875, r = 1.6 * (i % 40) / 40.0;
    q.push_back({r * std::cos(t * 6.283) * 0.6, r * std::sin(t * 6.283) * 0.6, r * 0.8 * std::cos(t)});
  }
  const std::vector<uint64_t> count = ray_crossings(ball, q);
  for (size_t i = 0; i < q.size(); ++i) {
    const double d = norm(q[i]);
    if (d < 0.95) {
      EXPECT_EQ(count[i], 1u) << d;
    } else if (d > 1.01) {
      EXPECT_EQ(count[i] % 2, 0u) << d;
    }
  }
}

// A triangle that repeats a vertex has no area: no ray crosses it, also one straight through
// its point (its three edges from one vertex would all read as the same side: a crossing).
TEST(RayCrossings, TrianglesWithoutAreaAreNeverCrossed) {
  TriMesh m;
  m.positions = {{0, 0, 1}, {1, 0, 1}, {0, 1, 1}};
  m.triangles = {{0, 0, 0}, {0, 0, 1}, {1, 2, 2}};
  EXPECT_EQ(ray_crossings(m, {{0, 0, 0}, {0.5, 0, 0}, {0.2, 0.2, 0}}), (std::vector<uint64_t>{0, 0, 0}));
  m.triangles = {{0, 1, 2}};
  EXPECT_EQ(ray_crossings(m, {{0, 0, 0}, {0.5, 0, 0}, {0.2, 0.2, 0}}), (std::vector<uint64_t>{1, 1, 1}));
}

TEST(RayCrossings, BadInputIsNamed) {
  TriMesh m = icosphere_mesh(1);
  EXPECT_TRUE(ray_crossings(m, {}).empty());
  EXPECT_EQ(ray_crossings(TriMesh{}, {{0, 0, 0}}), std::vector<uint64_t>{0});
  try {
    ray_crossings(m, {{0, 0, 0}, {0, std::nan(""), 0}});
    FAIL();
  } catch (const Error& e) {
    EXPECT_EQ(e.status(), Status::InvalidInput);
    EXPECT_NE(std::string(e.what()).find("point 1 is not finite"), std::string::npos) << e.what();
  }
  m.triangles[5][2] = uint32_t(m.positions.size());
  try {
    ray_crossings(m, {{0, 0, 0}});
    FAIL();
  } catch (const Error& e) {
    EXPECT_EQ(e.status(), Status::InvalidArgument);
    EXPECT_NE(std::string(e.what()).find("triangle 5 has vertex index"), std::string::npos) << e.what();
  }
}
