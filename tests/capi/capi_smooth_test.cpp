// The C ABI of smoothing and per-vertex attributes: same results as the C++ API, statuses and
// messages for misuse, outputs untouched on failure, old struct sizes, cancellation.
#include "particlemesh/particlemesh.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstddef>
#include <string>
#include <vector>

#include "particlemesh/sample/shapes.h"
#include "particlemesh/smooth/subdivide.h"
#include "support/test_support.h"

using namespace particlemesh;

namespace {

std::string last() { return pm_last_error_message(); }

pm_mesh* make_mesh(const TriMesh& m) {
  std::vector<double> p;
  for (const Vec3& v : m.positions) p.insert(p.end(), {v.x, v.y, v.z});
  std::vector<int32_t> t;
  for (const auto& tri : m.triangles) t.insert(t.end(), {int32_t(tri[0]), int32_t(tri[1]), int32_t(tri[2])});
  pm_mesh* mesh = nullptr;
  EXPECT_EQ(pm_mesh_create(p.data(), m.positions.size(), t.data(), m.triangles.size(), nullptr, &mesh), PM_OK)
      << last();
  return mesh;
}

struct MeshGuard {
  pm_mesh* m = nullptr;
  ~MeshGuard() { pm_mesh_destroy(m); }
};

pm_mesh* const kSentinel = reinterpret_cast<pm_mesh*>(0x1234);

}  // namespace

TEST(CApiSmooth, DefaultsMatchTheCppApi) {
  pm_smooth_options o;
  pm_smooth_options_init(&o);
  const SmoothOptions d;
  EXPECT_EQ(o.struct_size, sizeof(pm_smooth_options));
  EXPECT_EQ(o.scheme, PM_SMOOTH_LOOP);
  EXPECT_EQ(o.levels, 1);
  EXPECT_EQ(o.limit, 1);
  EXPECT_EQ(o.boundary, PM_BOUNDARY_EDGE_AND_CORNER);
  EXPECT_EQ(o.crease_method, PM_CREASE_UNIFORM);
  EXPECT_EQ(o.threads, 0);
  EXPECT_EQ(o.max_triangles, d.max_triangles);
  EXPECT_EQ(o.crease_count, 0u);
  EXPECT_EQ(o.crease_edges, nullptr);
  EXPECT_EQ(o.progress, nullptr);
  EXPECT_EQ(int(SmoothScheme::Butterfly), PM_SMOOTH_BUTTERFLY);
  EXPECT_EQ(int(BoundaryRule::EdgeOnly), PM_BOUNDARY_EDGE_ONLY);
  EXPECT_EQ(int(CreaseMethod::Chaikin), PM_CREASE_CHAIKIN);
  pm_smooth_options_init(nullptr);  // tolerated
}

