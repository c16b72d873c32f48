// Handles smaller than the sampling (surface/small_handles.h): a tunnel through a thin part,
// inside a patch of about an edge limit's reach, is taken out and the patch's outline filled;
// a handle no patch holds, and a surface of genus 0, are left as they are.
#include "surface/small_handles.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "particlemesh/mesh/topology_report.h"
#include "stage_support.h"
#include "support/test_support.h"

using namespace particlemesh;
using namespace particlemesh::detail;

namespace {

/// A closed finger: a box of unit-square cross-section along x, from x = 0 to `length`, rings
/// of four points at every unit, each end capped by two triangles; outward winding. With
/// `tunnel`, a tunnel goes through it `tunnel` units from its far tip: the top and the bottom
/// triangle there are taken out and their outlines joined by a tube through the inside,
/// pinched at mid height (the walls lean in), which gives the finger one handle.
struct Finger {
  std::vector<Vec3> P, N;
  std::vector<Frame> frames;
  std::vector<Triangle> tris;
  size_t rings = 0;
  Finger(int length, int tunnel) {
    rings = size_t(length) + 1;
    // Ring k's corners, counter-clockwise seen from +x: (y, z) = (0,0) (1,0) (1,1) (0,1).
    const double corner[4][2] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
    for (size_t k = 0; k < rings; ++k)
      for (const auto& c : corner) {
        P.push_back({double(k), c[0], c[1]});
        N.push_back({0, 0, 1});
      }
    auto id = [](size_t k, size_t c) { return uint32_t(4 * k + c % 4); };
    // Sides: between ring k and k + 1, side c runs from corner c to c + 1 (bottom, +y side,
    // top, -y side); its outward normal is the corners' ccw-from-+x order's outside.
    const size_t k0 = rings - 1 - size_t(tunnel);  // the tunnel's square of the sides
    for (size_t k = 0; k + 1 < rings; ++k)
      for (size_t c = 0; c < 4; ++c) {
        const Triangle t1 = {id(k, c), id(k + 1, c + 1), id(k + 1, c)};
        const Triangle t2 = {id(k, c), id(k, c + 1), id(k + 1, c + 1)};
        const bool cut = tunnel > 0 && k == k0;
        if (!(cut && c == 2)) tris.push_back(t1);  // the top's first triangle is cut
        if (!(cut && c == 0)) tris.push_back(t2);  // the bottom's second
      }
    tris.push_back({id(0, 0), id(0, 2), id(0, 1)});  // the near cap faces -x
    tris.push_back({id(0, 0), id(0, 3), id(0, 2)});
    tris.push_back({id(rings - 1, 0), id(rings - 1, 1), id(rings - 1, 2)});  // the far cap +x
    tris.push_back({id(rings - 1, 0), id(rings - 1, 2), id(rings - 1, 3)});
    if (tunnel > 0) {
      // The bottom triangle cut out, in its own winding, and above each of its corners a
      // corner of the top's (the top's winding reversed: the tube keeps both windings).
      const std::vector<uint32_t> lower = {id(k0, 0), id(k0, 1), id(k0 + 1, 1)};
      const std::vector<uint32_t> upper = {id(k0 + 1, 3), id(k0, 2), id(k0 + 1, 2)};
      Vec3 axis;
      for (uint32_t v : lower) axis += P[v] * (1.0 / 3);
      std::vector<uint32_t> middle;  // drawn in towards the tube's axis, at mid height
      for (uint32_t b : lower) {
        middle.push_back(uint32_t(P.size()));
        P.push_back({axis.x + 0.4 * (P[b].x - axis.x), axis.y + 0.4 * (P[b].y - axis.y), 0.5});
        N.push_back({0, 0, 1});
      }
      auto strip = [&](const std::vector<uint32_t>& a, const std::vector<uint32_t>& b) {
        for (size_t i = 0; i < 3; ++i) {
          const size_t j = (i + 1) % 3;
          tris.push_back({a[i], a[j], b[j]});
          tris.push_back({a[i], b[j], b[i]});
        }
      };
      strip(lower, middle);
      strip(middle, upper);
    }
    frames = detail::tangent_frames(N);
  }
};

TopologyReport report_of(const std::vector<Vec3>& P, const std::vector<Triangle>& tris) {
  TriMesh m;
  m.positions = P;
  m.triangles = tris;
  return topology_report(m);
}

}  // namespace

TEST(SmallHandles, ATunnelThroughAThinPartIsReplacedByAFillOfItsOutline) {
  const Finger f(12, 1);
  const TopologyReport before = report_of(f.P, f.tris);
  ASSERT_EQ(before.components, 1u);
  ASSERT_TRUE(before.closed);
  ASSERT_TRUE(before.consistently_oriented);
  ASSERT_EQ(before.per_component[0].genus, 1);
  EditableSurface e(f.P, f.frames, f.tris);
  const std::vector<double> L(f.P.size(), 1.5);
  FillOptions o;
  o.max_edge = &L;
  // An outline longer than the fill's loop limit (fill_holes) is not filled; nor one whose
  // fill would need longer edges than the fill's: the patch is then as it was, in order.
  EXPECT_EQ(remove_small_handles(e, o, 3), 0u);
  EXPECT_EQ(e.take(), f.tris);
  o.fill_edge_factor = 0.2;
  EXPECT_EQ(remove_small_handles(e, o, 100), 0u);
  EXPECT_EQ(e.take(), f.tris);
  EXPECT_EQ(e.boundary_set().size(), 0u);
  o.fill_edge_factor = 1.5;
  EXPECT_EQ(remove_small_handles(e, o, 100), 1u);
  const std::vector<Triangle> after = e.take();
  const TopologyReport r = report_of(f.P, after);
  EXPECT_EQ(r.components, 1u);
  EXPECT_TRUE(r.closed);
  EXPECT_TRUE(r.consistently_oriented);
  EXPECT_EQ(r.per_component[0].genus, 0);
  // The tip beyond the fill is gone with the tunnel (its particles are left for the insertion
  // to put back); the finger's base, beyond the patch's reach, keeps every triangle.
  for (const Triangle& t : f.tris) {
    if (f.P[t[0]].x < 6 && f.P[t[1]].x < 6 && f.P[t[2]].x < 6) {
      EXPECT_EQ(std::count(after.begin(), after.end(), t), 1) << t[0] << " " << t[1] << " " << t[2];
    }
  }
  EXPECT_EQ(remove_small_handles(e, o, 100), 0u);  // nothing left to take out
}

TEST(SmallHandles, LargerHandlesAndSurfacesOfGenusZeroStay) {
  // The tunnel farther from the tip than a patch reaches around it: the patch there is a
  // ring of the finger with the tunnel, two outlines, and stays (a handle of a real part, a
  // ring's tube, looks the same).
  const Finger far(12, 5);
  ASSERT_EQ(report_of(far.P, far.tris).per_component[0].genus, 1);
  EditableSurface e(far.P, far.frames, far.tris);
  const std::vector<double> L(far.P.size(), 1.5);
  FillOptions o;
  o.max_edge = &L;
  EXPECT_EQ(remove_small_handles(e, o, 100), 0u);
  EXPECT_EQ(test::canonical(e.take()), test::canonical(far.tris));
  // The finger without a tunnel: genus 0, nothing searched.
  const Finger plain(12, 0);
  EditableSurface g(plain.P, plain.frames, plain.tris);
  const std::vector<double> L2(plain.P.size(), 1.5);
  o.max_edge = &L2;
  EXPECT_EQ(remove_small_handles(g, o, 100), 0u);
  EXPECT_EQ(test::canonical(g.take()), test::canonical(plain.tris));
}
