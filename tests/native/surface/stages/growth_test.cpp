// Best-first manifold growth (surface/growth.h) on the raw test's triangles of flat sheets.
#include "surface/growth.h"

#include <gtest/gtest.h>

#include <map>

#include "particlemesh/surface/triangulate.h"
#include "surface/editable_surface.h"
#include "stage_support.h"
#include "support/test_support.h"

using namespace particlemesh;
using namespace particlemesh::detail;

namespace {

// The raw test's triangles of a jittered flat sheet (nx x ny points, unit spacing), with +z
// normals, ranked and grown.
struct Grown {
  std::vector<Vec3> P;
  std::vector<Triangle> raw;
  GrownSurface g;
};

Grown grow_sheet(size_t nx, size_t ny, double jitter) {
  test::Sheet s(nx, ny);
  PointCloud c;
  c.positions = s.P;
  c = test::jittered(c, jitter, 5);
  for (auto& p : c.positions) p.z = 0;
  Grown out;
  out.P = c.positions;
  TriangulateOptions o;
  o.spacing = 1.0;
  out.raw = triangulate_raw(c, o).mesh.triangles;
  const std::vector<Vec3> N(out.P.size(), Vec3{0, 0, 1});
  const std::vector<uint8_t> active(out.P.size(), 1);
  test::QuietTracker q;
  CandidateSet cs = rank_candidates(out.P, N, tangent_frames(N), active, out.raw, -0.5, q.tracker);
  out.g = grow_surface(out.P.size(), std::move(cs), q.tracker);
  return out;
}

}  // namespace

TEST(Growth, FlatSheetGrowsIntoOneManifoldDisk) {
  // The raw test keeps overlapping triangles on nearly square cells (three or four per cell);
  // growth keeps a consistently wound manifold: every directed edge once.
  const Grown r = grow_sheet(30, 20, 0.05);
  EXPECT_GT(r.raw.size(), r.g.triangles.size());
  std::map<std::pair<uint32_t, uint32_t>, int> directed;
  for (const Triangle& t : r.g.triangles) {
    EXPECT_GT(cross(r.P[t[1]] - r.P[t[0]], r.P[t[2]] - r.P[t[0]]).z, 0);  // wound about +z
    for (int k = 0; k < 3; ++k) ++directed[{t[k], t[(k + 1) % 3]}];
  }
  for (const auto& [e, n] : directed) EXPECT_EQ(n, 1);
  EXPECT_EQ(r.g.seeds, 1u);
  EXPECT_EQ(r.g.grown, r.g.triangles.size());
  // Every point is reached, and what growth leaves open besides the outline are small holes
  // (wrong diagonals, at most 6 edges), which the repair fills.
  std::vector<uint8_t> used(r.P.size(), 0);
  for (const Triangle& t : r.g.triangles)
    for (uint32_t v : t) used[v] = 1;
  EXPECT_EQ(std::count(used.begin(), used.end(), 1), 600);
  const std::vector<Frame> frames = tangent_frames(std::vector<Vec3>(r.P.size(), Vec3{0, 0, 1}));
  const EditableSurface e(r.P, frames, r.g.triangles);
  const auto loops = e.trace_loops();
  ASSERT_GE(loops.size(), 1u);
  size_t outline = 0;
  for (const auto& l : loops) {
    if (l.size() > 6) ++outline;
    else EXPECT_GE(l.size(), 3u);
  }
  EXPECT_EQ(outline, 1u);
  // Space order: each triangle at its lowest vertex, ascending.
  for (size_t i = 0; i < r.g.triangles.size(); ++i) {
    const Triangle& t = r.g.triangles[i];
    EXPECT_LT(t[0], t[1]);
    EXPECT_LT(t[0], t[2]);
    if (i > 0) {
      EXPECT_LE(r.g.triangles[i - 1][0], t[0]);
    }
  }
  // The accepted corners lead each vertex's list.
  for (uint32_t v = 0; v < r.P.size(); ++v) {
    uint32_t at_v = 0;
    for (const Triangle& t : r.g.triangles) at_v += t[0] == v || t[1] == v || t[2] == v;
    EXPECT_EQ(r.g.accepted_count[v], at_v);
  }
}

TEST(Growth, QuadTakesItsDelaunayPairNotTheOverlappingObtuseTriangle) {
  // A quad a b c d whose Delaunay diagonal is bd (the angles at a and c add up to less than
  // 180 degrees). Of its four triangles, abc and acd (obtuse at b and d) overlap the Delaunay
  // pair abd and bcd; the best-first rank (smallest largest angle) makes growth take the pair.
  const std::vector<Vec3> P = {{0, 0, 0}, {1.2, -0.6, 0}, {2.0, 0, 0}, {1.2, 0.6, 0}};
  const std::vector<Vec3> N(4, Vec3{0, 0, 1});
  const std::vector<uint8_t> active(4, 1);
  const std::vector<Triangle> raw = {{0, 1, 2}, {0, 1, 3}, {0, 2, 3}, {1, 2, 3}};
  test::QuietTracker q;
  CandidateSet cs = rank_candidates(P, N, tangent_frames(N), active, raw, -0.5, q.tracker);
  const GrownSurface g = grow_surface(P.size(), std::move(cs), q.tracker);
  EXPECT_EQ(test::canonical(g.triangles), (std::vector<Triangle>{{0, 1, 3}, {1, 2, 3}}));
}
