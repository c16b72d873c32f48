// Values at the edges of what the library computes with: normals without a direction,
// coordinates beyond float32's range or below its normal numbers, lengths too small or too
// large for double-precision geometry, messages about absurd numbers; the polygonizer's
// memory budget over the output mesh too; and cancellation where one point's (or one ray's)
// work is huge.
#include <gtest/gtest.h>

#include <cfloat>
#include <cmath>
#include <filesystem>
#include <fstream>

#include "hostile_support.h"
#include "particlemesh/io/mesh_io.h"
#include "particlemesh/mesh/topology_report.h"
#include "particlemesh/sample/shapes.h"
#include "particlemesh/sample/thin.h"
#include "particlemesh/surface/reconstruct.h"
#include "particlemesh/surface/triangulate.h"
#include "particlemesh/volume/polygonize.h"
#include "particlemesh/volume/raycast.h"
#include "particlemesh/volume/render.h"
#include "support/test_support.h"

using namespace particlemesh;
using namespace particlemesh::test;
namespace fs = std::filesystem;

namespace {

PointCloud sphere_sample() { return poisson_disk_sample(icosphere_mesh(4), 0.08, 3); }

PointCloud scaled(PointCloud c, double s) {
  for (Vec3& p : c.positions) p = p * s;
  return c;
}

std::string head_of(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::string s(400, '\0');
  in.read(s.data(), 400);
  return s.substr(0, size_t(in.gcount()));
}

}  // namespace

// A normal without a direction (all zero, or subnormal) is a particle without a normal: the
// surface stage estimates it. Before, zero normals were used as normals: a sphere came out in
// open pieces (auto), or with no triangle and exit 0 (input). With normals = input they are an
// error naming the particle.
TEST(Values, NormalsWithoutADirectionAreMissingNormals) {
  PointCloud c = sphere_sample();
  ASSERT_TRUE(c.has_normals());
  const PointCloud good = c;
  for (Vec3& n : c.normals) n = {0, 0, 0};
  SurfaceResult r = reconstruct_surface(c);
  TopologyReport t = topology_report(r.mesh);
  EXPECT_EQ(t.components, 1u);
  EXPECT_EQ(t.closed_components, 1u);
  EXPECT_TRUE(t.outward);
  // Float32 subnormals (what a float PLY's "1e-45" is) are no direction either; half of the
  // particles with their true normals and half without still face out.
  c = good;
  for (size_t i = 0; i < c.size(); ++i)
    if (i % 2) c.normals[i] = {double(std::numeric_limits<float>::denorm_min()), 0, -1e-39};
  t = topology_report(reconstruct_surface(c).mesh);
  EXPECT_EQ(t.closed_components, 1u);
  EXPECT_TRUE(t.outward);
  SurfaceOptions o;
  o.normals = SurfaceOptions::NormalSource::Input;
  PM_EXPECT_ERROR(reconstruct_surface(c, o), Status::InvalidInput,
                  "normals = input, but normals[1] has no direction (zero, or shorter than 1.2e-38)");
  EXPECT_EQ(topology_report(reconstruct_surface(good, o).mesh).closed_components, 1u);
}

// Coordinates beyond float32 (1e39) were written as inf into float32 files with exit 0;
// coordinates float32 holds only as subnormals (1e-44) came back on a coarse lattice with
// degenerate triangles. Both are written as float64 now, and read back exactly.
TEST(Values, CoordinatesFloat32CannotHoldAreWrittenAsDouble) {
  const auto dir = scratch_dir("float");
  const TriMesh unit = reconstruct_surface(sphere_sample()).mesh;
  for (double s : {1e39, 1e-44}) {
    TriMesh m = unit;
    for (Vec3& p : m.positions) p = p * s;
    for (const char* name : {"m.ply", "a.ply", "m.obj"}) {
      SCOPED_TRACE(std::to_string(s) + " " + name);
      const fs::path p = dir / name;
      write_mesh(m, p.string(), {std::string(name) == "a.ply" ? MeshFormat::PlyAscii : MeshFormat::Auto, true, {}});
      if (std::string(name) != "m.obj") {
        EXPECT_NE(head_of(p).find("property double x"), std::string::npos);
      }
      const TriMesh back = read_mesh(p.string());
      ASSERT_EQ(back.positions.size(), m.positions.size());
      for (size_t i = 0; i < m.positions.size(); ++i) ASSERT_EQ(back.positions[i], m.positions[i]) << i;
      const TopologyReport t = topology_report(back);
      EXPECT_EQ(t.degenerate_triangles, 0u);
      EXPECT_EQ(t.closed_components, 1u);
    }
  }
}

