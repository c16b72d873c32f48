// The renderer: the image of a test scene against a stored reference (made by the
// renderer and looked at), determinism, default framing, PNG round trip, errors.
#include "particlemesh/volume/render.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <limits>
#include <random>

#include "particlemesh/io/mesh_io.h"
#include "particlemesh/io/png.h"
#include "support/test_support.h"

using namespace particlemesh;

namespace {

const std::string kData = PM_TEST_DATA_DIR;

// The scene and settings of tests/data/render_scene_reference.png, which was written by
//   particlemesh render tests/data/render_scene.xyz -o tests/data/render_scene_reference.png
//       --radius 0.8 --threshold 0.5 --width 160 --height 120
RayCaster scene() {
  FieldParams p;
  p.radius = 0.8;
  p.threshold = 0.5;
  return RayCaster(ParticleField(read_point_cloud(kData + "/render_scene.xyz"), p));
}

RenderOptions small() {
  RenderOptions o;
  o.width = 160;
  o.height = 120;
  return o;
}

}  // namespace

TEST(Render, MatchesTheStoredReference) {
  const Image ref = read_png(kData + "/render_scene_reference.png");
  const RenderResult r = render(scene(), small());
  ASSERT_EQ(r.image.width, ref.width);
  ASSERT_EQ(r.image.height, ref.height);
  // Tolerance: other compilers / CPUs may round a few silhouette pixels the other way and
  // shade a level differently; a changed surface, camera or light changes far more.
  size_t off = 0;
  double sum = 0;
  for (size_t i = 0; i < ref.rgb.size(); ++i) {
    const int d = std::abs(int(r.image.rgb[i]) - int(ref.rgb[i]));
    sum += d;
    off += d > 12;
  }
  EXPECT_LE(off, ref.rgb.size() / 200) << "channels differing by more than 12 levels";
  EXPECT_LT(sum / double(ref.rgb.size()), 0.5) << "mean difference per channel";
  EXPECT_GT(r.hits, r.rays / 10);
}

TEST(Render, DoesNotDependOnTheThreadCount) {
  const RayCaster c = scene();
  RenderOptions a = small(), b = small();
  a.threads = 1;
  b.threads = 2;
  a.shading = b.shading = Shading::Normal;
  EXPECT_EQ(render(c, a).image.rgb, render(c, b).image.rgb);
}

// Anisotropic kernels render through the same caster: the same image for any thread count,
// and a different one from the spherical kernels' (flatter, smoother).
TEST(Render, AnisotropicKernelsDoNotDependOnTheThreadCount) {
  FieldParams p;
  p.radius = 0.8;
  p.threshold = 0.5;
  p.anisotropy.enabled = true;
  p.anisotropy.min_neighbors = 5;
  const RayCaster c(ParticleField(read_point_cloud(kData + "/render_scene.xyz"), p));
  EXPECT_GT(c.field().anisotropic_count(), 0u);
  RenderOptions a = small(), b = small();
  a.threads = 1;
  b.threads = 2;
  a.shading = b.shading = Shading::Normal;
  const RenderResult ra = render(c, a);
  EXPECT_EQ(ra.image.rgb, render(c, b).image.rgb);
  EXPECT_GT(ra.hits, ra.rays / 20);
  p.anisotropy.enabled = false;
  EXPECT_NE(render(RayCaster(ParticleField(read_point_cloud(kData + "/render_scene.xyz"), p)), a).image.rgb,
            ra.image.rgb);
}

TEST(Render, DefaultCameraFramesEveryParticle) {
  // A blob far from the origin, elongated: all of it is in the picture, not touching the
  // border, whatever the aspect.
  std::vector<Vec3> p;
  for (int i = 0; i < 20; ++i) p.push_back({5000.0 + 0.4 * i, -300.0, 20.0 + 0.1 * std::sin(i)});
  FieldParams fp;
  fp.radius = 0.6;
  fp.threshold = 0.5;
  const RayCaster c(ParticleField(p, fp));
  for (const auto& [w, h] : {std::pair{120, 80}, std::pair{80, 120}}) {
    RenderOptions o;
    o.width = w;
    o.height = h;
    o.shading = Shading::Normal;
    const RenderResult r = render(c, o);
    EXPECT_GT(r.hits, r.rays / 50) << w << "x" << h;
    const Image& im = r.image;
    const uint8_t* bg = im.pixel(0, 0);
    for (int x = 0; x < w; ++x)
      for (int y : {0, h - 1}) EXPECT_TRUE(std::equal(bg, bg + 3, im.pixel(x, y))) << x << "," << y;
    for (int y = 0; y < h; ++y)
      for (int x : {0, w - 1}) EXPECT_TRUE(std::equal(bg, bg + 3, im.pixel(x, y))) << x << "," << y;
  }
  const Camera cam = default_camera(c.field(), 1.5, {0, 0, 1});
  EXPECT_GT(cam.eye.z, cam.target.z);  // from above, for z up
}

