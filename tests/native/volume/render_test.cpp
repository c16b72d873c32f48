// The renderer (issue 8): the image of a test scene against a stored reference (made by the
// renderer and looked at), determinism, default framing, PNG round trip, errors.
#include "particlemesh/volume/render.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>

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