// Lengths whose squares and fourth powers double holds mesh as at unit scale; beyond that
// range the error says so (before: "all points coincide" at 1e-300, and at 1e-100 a mesh
// without a triangle, silently).
TEST(Values, LengthsOutsideWhatDoubleGeometryHoldsAreNamed) {
  const PointCloud c = sphere_sample();
  const TriangulateResult unit = triangulate_raw(c);
  for (double s : {1e-44, 1e44}) {
    SCOPED_TRACE(s);
    const TriangulateResult r = triangulate_raw(scaled(c, s));
    EXPECT_EQ(canonical(r.mesh.triangles), canonical(unit.mesh.triangles));
  }
  for (double s : {1e-300, 1e-100, 1e-60}) {
    SCOPED_TRACE(s);
    PM_EXPECT_ERROR(triangulate_raw(scaled(c, s)), Status::InvalidInput, "below the 1e-50 that the geometry resolves");
  }
  PM_EXPECT_ERROR(triangulate_raw(scaled(c, 1e75)), Status::LimitExceeded, "above the 1e+50");
  TriangulateOptions o;
  o.spacing = 1e-70;
  PM_EXPECT_ERROR(triangulate_raw(scaled(c, 1e-68), o), Status::InvalidInput, "the particle spacing r0 is 1e-70");
}

// Numbers in messages are %g-like: no 300 digits (std::to_string(1e300)), no "cells of size
// 0.000000", and no "use a larger spacing" where the cells follow a radius.
TEST(Values, MessagesShowNumbersReadably) {
  PointCloud c = fibonacci_sphere(1000);
  c.normals.clear();
  c.positions.push_back({1e300, -1e300, 0});
  TriangulateOptions o;
  o.spacing = 0.1;
  std::string msg;
  EXPECT_EQ(status_of([&] { triangulate_raw(c, o); }, &msg), Status::LimitExceeded);
  EXPECT_LT(msg.size(), 400u) << msg;  // one number of 300 digits would pass it
  EXPECT_NE(msg.find("e+300 cells of size"), std::string::npos) << msg;
  EXPECT_NE(msg.find("a larger spacing"), std::string::npos) << msg;
  EXPECT_EQ(status_of([&] { thin_points(c.positions.data(), 1000, 1e-8); }, &msg), Status::LimitExceeded);
  EXPECT_NE(msg.find("cells of size 4e-08"), std::string::npos) << msg;
  EXPECT_EQ(msg.find("0.000000"), std::string::npos) << msg;
  PolygonizeOptions po;
  po.radius = 1e-9;
  po.max_grid_bytes = 0;
  EXPECT_EQ(status_of([&] { polygonize(c, po); }, &msg), Status::LimitExceeded);
  EXPECT_EQ(msg.find("spacing"), std::string::npos) << msg;
  EXPECT_NE(msg.find("radius"), std::string::npos) << msg;
  EXPECT_LT(msg.size(), 400u) << msg;
}

