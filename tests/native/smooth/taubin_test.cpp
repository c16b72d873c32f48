// Taubin's lambda|mu smoothing: it takes the bumps out of a noisy closed surface, keeps its
// volume where plain Laplacian smoothing shrinks it, keeps the topology, is deterministic.
#include "particlemesh/smooth/taubin.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>

#include "particlemesh/core/error.h"
#include "particlemesh/mesh/topology_report.h"
#include "particlemesh/sample/shapes.h"
#include "particlemesh/volume/polygonize.h"

using namespace particlemesh;

namespace {

double volume(const TriMesh& m) {
  double v = 0;
  for (const Triangle& t : m.triangles) v += dot(m.positions[t[0]], cross(m.positions[t[1]], m.positions[t[2]])) / 6;
  return v;
}

// RMS distance of the vertices from the sphere of radius r about the origin.
double roughness(const TriMesh& m, double r) {
  double s = 0;
  for (const Vec3& p : m.positions) s += (norm(p) - r) * (norm(p) - r);
  return std::sqrt(s / double(m.positions.size()));
}

TriMesh noisy_sphere() {
  TriMesh m = icosphere_mesh(4, 1.0);
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> u(-0.02, 0.02);
  for (Vec3& p : m.positions) p = p * (1 + u(rng));
  return m;
}

}  // namespace

TEST(Taubin, SmoothsANoisySphereAndKeepsItsVolume) {
  const TriMesh noisy = noisy_sphere();
  TriMesh t = noisy;
  taubin_smooth(t, {});
  const double v0 = volume(noisy), v1 = volume(t);
  EXPECT_LT(roughness(t, std::cbrt(v1 * 3 / (4 * std::numbers::pi))), 0.5 * roughness(noisy, 1.0));
  EXPECT_NEAR(v1 / v0, 1.0, 0.01);
  // Plain Laplacian smoothing (the lambda steps alone) shrinks it by several percent: what
  // Taubin's inflating step is for.
  TriMesh lap = noisy;
  std::vector<std::vector<uint32_t>> nb(lap.positions.size());
  for (const Triangle& tr : lap.triangles)
    for (int k = 0; k < 3; ++k) nb[tr[size_t(k)]].push_back(tr[size_t((k + 1) % 3)]);  // each edge once per side
  for (int it = 0; it < 2 * TaubinOptions{}.iterations; ++it) {
    std::vector<Vec3> next = lap.positions;
    for (size_t v = 0; v < nb.size(); ++v) {
      Vec3 mean{};
      for (uint32_t j : nb[v]) mean += lap.positions[j];
      next[v] += (mean / double(nb[v].size()) - lap.positions[v]) * TaubinOptions{}.lambda;
    }
    lap.positions = next;
  }
  EXPECT_LT(volume(lap) / v0, 0.97);
  const TopologyReport r = topology_report(t);
  EXPECT_TRUE(r.closed && r.manifold && r.consistently_oriented && r.outward);
  EXPECT_EQ(t.triangles, noisy.triangles);
  ASSERT_EQ(t.normals.size(), t.positions.size());
  for (size_t i = 0; i < t.positions.size(); ++i) EXPECT_GT(dot(t.normals[i], normalized(t.positions[i])), 0.95);
}

TEST(Taubin, SameForAnyThreadCountAndClearErrors) {
  TriMesh a = noisy_sphere(), b = a;
  TaubinOptions o;
  o.threads = 1;
  taubin_smooth(a, o);
  o.threads = 2;
  taubin_smooth(b, o);
  EXPECT_EQ(a.positions, b.positions);
  EXPECT_EQ(a.normals, b.normals);
  TriMesh c = noisy_sphere();
  const TriMesh before = c;
  o.iterations = 0;
  taubin_smooth(c, o);
  EXPECT_EQ(c.positions, before.positions);
  for (auto bad : {TaubinOptions{-1}, TaubinOptions{10, 0.0}, TaubinOptions{10, 0.5, -0.4},
                   TaubinOptions{10, 0.5, -1.5}, TaubinOptions{10, 0.5, -0.53, -2}})
    EXPECT_THROW(taubin_smooth(c, bad), Error);
  c.triangles.push_back({0, 1, uint32_t(c.positions.size())});
  EXPECT_THROW(taubin_smooth(c, {}), Error);
}

// As polygonize's option: the bumps of a jittered block's flat top flatten (its normals tilt
// less from vertical), the volume stays, the triangles are the same.
TEST(Taubin, PolygonizeSmoothsItsMesh) {
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> u(-0.15, 0.15);
  PointCloud c;
  const int n = 16, h = 8;
  for (int z = 0; z < n; ++z)
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < n; ++x) c.positions.push_back({x + u(rng), y + u(rng), z + u(rng)});
  PolygonizeOptions o;
  const PolygonizeResult raw = polygonize(c, o);
  o.surface_smoothing.iterations = 10;
  const PolygonizeResult s = polygonize(c, o);
  EXPECT_EQ(s.stats.smoothing_iterations, 10);
  EXPECT_EQ(s.mesh.triangles, raw.mesh.triangles);
  EXPECT_NEAR(volume(s.mesh) / volume(raw.mesh), 1.0, 0.002);
  // RMS tilt from vertical of the normals on the top face, away from its edges.
  auto tilt = [&](const TriMesh& m) {
    double sum = 0;
    size_t k = 0;
    for (size_t i = 0; i < m.positions.size(); ++i) {
      const Vec3& p = m.positions[i];
      if (p.y < h - 1.5 || p.x < 4 || p.x > n - 5 || p.z < 4 || p.z > n - 5) continue;
      const double a = std::acos(std::clamp(m.normals[i].y, -1.0, 1.0));
      sum += a * a;
      ++k;
    }
    EXPECT_GT(k, 100u);
    return std::sqrt(sum / double(k));
  };
  EXPECT_LT(tilt(s.mesh), 0.8 * tilt(raw.mesh));
  o.surface_smoothing.mu = 0.1;
  EXPECT_THROW(polygonize(c, o), Error);
}