TEST(CApiSmooth, SmoothMatchesTheCppApiAndCarriesAttributes) {
  const TriMesh m = torus_mesh(1, 0.4, 20, 10);
  MeshGuard in{make_mesh(m)};
  std::vector<float> vel, w(m.positions.size(), 0.5f);
  for (const auto& p : m.positions) vel.insert(vel.end(), {float(p.x), float(2 * p.y), float(p.z - 1)});
  ASSERT_EQ(pm_mesh_set_attribute(in.m, "velocity", 3, vel.data(), m.positions.size()), PM_OK) << last();
  ASSERT_EQ(pm_mesh_set_attribute(in.m, "w", 1, w.data(), m.positions.size()), PM_OK) << last();

  for (int32_t scheme : {PM_SMOOTH_LOOP, PM_SMOOTH_BUTTERFLY}) {
    pm_smooth_options o;
    pm_smooth_options_init(&o);
    o.scheme = scheme;
    o.levels = 2;
    MeshGuard out;
    ASSERT_EQ(pm_smooth(in.m, &o, &out.m), PM_OK) << last();
    TriMesh cm = m;
    cm.attributes = {{"velocity", 3, vel}, {"w", 1, w}};
    SmoothOptions co;
    co.scheme = static_cast<SmoothScheme>(scheme);
    co.levels = 2;
    const SmoothResult ref = smooth_mesh(cm, co);
    size_t nv = 0, nt = 0;
    ASSERT_EQ(pm_mesh_get_counts(out.m, &nv, &nt), PM_OK);
    EXPECT_EQ(nv, ref.mesh.positions.size());
    EXPECT_EQ(nt, ref.mesh.triangles.size());
    std::vector<double> pos(3 * nv);
    ASSERT_EQ(pm_mesh_copy_positions(out.m, pos.data(), nv), PM_OK);
    for (size_t i = 0; i < nv; ++i) ASSERT_EQ(pos[3 * i + 1], ref.mesh.positions[i].y);
    int32_t has = 0;
    ASSERT_EQ(pm_mesh_has_normals(out.m, &has), PM_OK);
    EXPECT_EQ(has, 1);
    size_t count = 0;
    ASSERT_EQ(pm_mesh_get_attribute_count(out.m, &count), PM_OK);
    ASSERT_EQ(count, 2u);
    const char* name = nullptr;
    ASSERT_EQ(pm_mesh_get_attribute_name(out.m, 1, &name), PM_OK);
    EXPECT_STREQ(name, "w");
    int32_t comps = 0;
    ASSERT_EQ(pm_mesh_get_attribute_components(out.m, "velocity", &comps), PM_OK);
    ASSERT_EQ(comps, 3);
    std::vector<float> got(3 * nv);
    ASSERT_EQ(pm_mesh_copy_attribute(out.m, "velocity", got.data(), nv), PM_OK) << last();
    EXPECT_EQ(got, ref.mesh.attributes[0].values);
    std::vector<float> gw(nv);
    ASSERT_EQ(pm_mesh_copy_attribute(out.m, "w", gw.data(), nv), PM_OK);
    for (float x : gw) ASSERT_NEAR(x, 0.5f, 1e-6);
  }
  // NULL options: one Loop level at the limit.
  MeshGuard def;
  ASSERT_EQ(pm_smooth(in.m, nullptr, &def.m), PM_OK) << last();
  size_t nt = 0;
  ASSERT_EQ(pm_mesh_get_counts(def.m, nullptr, &nt), PM_OK);
  EXPECT_EQ(nt, 4 * m.triangles.size());
}

// Values per triangle corner cross the ABI both ways and go through pm_smooth as through
// smooth_mesh; misuse names what is wrong and changes nothing.
TEST(CApiSmooth, CornerAttributesCrossTheAbiAndAreSmoothed) {
  const TriMesh m = torus_mesh(1, 0.4, 12, 8);
  MeshGuard in{make_mesh(m)};
  const size_t nt = m.triangles.size();
  std::vector<float> uv(6 * nt);
  for (size_t i = 0; i < uv.size(); ++i) uv[i] = float(i % 7) * 0.125f + float(i / 6);
  ASSERT_EQ(pm_mesh_set_corner_attribute(in.m, "uv", 2, uv.data(), nt), PM_OK) << last();
  size_t count = 9;
  ASSERT_EQ(pm_mesh_get_corner_attribute_count(in.m, &count), PM_OK);
  EXPECT_EQ(count, 1u);
  const char* name = nullptr;
  ASSERT_EQ(pm_mesh_get_corner_attribute_name(in.m, 0, &name), PM_OK);
  EXPECT_STREQ(name, "uv");
  pm_smooth_options o;
  pm_smooth_options_init(&o);
  o.levels = 2;
  MeshGuard out;
  ASSERT_EQ(pm_smooth(in.m, &o, &out.m), PM_OK) << last();
  TriMesh cm = m;
  cm.corner_attributes = {{"uv", 2, uv}};
  SmoothOptions co;
  co.levels = 2;
  const SmoothResult ref = smooth_mesh(cm, co);
  int32_t comps = 0;
  ASSERT_EQ(pm_mesh_get_corner_attribute_components(out.m, "uv", &comps), PM_OK) << last();
  EXPECT_EQ(comps, 2);
  std::vector<float> got(6 * 16 * nt);
  ASSERT_EQ(pm_mesh_copy_corner_attribute(out.m, "uv", got.data(), 16 * nt), PM_OK) << last();
  EXPECT_EQ(got, ref.mesh.corner_attributes.at(0).values);
  // Misuse: the message names it, the mesh keeps what it had.
  EXPECT_EQ(pm_mesh_set_corner_attribute(in.m, "uv", 2, uv.data(), nt - 1), PM_STATUS_INVALID_ARGUMENT);
  EXPECT_NE(std::string(last()).find("triangle_count is " + std::to_string(nt - 1)), std::string::npos);
  std::vector<float> bad = uv;
  bad[13] = NAN;
  EXPECT_EQ(pm_mesh_set_corner_attribute(in.m, "uv", 2, bad.data(), nt), PM_STATUS_INVALID_INPUT);
  EXPECT_NE(std::string(last()).find("values[13] (triangle 2, corner 0, component 1) of corner attribute 'uv'"),
            std::string::npos);
  EXPECT_EQ(pm_mesh_set_corner_attribute(in.m, "uv", 65, uv.data(), nt), PM_STATUS_INVALID_ARGUMENT);
  EXPECT_EQ(pm_mesh_get_corner_attribute_components(in.m, "st", &comps), PM_STATUS_INVALID_ARGUMENT);
  EXPECT_NE(std::string(last()).find("no corner attribute 'st'"), std::string::npos);
  EXPECT_EQ(pm_mesh_copy_corner_attribute(out.m, "uv", got.data(), nt), PM_STATUS_INVALID_ARGUMENT);
  EXPECT_EQ(pm_mesh_get_corner_attribute_name(in.m, 1, &name), PM_STATUS_INVALID_ARGUMENT);
  std::vector<float> kept(6 * nt);
  ASSERT_EQ(pm_mesh_copy_corner_attribute(in.m, "uv", kept.data(), nt), PM_OK);
  EXPECT_EQ(kept, uv);
}

