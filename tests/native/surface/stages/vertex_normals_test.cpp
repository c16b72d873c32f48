// The finished surface's vertex normals and outward orientation (surface/vertex_normals.h,
// surface/orient_outward.h).
#include "surface/vertex_normals.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>

#include "stage_support.h"
#include "surface/orient_outward.h"

using namespace particlemesh;
using namespace particlemesh::detail;

TEST(VertexNormals, AngleWeightedAndFallbackForUnusedPoints) {
  test::Sheet s(3, 3);
  s.P.push_back({5, 5, 5});
  s.N.push_back({1, 0, 0});  // a point in no triangle keeps its own normal
  s.frames = tangent_frames(s.N);
  EditableSurface e(s.P, s.frames, s.tris);
  std::vector<uint8_t> active(s.P.size(), 1);
  size_t unused = 0;
  const auto n = surface_vertex_normals(e, active, s.N, unused);
  EXPECT_EQ(unused, 1u);
  for (size_t v = 0; v < 9; ++v) EXPECT_NEAR(distance(n[v], Vec3{0, 0, 1}), 0, 1e-12) << v;
  EXPECT_EQ(n[9].x, 1);
  // A bent sheet: the corner between two faces at 90 degrees gets their angle-weighted mean.
  const std::vector<Vec3> P = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  const std::vector<Vec3> N(4, Vec3{0, 0, 0});
  const std::vector<Frame> frames(4);
  EditableSurface bent(P, frames, std::vector<Triangle>{{0, 1, 2}, {0, 3, 1}});
  const auto m = surface_vertex_normals(bent, std::vector<uint8_t>(4, 1), N, unused);
  EXPECT_NEAR(distance(m[0], normalized(Vec3{0, 1, 1})), 0, 1e-7);  // two right angles
}

TEST(OrientOutward, ClosedComponentsTurnOutwardOpenOnesStay) {
  // A tetrahedron wound inward, one wound outward, and an open triangle.
  std::vector<Vec3> P = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  for (int k = 0; k < 4; ++k) P.push_back(P[k] + Vec3{3, 0, 0});
  for (const Vec3& p : {Vec3{6, 0, 0}, Vec3{7, 0, 0}, Vec3{6, 1, 0}}) P.push_back(p);
  const std::vector<Triangle> outward = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};
  std::vector<Triangle> tris;
  for (const Triangle& t : outward) tris.push_back({t[0], t[2], t[1]});                 // inward
  for (const Triangle& t : outward) tris.push_back({t[0] + 4, t[1] + 4, t[2] + 4});     // outward
  tris.push_back({8, 10, 9});                                                           // open, down
  const std::vector<uint64_t> boundary = {(uint64_t(8) << 32) | 10, (uint64_t(9) << 32) | 8, (uint64_t(10) << 32) | 9};
  std::vector<Vec3> normals(P.size(), Vec3{0, 0, 1});
  std::vector<Triangle> turned = tris;
  EXPECT_EQ(orient_closed_components_outward(P, turned, boundary, &normals), 1u);
  for (size_t i = 0; i < 4; ++i) EXPECT_EQ(turned[i], outward[i]);
  for (size_t i = 4; i < 9; ++i) EXPECT_EQ(turned[i], tris[i]);
  for (size_t v = 0; v < 4; ++v) EXPECT_EQ(normals[v].z, -1);
  for (size_t v = 4; v < P.size(); ++v) EXPECT_EQ(normals[v].z, 1);
}