TEST(Render, NormalShadingShowsTheNormal) {
  // One particle seen along -z: the centre pixel shows the normal +z, (0.5, 0.5, 1) as colour.
  FieldParams fp;
  fp.radius = 1;
  fp.threshold = 0.5;
  const RayCaster c(ParticleField({{0, 0, 0}}, fp));
  RenderOptions o;
  o.width = o.height = 41;
  o.shading = Shading::Normal;
  o.camera = Camera{{0, 0, 5}, {0, 0, 0}, {0, 1, 0}, 30};
  const RenderResult r = render(c, o);
  const uint8_t* px = r.image.pixel(20, 20);
  EXPECT_NEAR(px[0], 128, 2);
  EXPECT_NEAR(px[1], 128, 2);
  EXPECT_EQ(px[2], 255);
  // Upper part of the disc: normal with +y, so more green than red.
  const uint8_t* up = r.image.pixel(20, 14);
  EXPECT_GT(up[1], up[0] + 20);
}

TEST(Render, PngRoundTripAndErrors) {
  Image im;
  im.width = 7;
  im.height = 5;
  for (int i = 0; i < 7 * 5 * 3; ++i) im.rgb.push_back(uint8_t(i * 7));
  const auto dir = test::scratch_dir("png");
  const std::string path = (dir / "x.png").string();
  write_png(im, path);
  const Image back = read_png(path);
  EXPECT_EQ(back.width, 7);
  EXPECT_EQ(back.height, 5);
  EXPECT_EQ(back.rgb, im.rgb);
  EXPECT_THROW(read_png((dir / "missing.png").string()), Error);
  EXPECT_THROW(write_png(Image{}, path), Error);
  EXPECT_THROW(write_png(im, (dir / "no" / "such" / "dir.png").string()), Error);
  {
    std::FILE* f = std::fopen((dir / "bad.png").c_str(), "wb");
    std::fputs("not a png", f);
    std::fclose(f);
  }
  try {
    read_png((dir / "bad.png").string());
    ADD_FAILURE();
  } catch (const Error& e) {
    EXPECT_EQ(e.status(), Status::FormatError);
  }
  const RayCaster c = scene();
  RenderOptions o = small();
  o.width = 0;
  EXPECT_THROW(render(c, o), Error);
  o = small();
  o.camera = Camera{{0, 0, 0}, {0, 0, 0}, {0, 1, 0}, 40};
  EXPECT_THROW(render(c, o), Error);
  o.camera = Camera{{0, 5, 0}, {0, 0, 0}, {0, 1, 0}, 40};  // up along the view
  EXPECT_THROW(render(c, o), Error);
  // Cancelling from the progress callback.
  o = small();
  o.progress = [](std::string_view, double) { return false; };
  try {
    render(c, o);
    ADD_FAILURE() << "not cancelled";
  } catch (const Error& e) {
    EXPECT_EQ(e.status(), Status::Cancelled);
  }
  EXPECT_EQ(shading_from_name("Normal"), Shading::Normal);
  EXPECT_THROW(shading_from_name("phong"), Error);
}