TEST(CApiSmooth, CloudAttributesReachTheTriangulationAndTheSmoothMesh) {
  // A flat hexagonal lattice: its raw triangulation is a manifold disk.
  const PointCloud c = hex_lattice(8, 7, 1.0);
  std::vector<double> p;
  for (const auto& v : c.positions) p.insert(p.end(), {v.x, v.y, v.z});
  pm_cloud* cloud = nullptr;
  ASSERT_EQ(pm_cloud_create(p.data(), nullptr, c.size(), &cloud), PM_OK);
  std::vector<float> id(c.size());
  for (size_t i = 0; i < id.size(); ++i) id[i] = float(i);
  ASSERT_EQ(pm_cloud_set_attribute(cloud, "id", 1, id.data(), c.size()), PM_OK) << last();
  EXPECT_EQ(pm_cloud_set_attribute(cloud, "id", 1, id.data(), c.size() - 1), PM_STATUS_INVALID_ARGUMENT);
  EXPECT_NE(last().find("vertex_count"), std::string::npos);
  MeshGuard tri;
  ASSERT_EQ(pm_triangulate(cloud, nullptr, &tri.m, nullptr), PM_OK) << last();
  std::vector<float> back(c.size());
  ASSERT_EQ(pm_mesh_copy_attribute(tri.m, "id", back.data(), c.size()), PM_OK) << last();
  EXPECT_EQ(back, id);  // vertex i is particle i
  pm_smooth_options o;
  pm_smooth_options_init(&o);
  o.scheme = PM_SMOOTH_BUTTERFLY;
  MeshGuard s;
  ASSERT_EQ(pm_smooth(tri.m, &o, &s.m), PM_OK) << last();
  size_t nv = 0;
  ASSERT_EQ(pm_mesh_get_counts(s.m, &nv, nullptr), PM_OK);
  std::vector<float> sid(nv);
  ASSERT_EQ(pm_mesh_copy_attribute(s.m, "id", sid.data(), nv), PM_OK);
  for (size_t i = 0; i < c.size(); ++i) EXPECT_EQ(sid[i], float(i));  // butterfly interpolates
  pm_cloud_destroy(cloud);
}