TEST(OrientOutward, FlatClosedPiecesAreOpened) {
  // Two patches closed onto their reversed copies (pillows of no volume): one in a plane of
  // coordinates (its volume exactly 0), one in a tilted plane (0 within rounding). Beside
  // them a tetrahedron 1e-3 as high as it is wide (flat-looking, but a solid) and an open
  // triangle: those stay, and the tetrahedron is turned outward as without the pillows.
  std::vector<Vec3> P = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}};  // a square in z = 0
  const Vec3 u = normalized(Vec3{1, 0.3, 0.7}), w = normalized(cross(u, Vec3{0.2, 1, 0.1}));
  for (const Vec3& q : {Vec3{0, 0, 0}, Vec3{1, 0, 0}, Vec3{1, 1, 0}, Vec3{0, 1, 0}})
    P.push_back(Vec3{5, 5, 5} + u * q.x + w * q.y);                    // the same square, tilted
  for (const Vec3& q : {Vec3{0, 0, 0}, Vec3{1, 0, 0}, Vec3{0, 1, 0}, Vec3{0.3, 0.3, 1e-3}})
    P.push_back(q + Vec3{10, 0, 0});                                   // a thin tetrahedron
  for (const Vec3& q : {Vec3{20, 0, 0}, Vec3{21, 0, 0}, Vec3{20, 1, 0}}) P.push_back(q);
  std::vector<Triangle> tris;
  for (uint32_t b : {0u, 4u}) {
    tris.push_back({b, b + 1, b + 2});  // facing +z (+u x w)
    tris.push_back({b, b + 2, b + 3});
    tris.push_back({b, b + 3, b + 1});  // the copy reversed, split along the other diagonal
    tris.push_back({b + 1, b + 3, b + 2});
  }
  const std::vector<Triangle> thin_inward = {{8, 9, 10}, {8, 11, 9}, {8, 10, 11}, {9, 11, 10}};
  for (const Triangle& t : thin_inward) tris.push_back(t);
  tris.push_back({12, 13, 14});
  const std::vector<uint64_t> boundary = {(uint64_t(12) << 32) | 13, (uint64_t(13) << 32) | 14, (uint64_t(14) << 32) | 12};
  std::vector<Triangle> alone(tris.begin() + 8, tris.end());
  EXPECT_EQ(orient_closed_components_outward(P, alone, boundary), 1u);
  EXPECT_NE(alone[0], thin_inward[0]);

  // The particles' normals say which side: +z for the first square, -(u x w) for the second.
  std::vector<Vec3> sides(P.size(), Vec3{0, 0, 1});
  for (uint32_t v = 4; v < 8; ++v) sides[v] = Vec3{} - cross(u, w);
  FlatPieces flat;
  flat.sides = &sides;
  std::vector<Triangle> kept = tris;
  EXPECT_EQ(orient_closed_components_outward(P, kept, boundary, nullptr, true, &flat), 1u);
  // (pieces, removed whole, triangles removed, particles left unused)
  const auto counts = [](const FlatPieces& f) { return std::array<size_t, 4>{f.pieces, f.removed, f.triangles, f.points}; };
  EXPECT_EQ(counts(flat), (std::array<size_t, 4>{2, 0, 4, 0}));
  EXPECT_EQ(flat.loops, (std::vector<size_t>{4, 4}));
  std::vector<Triangle> want = {tris[0], tris[1], tris[6], tris[7]};
  want.insert(want.end(), alone.begin(), alone.end());
  EXPECT_EQ(kept, want);  // the rest as without the pillows, in order

  // Without the particles' normals, or turning off: the pillows go whole; nothing is turned.
  FlatPieces blind;
  std::vector<Triangle> unturned = tris;
  EXPECT_EQ(orient_closed_components_outward(P, unturned, boundary, nullptr, false, &blind), 0u);
  EXPECT_EQ(counts(blind), (std::array<size_t, 4>{2, 2, 8, 8}));
  EXPECT_TRUE(blind.loops.empty());
  EXPECT_EQ(std::vector<Triangle>(unturned.begin(), unturned.begin() + 4), thin_inward);
}

namespace {

// The unit cube's 12 triangles, wound outward, face by face (two triangles a face).
std::vector<Triangle> cube_outward() {
  // Vertex i = (i & 1, i >> 1 & 1, i >> 2 & 1).
  const std::array<std::array<uint32_t, 4>, 6> faces = {{
      {0, 2, 3, 1}, {4, 5, 7, 6},   // z = 0 (down), z = 1 (up)
      {0, 1, 5, 4}, {2, 6, 7, 3},   // y = 0, y = 1
      {0, 4, 6, 2}, {1, 3, 7, 5}}};  // x = 0, x = 1
  std::vector<Triangle> t;
  for (const auto& f : faces) {
    t.push_back({f[0], f[1], f[2]});
    t.push_back({f[0], f[2], f[3]});
  }
  return t;
}

std::vector<Vec3> cube_points(Vec3 at, double size) {
  std::vector<Vec3> P;
  for (uint32_t i = 0; i < 8; ++i) P.push_back(at + Vec3{double(i & 1), double(i >> 1 & 1), double(i >> 2 & 1)} * size);
  return P;
}

// The half-edges (a << 32 | b) whose reverse no triangle holds.
std::vector<uint64_t> boundary_of(const std::vector<Triangle>& tris) {
  std::vector<uint64_t> he;
  for (const Triangle& t : tris)
    for (int k = 0; k < 3; ++k) he.push_back(uint64_t(t[k]) << 32 | t[(k + 1) % 3]);
  std::sort(he.begin(), he.end());
  std::vector<uint64_t> out;
  for (uint64_t e : he)
    if (!std::binary_search(he.begin(), he.end(), (e & 0xffffffffu) << 32 | e >> 32)) out.push_back(e);
  return out;
}

Triangle reversed(const Triangle& t) { return {t[0], t[2], t[1]}; }

// The loops left open, as the surface builder traces them.
std::vector<std::vector<uint32_t>> loops_of(const std::vector<Vec3>& P, const std::vector<Triangle>& tris) {
  return EditableSurface(P, tangent_frames(std::vector<Vec3>(P.size(), Vec3{0, 0, 1})), tris).trace_loops();
}

}  // namespace

