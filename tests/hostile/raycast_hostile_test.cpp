// Ray casting and rendering under hostile inputs: bad rays named by index,
// cancellation of a large batch and of a render, byte-identical hits and images for any thread
// count, and the PNG writer under a failing write.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <vector>

#include "hostile_support.h"
#include "particlemesh/io/png.h"
#include "particlemesh/sample/shapes.h"
#include "particlemesh/volume/raycast.h"
#include "particlemesh/volume/render.h"
#include "support/test_support.h"

using namespace particlemesh;
using namespace particlemesh::test;
namespace fs = std::filesystem;

namespace {

PointCloud blob_cloud(size_t n) {
  PointCloud c = fibonacci_sphere(n, 1.0);
  const size_t m = c.size();
  for (size_t i = 0; i < m; ++i) c.positions.push_back(c.positions[i] * 0.6);  // two shells
  c.normals.clear();
  return c;
}

// Rays from a sphere of origins around the cloud, towards jittered points near the centre.
void rays(size_t n, std::vector<Vec3>& o, std::vector<Vec3>& d) {
  const PointCloud s = fibonacci_sphere(n, 3.0);
  o = s.positions;
  d.resize(n);
  for (size_t i = 0; i < n; ++i)
    d[i] = Vec3{0.3 * std::sin(double(i)), 0.3 * std::cos(1.7 * double(i)), 0.2 * std::sin(0.3 * double(i))} - o[i];
}

}  // namespace

TEST(RaycastHostile, BadRaysAndRangesAreNamed) {
  const RayCaster caster(ParticleField(blob_cloud(500), {}));
  std::vector<Vec3> o, d;
  rays(40, o, d);
  d[12] = {0, 0, 0};
  PM_EXPECT_ERROR(cast_first_hits(caster, o.data(), d.data(), o.size()), Status::InvalidArgument, "directions[12]");
  d[12] = {1, 0, 0};
  o[7].y = NAN;
  PM_EXPECT_ERROR(cast_all_hits(caster, o.data(), d.data(), o.size()), Status::InvalidArgument, "origins[7]");
  o[7].y = 0;
  RaycastOptions ro;
  ro.t_min = 2;
  ro.t_max = 1;
  EXPECT_NE(status_of([&] { cast_first_hits(caster, o.data(), d.data(), o.size(), ro); }), Status::Ok);
  ro.t_min = NAN;
  EXPECT_EQ(status_of([&] { cast_first_hits(caster, o.data(), d.data(), o.size(), ro); }), Status::InvalidArgument);
  PointCloud bad = blob_cloud(100);
  bad.positions[42].z = INFINITY;
  PM_EXPECT_ERROR(ParticleField(bad, {}), Status::InvalidInput, "positions[42]");
  FieldParams p;
  p.radii.assign(200, 0.3);
  p.radii[9] = 0;
  PM_EXPECT_ERROR(ParticleField(blob_cloud(100), p), Status::InvalidArgument, "radii[9]");
  p.radii.resize(10);
  PM_EXPECT_ERROR(ParticleField(blob_cloud(100), p), Status::InvalidArgument, "radii");
}

TEST(Cancellation, RaycastBatchAndRender) {
  const RayCaster caster(ParticleField(blob_cloud(kSanitized ? 20000 : 100000), {}));
  std::vector<Vec3> o, d;
  rays(kSanitized ? 12000 : 120000, o, d);  // a few seconds of CPU either way
  const ProgressTrace cast = expect_prompt_cancellation("cast_all_hits", [&](const ProgressCallback& p) {
    RaycastOptions ro;
    ro.progress = p;
    cast_all_hits(caster, o.data(), d.data(), o.size(), ro);
  });
  // The callbacks come all through the batch, not only at its ends, however fast the machine
  // (a call shorter than the latency bound would pass the bound without them).
  EXPECT_LT(cast.longest_gap, cast.cpu / 8) << cast.gap_stage;
  const ProgressTrace image = expect_prompt_cancellation("render", [&](const ProgressCallback& p) {
    RenderOptions ro;
    ro.width = kSanitized ? 200 : 1024;
    ro.height = kSanitized ? 150 : 768;
    ro.progress = p;
    render(caster, ro);
  });
  EXPECT_LT(image.longest_gap, image.cpu / 4) << image.gap_stage;
}

TEST(Determinism, RaycastAndRender) {
  FieldParams fp;
  const PointCloud c = blob_cloud(3000);
  for (size_t i = 0; i < c.size(); ++i) fp.radii.push_back(0.12 + 0.05 * std::abs(std::sin(double(i))));
  const RayCaster caster(ParticleField(c, fp));
  std::vector<Vec3> o, d;
  rays(20000, o, d);
  uint64_t first = 0, first_img = 0;
  for (int t : {1, 2, 3, 0, 1, 0}) {
    RaycastOptions ro;
    ro.threads = t;
    const AllHits h = cast_all_hits(caster, o.data(), d.data(), o.size(), ro);
    TriMesh m;  // hash the hits through the mesh hasher
    for (const RayHit& x : h.hits) m.positions.push_back(x.position), m.normals.push_back(x.normal);
    for (uint64_t v : h.offsets) m.positions.push_back({double(v), 0, 0});
    const uint64_t hash = mesh_hash(m);
    if (first == 0) first = hash;
    EXPECT_EQ(hash, first) << "threads = " << t;
    RenderOptions r;
    r.width = 160;
    r.height = 120;
    r.threads = t;
    const Image img = render(caster, r).image;
    TriMesh im;
    for (size_t i = 0; i + 2 < img.rgb.size(); i += 3) im.positions.push_back({double(img.rgb[i]), double(img.rgb[i + 1]), double(img.rgb[i + 2])});
    const uint64_t ih = mesh_hash(im);
    if (first_img == 0) first_img = ih;
    EXPECT_EQ(ih, first_img) << "threads = " << t;
  }
}