TEST(CApiSmooth, AttributeMisuse) {
  MeshGuard m{make_mesh(icosphere_mesh(0))};
  std::vector<float> v(12 * 3, 1.f);
  EXPECT_EQ(pm_mesh_set_attribute(nullptr, "a", 1, v.data(), 12), PM_STATUS_INVALID_ARGUMENT);
  EXPECT_EQ(pm_mesh_set_attribute(m.m, nullptr, 1, v.data(), 12), PM_STATUS_INVALID_ARGUMENT);
  EXPECT_EQ(pm_mesh_set_attribute(m.m, "", 1, v.data(), 12), PM_STATUS_INVALID_ARGUMENT);
  EXPECT_EQ(pm_mesh_set_attribute(m.m, "a", 0, v.data(), 12), PM_STATUS_INVALID_ARGUMENT);
  EXPECT_NE(last().find("components"), std::string::npos);
  EXPECT_EQ(pm_mesh_set_attribute(m.m, "a", 1, nullptr, 12), PM_STATUS_INVALID_ARGUMENT);
  EXPECT_EQ(pm_mesh_set_attribute(m.m, "a", 1, v.data(), 11), PM_STATUS_INVALID_ARGUMENT);
  v[7] = std::nanf("");
  EXPECT_EQ(pm_mesh_set_attribute(m.m, "a", 3, v.data(), 12), PM_STATUS_INVALID_INPUT);
  EXPECT_NE(last().find("values[7] (vertex 2, component 1)"), std::string::npos) << last();
  v[7] = 2.f;
  ASSERT_EQ(pm_mesh_set_attribute(m.m, "a", 3, v.data(), 12), PM_OK);
  ASSERT_EQ(pm_mesh_set_attribute(m.m, "a", 1, v.data(), 12), PM_OK);  // replaces
  size_t count = 0;
  ASSERT_EQ(pm_mesh_get_attribute_count(m.m, &count), PM_OK);
  EXPECT_EQ(count, 1u);
  int32_t comps = 42;
  ASSERT_EQ(pm_mesh_get_attribute_components(m.m, "a", &comps), PM_OK);
  EXPECT_EQ(comps, 1);
  comps = 42;
  EXPECT_EQ(pm_mesh_get_attribute_components(m.m, "velocity", &comps), PM_STATUS_INVALID_ARGUMENT);
  EXPECT_NE(last().find("'velocity'"), std::string::npos);
  EXPECT_EQ(comps, 42);  // untouched
  std::vector<float> out(12, -1.f);
  EXPECT_EQ(pm_mesh_copy_attribute(m.m, "a", out.data(), 11), PM_STATUS_INVALID_ARGUMENT);
  EXPECT_EQ(out[0], -1.f);
  EXPECT_EQ(pm_mesh_copy_attribute(m.m, "velocity", out.data(), 12), PM_STATUS_INVALID_ARGUMENT);
  EXPECT_EQ(pm_mesh_copy_attribute(m.m, "a", nullptr, 12), PM_STATUS_INVALID_ARGUMENT);
  const char* name = nullptr;
  EXPECT_EQ(pm_mesh_get_attribute_name(m.m, 1, &name), PM_STATUS_INVALID_ARGUMENT);
  EXPECT_EQ(name, nullptr);
  EXPECT_EQ(pm_cloud_set_attribute(nullptr, "a", 1, v.data(), 12), PM_STATUS_INVALID_ARGUMENT);
}