TEST(OrientOutward, NearlyClosedPiecesTurnAsClosedOnesWhereEnabled) {
  // A cube wound inward with openings: one triangle gone (its cap 1/11 of the rest), one face
  // gone (1/5), three faces gone (a bent strip, its cap about as large as it: left as it is);
  // beside them a closed small
  // cube wound inward inside the first (a capped piece nests nothing: the small one faces
  // outward, as it would alone).
  const std::vector<Triangle> cube = cube_outward();
  std::vector<Vec3> P;
  std::vector<Triangle> tris;
  auto add = [&](Vec3 at, double size, size_t drop) {
    const auto base = uint32_t(P.size());
    for (const Vec3& p : cube_points(at, size)) P.push_back(p);
    for (size_t i = drop; i < cube.size(); ++i)
      tris.push_back(reversed({cube[i][0] + base, cube[i][1] + base, cube[i][2] + base}));
  };
  add({0, 0, 0}, 1, 1);     // tris 0..10
  add({3, 0, 0}, 1, 2);     // 11..20
  add({6, 0, 0}, 1, 6);     // 21..26
  add({0.4, 0.4, 0.4}, 0.2, 0);  // 27..38, inside the first
  const std::vector<Triangle> before = tris;
  const std::vector<uint64_t> boundary = boundary_of(tris);
  std::vector<Vec3> normals(P.size(), Vec3{0, 0, 1});

  const std::vector<std::vector<uint32_t>> loops = loops_of(P, tris);
  NearlyClosed nearly;
  nearly.loops = &loops;
  std::vector<Triangle> turned = tris;
  EXPECT_EQ(orient_closed_components_outward(P, turned, boundary, &normals, true, nullptr, &nearly), 3u);
  EXPECT_EQ(nearly.pieces, 2u);
  EXPECT_EQ(nearly.turned, 2u);
  for (size_t i = 0; i < before.size(); ++i) {
    const bool open_box = i >= 21 && i < 27;
    EXPECT_EQ(turned[i], open_box ? before[i] : reversed(before[i])) << i;
  }
  for (uint32_t v = 0; v < P.size(); ++v) EXPECT_EQ(normals[v].z, v >= 16 && v < 24 ? 1 : -1) << v;

  // Not enabled (input normals, a viewpoint): only the closed cube turns.
  NearlyClosed off;
  std::vector<Triangle> kept = tris;
  EXPECT_EQ(orient_closed_components_outward(P, kept, boundary, nullptr, true, nullptr, &off), 1u);
  EXPECT_EQ(off.pieces, 0u);
  for (size_t i = 0; i < before.size(); ++i) EXPECT_EQ(kept[i], i >= 27 ? reversed(before[i]) : before[i]) << i;

  // Wound outward already: nothing turns, both counted as judged.
  std::vector<Triangle> outward = turned;
  const std::vector<std::vector<uint32_t>> outward_loops = loops_of(P, outward);
  NearlyClosed again;
  again.loops = &outward_loops;
  EXPECT_EQ(orient_closed_components_outward(P, outward, boundary_of(outward), nullptr, true, nullptr, &again), 0u);
  EXPECT_EQ(again.pieces, 2u);
  EXPECT_EQ(again.turned, 0u);
  EXPECT_EQ(outward, turned);
}