// The budget covers the output mesh too (before: the sampled grid only; tiny radii over many
// particles made a mesh of gigabytes on top of a grid under the budget).
TEST(PolygonizeLimits, TheMeshCountsAgainstTheBudget) {
  PointCloud c;  // 125 separate blobs, each a small sphere mesh
  for (int i = 0; i < 125; ++i) c.positions.push_back({double(i % 5) * 10, double((i / 5) % 5) * 10, double(i / 25) * 10});
  PolygonizeOptions o;
  o.radius = 1;
  o.threshold = 0.2;
  o.cell_size = 0.1;
  o.max_grid_bytes = 0;
  const PolygonizeResult ok = polygonize(c, o);
  ASSERT_GT(ok.mesh.triangles.size(), 125u * 100);
  const double mesh_bytes = double(ok.mesh.positions.size()) * 48 + double(ok.mesh.triangles.size()) * 12;
  EXPECT_GT(double(ok.stats.grid_bytes), mesh_bytes);
  o.max_grid_bytes = ok.stats.grid_bytes - 1;
  PM_EXPECT_ERROR(polygonize(c, o), Status::LimitExceeded, "the mesh would need");
  o.max_grid_bytes = ok.stats.grid_bytes;
  EXPECT_EQ(polygonize(c, o).mesh.triangles, ok.mesh.triangles);
}

// With the limits lifted (L = 100 r0, any number of neighbours and triplets) one point's
// triplets take seconds: the cancel flag is checked inside them. Before, a request waited for
// the whole test (SIGTERM took 441 s on 2000 points).
TEST(Cancellation, OnePointsTripletsWithTheLimitsLifted) {
  const PointCloud c = fibonacci_sphere(600);
  TriangulateOptions o;
  o.max_edge_factor = 100;
  o.max_neighbors = 100000;
  o.max_triplets_per_point = 0;
  Status status = Status::Ok;
  std::string stage;
  const double latency = cancel_after(0.3, [&](const ProgressCallback& p) {
    o.progress = p;
    triangulate_raw(c, o);
  }, &status, &stage);
  std::printf("cancelled in %s: returned after %.3f s\n", stage.c_str(), latency);
  EXPECT_EQ(status, Status::Cancelled);
  EXPECT_GE(latency, 0.0);
  EXPECT_LT(latency, 2.0);
}

// A radius covering every particle, rays cast from inside the blob: each ray sums thousands of
// particles on each of thousands of intervals (seconds per ray). Cancellation was checked per
// image row (render) and per 256 rays (batches); now within a ray, every 32 intervals.
TEST(Cancellation, RaysThroughAHugeRadius) {
  FieldParams fp;
  fp.radius = 3;
  const RayCaster caster(ParticleField(fibonacci_sphere(kSanitized ? 10000 : 30000), fp));
  RenderOptions ro;
  ro.width = 64;
  ro.height = 8;
  Camera cam;  // at the centre of the particles, inside the iso-surface
  cam.eye = {0, 0, 0};
  cam.target = {0, 0, 1};
  ro.camera = cam;
  Status status = Status::Ok;
  double latency = cancel_after(0.3, [&](const ProgressCallback& p) {
    ro.progress = p;
    render(caster, ro);
  }, &status);
  std::printf("render cancelled: returned after %.3f s\n", latency);
  EXPECT_EQ(status, Status::Cancelled);
  EXPECT_GE(latency, 0.0);
  EXPECT_LT(latency, 2.0);
  std::vector<Vec3> origins(64, Vec3{0, 0, 0}), directions;
  for (int i = 0; i < 64; ++i) directions.push_back(normalized(Vec3{std::cos(i * 0.1), std::sin(i * 0.1), 0.3}));
  latency = cancel_after(0.3, [&](const ProgressCallback& p) {
    RaycastOptions o;
    o.progress = p;
    cast_all_hits(caster, origins.data(), directions.data(), origins.size(), o);
  }, &status);
  std::printf("cast_all_hits cancelled: returned after %.3f s\n", latency);
  EXPECT_EQ(status, Status::Cancelled);
  EXPECT_GE(latency, 0.0);
  EXPECT_LT(latency, 2.0);
}