TEST(CApiSmooth, SmoothMisuseGivesStatusAndMessageAndLeavesTheOutputAlone) {
  MeshGuard m{make_mesh(icosphere_mesh(1))};
  pm_mesh* out = kSentinel;
  pm_smooth_options o;
  pm_smooth_options_init(&o);
  EXPECT_EQ(pm_smooth(nullptr, &o, &out), PM_STATUS_INVALID_ARGUMENT);
  EXPECT_EQ(pm_smooth(m.m, &o, nullptr), PM_STATUS_INVALID_ARGUMENT);
  o.levels = 11;
  EXPECT_EQ(pm_smooth(m.m, &o, &out), PM_STATUS_INVALID_ARGUMENT);
  EXPECT_NE(last().find("levels"), std::string::npos);
  o.levels = 10;  // 80 * 4^10 > 2^25
  EXPECT_EQ(pm_smooth(m.m, &o, &out), PM_STATUS_LIMIT_EXCEEDED);
  EXPECT_NE(last().find("max_triangles"), std::string::npos);
  pm_smooth_options_init(&o);
  o.scheme = 5;
  EXPECT_EQ(pm_smooth(m.m, &o, &out), PM_STATUS_INVALID_ARGUMENT);
  pm_smooth_options_init(&o);
  o.boundary = 2;
  EXPECT_EQ(pm_smooth(m.m, &o, &out), PM_STATUS_INVALID_ARGUMENT);
  pm_smooth_options_init(&o);
  o.struct_size = 0;
  EXPECT_EQ(pm_smooth(m.m, &o, &out), PM_STATUS_INVALID_ARGUMENT);
  EXPECT_NE(last().find("struct_size"), std::string::npos);
  pm_smooth_options_init(&o);
  o.crease_count = 1;
  EXPECT_EQ(pm_smooth(m.m, &o, &out), PM_STATUS_INVALID_ARGUMENT);
  EXPECT_NE(last().find("crease_edges"), std::string::npos);
  const int32_t bad[] = {-1, 3};
  o.crease_edges = bad;
  EXPECT_EQ(pm_smooth(m.m, &o, &out), PM_STATUS_INVALID_ARGUMENT);
  const int32_t not_edge[] = {0, 3};
  o.crease_edges = not_edge;
  EXPECT_EQ(pm_smooth(m.m, &o, &out), PM_STATUS_INVALID_ARGUMENT);
  EXPECT_NE(last().find("is not an edge"), std::string::npos);
  EXPECT_EQ(out, kSentinel);

  // Non-manifold input: a third triangle on an edge. Butterfly refuses it; Loop (the default)
  // keeps it as a sharp crease.
  TriMesh fin = icosphere_mesh(0);
  fin.positions.push_back({3, 3, 3});
  fin.triangles.push_back({fin.triangles[0][0], fin.triangles[0][1], 12});
  MeshGuard bad_mesh{make_mesh(fin)};
  pm_smooth_options bf;
  pm_smooth_options_init(&bf);
  bf.scheme = PM_SMOOTH_BUTTERFLY;
  EXPECT_EQ(pm_smooth(bad_mesh.m, &bf, &out), PM_STATUS_INVALID_INPUT);
  EXPECT_NE(last().find("non-manifold"), std::string::npos);
  EXPECT_EQ(out, kSentinel);
  pm_mesh* fin_smooth = nullptr;
  ASSERT_EQ(pm_smooth(bad_mesh.m, nullptr, &fin_smooth), PM_OK) << last();
  pm_topology_report r{};
  r.struct_size = sizeof(r);
  ASSERT_EQ(pm_mesh_report(fin_smooth, &r), PM_OK);
  EXPECT_EQ(r.nonmanifold_edges, 2u);  // the fin's edge, halved
  pm_mesh_destroy(fin_smooth);
}

TEST(CApiSmooth, CreasesThroughTheAbi) {
  const TriMesh m = icosphere_mesh(1);
  MeshGuard in{make_mesh(m)};
  const int32_t edges[] = {int32_t(m.triangles[0][0]), int32_t(m.triangles[0][1]), int32_t(m.triangles[0][1]),
                           int32_t(m.triangles[0][2])};
  const float sharp[] = {PM_CREASE_INFINITE, 1.5f};
  pm_smooth_options o;
  pm_smooth_options_init(&o);
  o.limit = 0;
  o.crease_count = 2;
  o.crease_edges = edges;
  o.crease_sharpness = sharp;
  MeshGuard out;
  ASSERT_EQ(pm_smooth(in.m, &o, &out.m), PM_OK) << last();
  SmoothOptions co;
  co.limit = false;
  co.creases = {{m.triangles[0][0], m.triangles[0][1], 10.f}, {m.triangles[0][1], m.triangles[0][2], 1.5f}};
  const SmoothResult ref = smooth_mesh(m, co);
  size_t nv = 0;
  ASSERT_EQ(pm_mesh_get_counts(out.m, &nv, nullptr), PM_OK);
  std::vector<double> pos(3 * nv);
  ASSERT_EQ(pm_mesh_copy_positions(out.m, pos.data(), nv), PM_OK);
  for (size_t i = 0; i < nv; ++i) ASSERT_EQ(pos[3 * i], ref.mesh.positions[i].x);
  // NULL sharpness = all infinitely sharp.
  o.crease_sharpness = nullptr;
  MeshGuard inf;
  ASSERT_EQ(pm_smooth(in.m, &o, &inf.m), PM_OK) << last();
}

TEST(CApiSmooth, OldCallersWithASmallerStructGetDefaultsForTheRest) {
  MeshGuard in{make_mesh(icosphere_mesh(1))};
  pm_smooth_options o;
  pm_smooth_options_init(&o);
  o.scheme = PM_SMOOTH_BUTTERFLY;
  o.levels = 2;
  o.threads = 77;  // beyond the old size: must not be read
  o.struct_size = uint32_t(offsetof(pm_smooth_options, limit));
  MeshGuard out;
  ASSERT_EQ(pm_smooth(in.m, &o, &out.m), PM_OK) << last();
  size_t nt = 0;
  ASSERT_EQ(pm_mesh_get_counts(out.m, nullptr, &nt), PM_OK);
  EXPECT_EQ(nt, 80u * 16u);
}

