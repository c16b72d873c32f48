// Determinism: every stage gives byte-identical output for any thread count and on
// every run (render farms cache on it). Threads beyond the machine's cores are clamped by the
// library, so on a 2-core machine this compares 1 and 2 workers, and repeated runs.
#include <gtest/gtest.h>

#include "hostile_support.h"
#include "particlemesh/sample/shapes.h"
#include "particlemesh/smooth/subdivide.h"
#include "particlemesh/surface/normals.h"
#include "particlemesh/surface/reconstruct.h"
#include "particlemesh/spatial/spacing.h"
#include "particlemesh/surface/triangulate.h"
#include "support/test_support.h"

using namespace particlemesh;
using namespace particlemesh::test;

namespace {

constexpr int kThreads[] = {1, 2, 3, 0, 1, 0};  // 1 and 0 twice: repeated runs

// hash(threads) must not depend on threads (nor on the run).
void expect_same_for_any_thread_count(const char* what, const std::function<uint64_t(int)>& hash) {
  const uint64_t first = hash(kThreads[0]);
  for (size_t i = 1; i < std::size(kThreads); ++i)
    EXPECT_EQ(hash(kThreads[i]), first) << what << " with threads = " << kThreads[i] << " (run " << i << ")";
}

// A jittered, duplicated, unevenly dense cloud: the inputs where scheduling order would show.
PointCloud awkward_cloud(double spacing = 0.02) {
  PointCloud c = double_torus_sample(spacing, 7);
  const double jitter = 0.2 * spacing;
  const PointCloud r = test::random_cloud(c.size(), 11, jitter);
  for (size_t i = 0; i < c.size(); ++i) c.positions[i] += r.positions[i] - Vec3{0.5 * jitter, 0.5 * jitter, 0.5 * jitter};
  for (size_t i = 0; i < c.size(); i += 17) {
    c.positions.push_back(c.positions[i]);
    c.normals.push_back(c.normals[i]);
  }
  return c;
}

}  // namespace

TEST(Determinism, TriangulateRaw) {
  const PointCloud c = awkward_cloud();
  expect_same_for_any_thread_count("triangulate_raw", [&](int t) {
    TriangulateOptions o;
    o.threads = t;
    const TriangulateResult r = triangulate_raw(c, o);
    return mesh_hash(r.mesh) ^ (r.stats.triplets * 31 + r.stats.kept);
  });
}

TEST(Determinism, ReconstructSurfaceEveryNormalSource) {
  const PointCloud c = awkward_cloud();
  for (auto source : {SurfaceOptions::NormalSource::Auto, SurfaceOptions::NormalSource::Estimate,
                      SurfaceOptions::NormalSource::Input}) {
    expect_same_for_any_thread_count("reconstruct_surface", [&](int t) {
      SurfaceOptions o;
      o.threads = t;
      o.normals = source;
      const SurfaceResult r = reconstruct_surface(c, o);
      return mesh_hash(r.mesh) ^ r.surface.holes_filled;
    });
  }
}

// 68k points: every parallel stage cut into many blocks.
TEST(Determinism, ReconstructSurfaceLargerCloud) {
  const PointCloud c = awkward_cloud(0.008);
  ASSERT_GE(c.size(), 50000u);
  expect_same_for_any_thread_count("reconstruct_surface, 68k points", [&](int t) {
    SurfaceOptions o;
    o.threads = t;
    o.normals = SurfaceOptions::NormalSource::Estimate;
    const SurfaceResult r = reconstruct_surface(c, o);
    return mesh_hash(r.mesh) ^ r.surface.holes_filled;
  });
}

TEST(Determinism, SpacingAndNormals) {
  const PointCloud c = awkward_cloud();
  expect_same_for_any_thread_count("estimate_spacing", [&](int t) {
    const double s = estimate_spacing(c.positions.data(), c.size(), t).spacing;
    uint64_t bits;
    std::memcpy(&bits, &s, sizeof bits);
    return bits;
  });
  expect_same_for_any_thread_count("estimate_normals", [&](int t) {
    NormalOptions o;
    o.threads = t;
    TriMesh m;
    m.normals = estimate_normals(c, o);
    return mesh_hash(m);
  });
}

TEST(Determinism, SmoothLoopAndButterflyWithAttributes) {
  const PointCloud c = awkward_cloud();
  TriMesh m = reconstruct_surface(c).mesh;
  std::vector<float> v;
  for (const auto& p : m.positions) v.insert(v.end(), {float(p.x), float(p.y * p.z), 1.0f});
  m.attributes = {{"velocity", 3, v}};
  for (SmoothScheme scheme : {SmoothScheme::Loop, SmoothScheme::Butterfly}) {
    expect_same_for_any_thread_count(scheme == SmoothScheme::Loop ? "smooth loop" : "smooth butterfly", [&](int t) {
      SmoothOptions o;
      o.scheme = scheme;
      o.levels = 2;
      o.threads = t;
      return mesh_hash(smooth_mesh(m, o).mesh);
    });
  }
}