// The camera's rays traced in tiles (cast_camera_rays, what render() uses) against the same
// rays cast one by one through the hierarchy (RayCaster::first_hit): the same hits, bit for
// bit, on scenes built to catch a particle a tile forgets: random clouds, the eye inside the
// supports, a thin line and a sheet seen nearly edge-on (rays grazing supports), two clumps
// far apart, a lattice whose events tie, anisotropic kernels, every kernel. 45 x 31 pixels: tiles cut by the image's edge.
namespace {

struct TileScene {
  const char* name;
  PointCloud cloud;
  FieldParams params;
  Camera camera;
};

std::vector<TileScene> tile_scenes() {
  std::vector<TileScene> s;
  std::mt19937_64 rng(12345);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  auto cloud_in_box = [&](size_t n, Vec3 lo, Vec3 hi) {
    PointCloud c;
    for (size_t i = 0; i < n; ++i)
      c.positions.push_back({lo.x + (hi.x - lo.x) * u(rng), lo.y + (hi.y - lo.y) * u(rng), lo.z + (hi.z - lo.z) * u(rng)});
    return c;
  };
  auto camera = [](Vec3 eye, Vec3 target, double fov) {
    Camera c;
    c.eye = eye;
    c.target = target;
    c.fov_degrees = fov;
    return c;
  };
  FieldParams p;
  p.radius = 0.15;
  p.threshold = 0.4;
  p.kernel = Kernel::Poly4;
  s.push_back({"random cloud, poly4", cloud_in_box(400, {0, 0, 0}, {1, 1, 1}), p, camera({2.2, 1.4, 2.6}, {0.5, 0.5, 0.5}, 35)});
  p.kernel = Kernel::Wyvill;
  s.push_back({"eye inside the cloud, wyvill", cloud_in_box(400, {0, 0, 0}, {1, 1, 1}), p, camera({0.5, 0.5, 0.5}, {1, 0.8, 0.1}, 90)});
  p.kernel = Kernel::Poly6;
  p.threshold = 0.2;
  s.push_back({"two clumps far apart, poly6",
               [&] {
                 PointCloud c = cloud_in_box(150, {0, 0, 0}, {0.4, 0.4, 0.4});
                 const PointCloud d = cloud_in_box(150, {5, 0.2, -0.3}, {5.4, 0.6, 0.1});
                 c.positions.insert(c.positions.end(), d.positions.begin(), d.positions.end());
                 return c;
               }(),
               p, camera({-2, 0.5, 1.5}, {6, 0.3, -0.1}, 30)});
  PointCloud line;
  for (int i = 0; i < 60; ++i) line.positions.push_back({0.01 * i, 0.0, 0.0});
  p = FieldParams{};
  p.radius = 0.02;
  p.threshold = 0.5;
  p.kernel = Kernel::Poly4;
  s.push_back({"a thin line seen along itself", line, p, camera({-0.3, 0.004, 0.003}, {0.6, 0.0, 0.0}, 6)});
  PointCloud sheet;
  for (int i = 0; i < 30; ++i)
    for (int j = 0; j < 30; ++j) sheet.positions.push_back({0.02 * i, 0.0005 * u(rng), 0.02 * j});
  p.radius = 0.04;
  s.push_back({"a sheet seen nearly edge-on", sheet, p, camera({0.3, 0.03, -1.5}, {0.3, 0.0, 0.3}, 25)});
  // A perfect lattice seen along a symmetry axis: the middle pixel's ray (45 x 31: px = py = 0
  // exactly) enters mirrored spheres at the same t, so events tie.
  PointCloud lattice;
  for (int i = 0; i < 6; ++i)
    for (int j = 0; j < 6; ++j)
      for (int k = 0; k < 6; ++k) lattice.positions.push_back({0.1 * i, 0.1 * j, 0.1 * k});
  p = FieldParams{};
  p.radius = 0.2;
  s.push_back({"a lattice seen along an axis", lattice, p, camera({0.25, 0.25, -1.0}, {0.25, 0.25, 0.25}, 40)});
  p = FieldParams{};
  p.radius = 0.8;
  p.threshold = 0.5;
  p.anisotropy.enabled = true;
  p.anisotropy.min_neighbors = 5;
  s.push_back({"anisotropic", read_point_cloud(kData + "/render_scene.xyz"), p, Camera{}});
  p = FieldParams{};
  p.radius = 0.2;
  p.threshold = 0.3;
  p.kernel = Kernel::Blinn;
  s.push_back({"random cloud, blinn", cloud_in_box(120, {0, 0, 0}, {1, 1, 1}), p, camera({1.8, -1.2, 2.0}, {0.5, 0.5, 0.5}, 45)});
  return s;
}

}  // namespace

TEST(CameraRays, TilesGiveTheHitsOfSingleRaysBitForBit) {
  const int W = 45, H = 31;
  for (TileScene& sc : tile_scenes()) {
    SCOPED_TRACE(sc.name);
    const RayCaster caster(ParticleField(sc.cloud, sc.params));
    Camera cam = sc.camera;
    if (norm(cam.target - cam.eye) == 0) cam = default_camera(caster.field(), double(W) / double(H));
    size_t hits = 0, differ = 0;
    for (int threads : {1, 3}) {
      const FirstHits tiles = cast_camera_rays(caster, cam, W, H, threads);
      ASSERT_EQ(tiles.t.size(), size_t(W) * size_t(H));
      hits = 0;
      for (int y = 0; y < H; ++y)
        for (int x = 0; x < W; ++x) {
          const size_t i = size_t(y) * size_t(W) + size_t(x);
          const auto one = caster.first_hit(cam.eye, camera_ray_direction(cam, W, H, x, y));
          if (!one) {
            differ += tiles.t[i] != std::numeric_limits<double>::infinity();
            continue;
          }
          ++hits;
          differ += tiles.t[i] != one->t || tiles.positions[i] != one->position || tiles.normals[i] != one->normal ||
                    tiles.entering[i] != uint8_t(one->entering);
        }
      EXPECT_EQ(tiles.hit_count, hits);
    }
    EXPECT_EQ(differ, 0u) << "pixels whose tiled hit is not the single ray's";
    // Every scene shows the surface (a blank image would prove nothing).
    EXPECT_GT(hits, size_t(W * H) / 50);
  }
}

TEST(CameraRays, RenderShowsTheTiledHits) {
  const RayCaster c = scene();
  const RenderOptions o = small();
  const RenderResult r = render(c, o);
  const FirstHits h = cast_camera_rays(c, r.camera, o.width, o.height);
  EXPECT_EQ(r.hits, h.hit_count);
  EXPECT_THROW(camera_ray_direction(r.camera, 160, 120, 160, 0), Error);
  EXPECT_THROW(cast_camera_rays(c, r.camera, 0, 120), Error);
}