TEST(CApiSmooth, ProgressCallbackCancels) {
  MeshGuard in{make_mesh(icosphere_mesh(3))};
  struct State {
    int calls = 0;
    int stop_at = 1 << 30;
  } st;
  pm_smooth_options o;
  pm_smooth_options_init(&o);
  o.levels = 2;
  o.progress = [](void* user, const char* stage, double fraction) -> int {
    auto* s = static_cast<State*>(user);
    EXPECT_NE(stage, nullptr);
    EXPECT_GE(fraction, 0.0);
    EXPECT_LE(fraction, 1.0);
    return ++s->calls >= s->stop_at ? 1 : 0;
  };
  o.progress_user_data = &st;
  MeshGuard ok;
  ASSERT_EQ(pm_smooth(in.m, &o, &ok.m), PM_OK) << last();
  EXPECT_GE(st.calls, 4);
  st = State{};
  st.stop_at = 2;
  pm_mesh* out = kSentinel;
  EXPECT_EQ(pm_smooth(in.m, &o, &out), PM_STATUS_CANCELLED);
  EXPECT_EQ(out, kSentinel);
}

// ---- refine once, evaluate many -----------------------------------------------------------

namespace {

struct SmootherGuard {
  pm_smoother* s = nullptr;
  ~SmootherGuard() { pm_smoother_destroy(s); }
};

/// Everything a mesh handle holds, to compare two of them byte for byte.
struct Copied {
  std::vector<double> positions, normals;
  std::vector<int32_t> triangles;
  std::vector<float> velocity;
  bool operator==(const Copied&) const = default;
};

Copied copy_out(pm_mesh* m) {
  Copied c;
  size_t nv = 0, nt = 0;
  EXPECT_EQ(pm_mesh_get_counts(m, &nv, &nt), PM_OK);
  c.positions.resize(3 * nv);
  c.normals.resize(3 * nv);
  c.triangles.resize(3 * nt);
  c.velocity.resize(3 * nv);
  EXPECT_EQ(pm_mesh_copy_positions(m, c.positions.data(), nv), PM_OK);
  EXPECT_EQ(pm_mesh_copy_normals(m, c.normals.data(), nv), PM_OK);
  EXPECT_EQ(pm_mesh_copy_triangles(m, c.triangles.data(), nt), PM_OK);
  EXPECT_EQ(pm_mesh_copy_attribute(m, "velocity", c.velocity.data(), nv), PM_OK) << last();
  return c;
}

}  // namespace

TEST(CApiSmoother, EvaluateGivesWhatPmSmoothGives) {
  const TriMesh m = torus_mesh(1, 0.4, 24, 12);
  for (int32_t scheme : {PM_SMOOTH_LOOP, PM_SMOOTH_BUTTERFLY}) {
    SCOPED_TRACE(scheme == PM_SMOOTH_LOOP ? "loop" : "butterfly");
    pm_smooth_options o;
    pm_smooth_options_init(&o);
    o.scheme = scheme;
    o.levels = 2;
    MeshGuard first{make_mesh(m)};
    SmootherGuard s;
    ASSERT_EQ(pm_smoother_create(first.m, &o, &s.s), PM_OK) << last();
    for (int frame = 1; frame <= 3; ++frame) {
      TriMesh moved = m;
      for (size_t i = 0; i < moved.positions.size(); ++i)
        moved.positions[i] = moved.positions[i] * (1.0 + 0.03 * std::sin(frame + double(i)));
      MeshGuard in{make_mesh(moved)};
      std::vector<float> vel;
      for (const auto& p : moved.positions) vel.insert(vel.end(), {float(p.x), float(frame), float(p.z)});
      ASSERT_EQ(pm_mesh_set_attribute(in.m, "velocity", 3, vel.data(), moved.positions.size()), PM_OK);
      int32_t matches = -1;
      ASSERT_EQ(pm_smoother_matches(s.s, in.m, &matches), PM_OK);
      EXPECT_EQ(matches, 1);
      MeshGuard a, b;
      ASSERT_EQ(pm_smoother_evaluate(s.s, in.m, &a.m), PM_OK) << last();
      ASSERT_EQ(pm_smooth(in.m, &o, &b.m), PM_OK) << last();
      EXPECT_TRUE(copy_out(a.m) == copy_out(b.m)) << "frame " << frame;
    }
  }
  // NULL options: one Loop level at the limit, as pm_smooth.
  MeshGuard in{make_mesh(m)};
  SmootherGuard s;
  ASSERT_EQ(pm_smoother_create(in.m, nullptr, &s.s), PM_OK) << last();
  MeshGuard out;
  ASSERT_EQ(pm_smoother_evaluate(s.s, in.m, &out.m), PM_OK) << last();
  size_t nt = 0;
  ASSERT_EQ(pm_mesh_get_counts(out.m, nullptr, &nt), PM_OK);
  EXPECT_EQ(nt, 4 * m.triangles.size());
}

TEST(CApiSmoother, MisuseGivesStatusAndMessageAndLeavesTheOutputAlone) {
  const TriMesh m = torus_mesh(1, 0.4, 24, 12);
  MeshGuard in{make_mesh(m)};
  SmootherGuard s;
  pm_smoother* const kNoSmoother = reinterpret_cast<pm_smoother*>(0x1);
  pm_smoother* unset = kNoSmoother;
  EXPECT_EQ(pm_smoother_create(nullptr, nullptr, &unset), PM_STATUS_INVALID_ARGUMENT);
  EXPECT_EQ(last().rfind("mesh is NULL", 0), 0u) << last();
  EXPECT_EQ(pm_smoother_create(in.m, nullptr, nullptr), PM_STATUS_INVALID_ARGUMENT);
  EXPECT_EQ(last().rfind("out_smoother is NULL", 0), 0u) << last();
  pm_smooth_options o;
  pm_smooth_options_init(&o);
  o.levels = 11;
  EXPECT_EQ(pm_smoother_create(in.m, &o, &unset), PM_STATUS_INVALID_ARGUMENT);
  EXPECT_NE(last().find("levels"), std::string::npos) << last();
  EXPECT_EQ(unset, kNoSmoother);
  ASSERT_EQ(pm_smoother_create(in.m, nullptr, &s.s), PM_OK) << last();

  // Another mesh: refused by evaluate, told apart by matches.
  MeshGuard other{make_mesh(torus_mesh(1, 0.4, 20, 12))};
  int32_t matches = -1;
  ASSERT_EQ(pm_smoother_matches(s.s, other.m, &matches), PM_OK);
  EXPECT_EQ(matches, 0);
  pm_mesh* out = kSentinel;
  EXPECT_EQ(pm_smoother_evaluate(s.s, other.m, &out), PM_STATUS_INVALID_ARGUMENT);
  EXPECT_NE(last().find("does not have the triangles"), std::string::npos) << last();
  EXPECT_EQ(out, kSentinel);
  // A bad coordinate is named.
  TriMesh bad = m;
  bad.positions[5].x = 1e60;
  MeshGuard b{make_mesh(bad)};
  EXPECT_EQ(pm_smoother_evaluate(s.s, b.m, &out), PM_STATUS_INVALID_INPUT);
  EXPECT_NE(last().find("positions[5]"), std::string::npos) << last();
  EXPECT_EQ(out, kSentinel);
  // NULL arguments, each named.
  EXPECT_EQ(pm_smoother_evaluate(nullptr, in.m, &out), PM_STATUS_INVALID_ARGUMENT);
  EXPECT_EQ(last().rfind("smoother is NULL", 0), 0u) << last();
  EXPECT_EQ(pm_smoother_evaluate(s.s, nullptr, &out), PM_STATUS_INVALID_ARGUMENT);
  EXPECT_EQ(last().rfind("mesh is NULL", 0), 0u) << last();
  EXPECT_EQ(pm_smoother_evaluate(s.s, in.m, nullptr), PM_STATUS_INVALID_ARGUMENT);
  EXPECT_EQ(last().rfind("out_mesh is NULL", 0), 0u) << last();
  EXPECT_EQ(pm_smoother_matches(nullptr, in.m, &matches), PM_STATUS_INVALID_ARGUMENT);
  EXPECT_EQ(pm_smoother_matches(s.s, nullptr, &matches), PM_STATUS_INVALID_ARGUMENT);
  EXPECT_EQ(pm_smoother_matches(s.s, in.m, nullptr), PM_STATUS_INVALID_ARGUMENT);
  EXPECT_EQ(last().rfind("out_matches is NULL", 0), 0u) << last();
  pm_smoother_destroy(nullptr);  // tolerated
}
