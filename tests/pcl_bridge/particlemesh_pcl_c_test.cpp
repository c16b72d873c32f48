// particlemesh_pcl/particlemesh_pcl_c.h: pm_pcl_read_cloud gives the same particles as
// loadParticles as an ordinary pm_cloud (normals, "color" in [0, 1], NaN points dropped and
// counted), bad files fail with a status and a message naming the file, outputs untouched,
// no exception crosses; pm_pcl_preprocess gives what particlemesh_pcl::preprocess gives.
#include "particlemesh_pcl/particlemesh_pcl_c.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "particlemesh_pcl/io.h"
#include "particlemesh_pcl/preprocessing.h"
#include "support/test_support.h"

namespace {

std::string last() { return pm_pcl_last_error_message(); }

pm_pcl_read_info new_info() {
  pm_pcl_read_info info;
  std::memset(&info, 0xab, sizeof info);
  info.struct_size = sizeof info;
  return info;
}

std::vector<float> copy_attribute(const pm_cloud* c, const char* name, int32_t components) {
  int32_t got = 0;
  EXPECT_EQ(pm_cloud_get_attribute_components(c, name, &got), PM_OK) << pm_last_error_message();
  EXPECT_EQ(got, components);
  size_t n = 0;
  EXPECT_EQ(pm_cloud_get_count(c, &n), PM_OK);
  std::vector<float> v(n * size_t(components));
  EXPECT_EQ(pm_cloud_copy_attribute(c, name, v.data(), n), PM_OK) << pm_last_error_message();
  return v;
}

}  // namespace

TEST(PclBridgeC, AbiVersion) { EXPECT_EQ(pm_pcl_abi_version(), uint32_t(PM_PCL_ABI_VERSION)); }

TEST(PclBridgeC, ColoredCloudMatchesLoadParticles) {
  PM_REQUIRE_DATA(path, "pcd/colored_cloud.pcd");
  pm_cloud* c = nullptr;
  pm_pcl_read_info info = new_info();
  ASSERT_EQ(pm_pcl_read_cloud(path.c_str(), &c, &info), PM_OK) << last();
  EXPECT_STREQ(pm_pcl_last_error_message(), "");
  EXPECT_EQ(info.struct_size, sizeof info);
  EXPECT_EQ(info.input_points, 1000u);
  EXPECT_EQ(info.valid_points, 1000u);
  EXPECT_EQ(info.invalid_points, 0u);
  EXPECT_EQ(info.width, 1u);
  EXPECT_EQ(info.height, 1000u);
  EXPECT_EQ(info.has_normals, 1);
  EXPECT_EQ(info.has_color, 1);
  EXPECT_EQ(info.has_intensity, 0);

  const particlemesh::PointCloud ref = particlemesh_pcl::loadParticles(path);
  size_t n = 0;
  ASSERT_EQ(pm_cloud_get_count(c, &n), PM_OK);
  ASSERT_EQ(n, ref.size());
  std::vector<float> p(3 * n), nrm(3 * n);
  ASSERT_EQ(pm_cloud_copy_positions_f32(c, p.data(), n), PM_OK);
  ASSERT_EQ(pm_cloud_copy_normals_f32(c, nrm.data(), n), PM_OK);
  for (size_t i = 0; i < n; ++i) {
    EXPECT_FLOAT_EQ(p[3 * i], float(ref.positions[i].x)) << i;
    EXPECT_FLOAT_EQ(p[3 * i + 2], float(ref.positions[i].z)) << i;
    EXPECT_FLOAT_EQ(nrm[3 * i + 1], float(ref.normals[i].y)) << i;
  }
  size_t count = 0;
  ASSERT_EQ(pm_cloud_get_attribute_count(c, &count), PM_OK);
  ASSERT_EQ(count, 2u);  // the colour, and the file's curvature field
  const char* name = nullptr;
  ASSERT_EQ(pm_cloud_get_attribute_name(c, 0, &name), PM_OK);
  EXPECT_STREQ(name, "color");
  ASSERT_EQ(pm_cloud_get_attribute_name(c, 1, &name), PM_OK);
  EXPECT_STREQ(name, "curvature");
  const std::vector<float> colour = copy_attribute(c, "color", 3);
  ASSERT_EQ(ref.attributes.size(), 2u);
  EXPECT_EQ(colour, ref.attributes[0].values);
  EXPECT_EQ(copy_attribute(c, "curvature", 1), ref.attributes[1].values);
  float lo = 1, hi = 0;
  for (float x : colour) lo = std::min(lo, x), hi = std::max(hi, x);
  EXPECT_GE(lo, 0.0f);
  EXPECT_LE(hi, 1.0f);
  EXPECT_GT(hi - lo, 0.5f);  // real colours, not one value
  pm_cloud_destroy(c);
}

TEST(PclBridgeC, KinectFrameDropsItsNaNPointsAndKeepsColour) {
  PM_REQUIRE_DATA(path, "pcd/kinect_frame_20121214T142255.814212.pcd");
  pm_cloud* c = nullptr;
  pm_pcl_read_info info = new_info();
  ASSERT_EQ(pm_pcl_read_cloud(path.c_str(), &c, &info), PM_OK) << last();
  // DATA.md: organized 640x480, 307200 points of which 35625 are NaN.
  EXPECT_EQ(info.width, 640u);
  EXPECT_EQ(info.height, 480u);
  EXPECT_EQ(info.input_points, 307200u);
  EXPECT_EQ(info.invalid_points, 35625u);
  EXPECT_EQ(info.valid_points, 307200u - 35625u);
  EXPECT_EQ(info.has_normals, 0);
  EXPECT_EQ(info.has_color, 1);
  size_t n = 0;
  ASSERT_EQ(pm_cloud_get_count(c, &n), PM_OK);
  EXPECT_EQ(n, 307200u - 35625u);
  int32_t has_normals = 1;
  ASSERT_EQ(pm_cloud_has_normals(c, &has_normals), PM_OK);
  EXPECT_EQ(has_normals, 0);
  std::vector<float> p(3 * n);
  ASSERT_EQ(pm_cloud_copy_positions_f32(c, p.data(), n), PM_OK);
  for (size_t i = 0; i < n; ++i) ASSERT_TRUE(p[3 * i + 2] > 0.6f && p[3 * i + 2] < 1.8f) << i;  // z 0.67..1.71
  EXPECT_EQ(copy_attribute(c, "color", 3).size(), 3 * n);
  pm_cloud_destroy(c);
}

TEST(PclBridgeC, OtherFormatsGoThroughTheCoreReader) {
  PM_REQUIRE_DATA(path, "points/spot_poisson.ply");
  pm_cloud* c = nullptr;
  ASSERT_EQ(pm_pcl_read_cloud(path.c_str(), &c, nullptr), PM_OK) << last();  // info may be NULL
  size_t n = 0;
  ASSERT_EQ(pm_cloud_get_count(c, &n), PM_OK);
  EXPECT_EQ(n, 8747u);
  pm_cloud_destroy(c);
}

TEST(PclBridgeC, BadFilesFailNamingTheFileWithOutputsUntouched) {
  const auto dir = particlemesh::test::scratch_dir("pcd");
  const std::string truncated = (dir / "truncated.pcd").string();
  std::ofstream(truncated) << "VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\n"
                              "WIDTH 3\nHEIGHT 1\nPOINTS 3\nDATA ascii\n0 0 0\n1 0 0\n";
  const std::string not_pcd = (dir / "hello.pcd").string();
  std::ofstream(not_pcd) << "hello world\n";
  const std::string all_nan = (dir / "all_nan.pcd").string();
  std::ofstream(all_nan) << "VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\n"
                            "WIDTH 2\nHEIGHT 1\nPOINTS 2\nDATA ascii\nnan nan nan\nnan 0 0\n";
  struct Case { std::string path; pm_status status; const char* words; };
  for (const Case& k : {Case{truncated, PM_STATUS_FORMAT_ERROR, "truncated data"},
                        Case{not_pcd, PM_STATUS_FORMAT_ERROR, "not a PCD file"},
                        Case{all_nan, PM_STATUS_INVALID_INPUT, "no valid point"},
                        Case{(dir / "missing.pcd").string(), PM_STATUS_IO_ERROR, "no such file"}}) {
    SCOPED_TRACE(k.path);
    pm_cloud* sentinel = reinterpret_cast<pm_cloud*>(0x1);
    pm_cloud* c = sentinel;
    pm_pcl_read_info info = new_info();
    const pm_pcl_read_info before = info;
    EXPECT_EQ(pm_pcl_read_cloud(k.path.c_str(), &c, &info), k.status);
    EXPECT_NE(last().find(k.path), std::string::npos) << last();
    EXPECT_NE(last().find(k.words), std::string::npos) << last();
    EXPECT_EQ(c, sentinel);
    EXPECT_EQ(std::memcmp(&info, &before, sizeof info), 0);
  }
}

TEST(PclBridgeC, NullArgumentsAndBadStructSize) {
  PM_REQUIRE_DATA(path, "pcd/bun0.pcd");
  pm_cloud* c = nullptr;
  EXPECT_EQ(pm_pcl_read_cloud(nullptr, &c, nullptr), PM_STATUS_INVALID_ARGUMENT);
  EXPECT_NE(last().find("path is NULL"), std::string::npos) << last();
  EXPECT_EQ(pm_pcl_read_cloud(path.c_str(), nullptr, nullptr), PM_STATUS_INVALID_ARGUMENT);
  EXPECT_NE(last().find("out_cloud is NULL"), std::string::npos) << last();
  pm_pcl_read_info info{};
  EXPECT_EQ(pm_pcl_read_cloud(path.c_str(), &c, &info), PM_STATUS_INVALID_ARGUMENT);
  EXPECT_NE(last().find("struct_size"), std::string::npos) << last();
  EXPECT_EQ(c, nullptr);
}

TEST(PclBridgeC, AnOlderCallersSmallerInfoGetsItsPrefixOnly) {
  PM_REQUIRE_DATA(path, "pcd/bun0.pcd");
  // A caller built when the struct ended after valid_points.
  struct Old {
    pm_pcl_read_info head;
  } old;
  std::memset(&old, 0xcd, sizeof old);
  const size_t prefix = offsetof(pm_pcl_read_info, invalid_points);
  old.head.struct_size = uint32_t(prefix);
  pm_cloud* c = nullptr;
  ASSERT_EQ(pm_pcl_read_cloud(path.c_str(), &c, &old.head), PM_OK) << last();
  EXPECT_EQ(old.head.struct_size, prefix);
  EXPECT_EQ(old.head.input_points, 397u);
  EXPECT_EQ(old.head.valid_points, 397u);
  const auto* bytes = reinterpret_cast<const unsigned char*>(&old.head);
  for (size_t i = prefix; i < sizeof old.head; ++i) ASSERT_EQ(bytes[i], 0xcd) << i;  // not written
  int32_t has_normals = 0;
  ASSERT_EQ(pm_cloud_has_normals(c, &has_normals), PM_OK);
  EXPECT_EQ(has_normals, 1);
  pm_cloud_destroy(c);
}

namespace {

/// A unit sphere of `n` Fibonacci points moved radially by noise of 1 % of its radius (a
/// scanner's noise across the surface), with an "id" channel.
particlemesh::PointCloud noisy_sphere(size_t n) {
  particlemesh::PointCloud c;
  particlemesh::VertexAttribute id{"id", 1, {}};
  uint64_t state = 12345;
  for (size_t i = 0; i < n; ++i) {
    const double z = 1 - 2 * (double(i) + 0.5) / double(n), r = std::sqrt(1 - z * z);
    const double phi = double(i) * M_PI * (3 - std::sqrt(5.0));
    state = state * 6364136223846793005ull + 1442695040888963407ull;
    const double s = 1 + 0.01 * (double(state >> 11) / double(1ull << 53) - 0.5) * 2;
    c.positions.push_back(particlemesh::Vec3{r * std::cos(phi), r * std::sin(phi), z} * s);
    id.values.push_back(float(i));
  }
  c.attributes.push_back(id);
  return c;
}

pm_cloud* to_handle(const particlemesh::PointCloud& c) {
  std::vector<double> xyz;
  for (const auto& p : c.positions) xyz.insert(xyz.end(), {p.x, p.y, p.z});
  pm_cloud* h = nullptr;
  EXPECT_EQ(pm_cloud_create(xyz.data(), nullptr, c.size(), &h), PM_OK) << pm_last_error_message();
  for (const auto& a : c.attributes)
    EXPECT_EQ(pm_cloud_set_attribute(h, a.name.c_str(), a.components, a.values.data(), c.size()), PM_OK);
  return h;
}

}  // namespace

// pm_pcl_preprocess is particlemesh_pcl::preprocess behind the C ABI: the same points, normals,
// channels, kept indices and counts; bad parameters fail naming them, the output untouched.
TEST(PclBridgeC, PreprocessGivesWhatPreprocessGives) {
  const particlemesh::PointCloud input = noisy_sphere(8000);
  particlemesh_pcl::PreprocessOptions o;
  o.remove_outliers = true;
  o.mls_radius = 0.08;
  o.estimate_normals = true;
  o.viewpoint[2] = 0.25f;  // inside: the normals face inward
  particlemesh::PointCloud expected = input;
  std::vector<uint32_t> expected_kept;
  const particlemesh_pcl::PreprocessReport want = particlemesh_pcl::preprocess(expected, o, &expected_kept);
  ASSERT_GT(want.outliers_removed, 0u);
  ASSERT_GT(want.smoothed, 0u);

  pm_pcl_preprocess_options c;
  pm_pcl_preprocess_options_init(&c);
  EXPECT_EQ(c.struct_size, sizeof c);
  EXPECT_EQ(c.remove_outliers, 0);
  EXPECT_EQ(c.outlier_mean_k, 50);
  EXPECT_EQ(c.downsampling, PM_PCL_DOWNSAMPLE_NONE);
  c.remove_outliers = 1;
  c.mls_radius = 0.08;
  c.estimate_normals = 1;
  c.viewpoint[2] = 0.25f;
  pm_cloud* in = to_handle(input);
  pm_cloud* out = nullptr;
  std::vector<uint32_t> kept(input.size(), 0xffffffffu);
  pm_pcl_preprocess_report report;
  report.struct_size = sizeof report;
  ASSERT_EQ(pm_pcl_preprocess(in, &c, &out, kept.data(), &report), PM_OK) << last();
  EXPECT_EQ(report.input_points, input.size());
  EXPECT_EQ(report.outliers_removed, want.outliers_removed);
  EXPECT_EQ(report.smoothed, want.smoothed);
  EXPECT_EQ(report.smoothing_max_shift, want.smoothing_max_shift);
  EXPECT_EQ(report.output_points, expected.size());
  EXPECT_EQ(report.normals_estimated, 1);
  kept.resize(expected.size());
  EXPECT_EQ(kept, expected_kept);
  size_t n = 0;
  ASSERT_EQ(pm_cloud_get_count(out, &n), PM_OK);
  ASSERT_EQ(n, expected.size());
  std::vector<double> xyz(3 * n), normals(3 * n);
  ASSERT_EQ(pm_cloud_copy_positions(out, xyz.data(), n), PM_OK);
  ASSERT_EQ(pm_cloud_copy_normals(out, normals.data(), n), PM_OK);
  size_t inward = 0;
  for (size_t i = 0; i < n; ++i) {
    ASSERT_EQ(xyz[3 * i], expected.positions[i].x) << i;
    ASSERT_EQ(xyz[3 * i + 2], expected.positions[i].z) << i;
    ASSERT_EQ(normals[3 * i + 1], expected.normals[i].y) << i;
    inward += normals[3 * i] * xyz[3 * i] + normals[3 * i + 1] * xyz[3 * i + 1] + normals[3 * i + 2] * xyz[3 * i + 2] < 0;
  }
  EXPECT_EQ(inward, n);
  const std::vector<float> id = copy_attribute(out, "id", 1);
  for (size_t i = 0; i < n; ++i) ASSERT_EQ(id[i], float(kept[i])) << i;
  pm_cloud_destroy(out);

  // NULL options: every step off, a copy.
  out = nullptr;
  ASSERT_EQ(pm_pcl_preprocess(in, nullptr, &out, nullptr, nullptr), PM_OK) << last();
  ASSERT_EQ(pm_cloud_get_count(out, &n), PM_OK);
  EXPECT_EQ(n, input.size());
  pm_cloud_destroy(out);

  // Bad parameters: a status, a message naming what, *out_cloud untouched.
  pm_cloud* sentinel = reinterpret_cast<pm_cloud*>(0x1);
  out = sentinel;
  pm_pcl_preprocess_options bad = c;
  bad.downsampling = 7;
  EXPECT_EQ(pm_pcl_preprocess(in, &bad, &out, nullptr, nullptr), PM_STATUS_INVALID_ARGUMENT);
  EXPECT_NE(last().find("options->downsampling is 7"), std::string::npos) << last();
  bad = c;
  bad.downsampling = PM_PCL_DOWNSAMPLE_VOXEL_GRID;
  EXPECT_EQ(pm_pcl_preprocess(in, &bad, &out, nullptr, nullptr), PM_STATUS_INVALID_ARGUMENT);
  EXPECT_NE(last().find("leaf size > 0"), std::string::npos) << last();
  bad = c;
  bad.viewpoint[0] = std::nanf("");
  EXPECT_EQ(pm_pcl_preprocess(in, &bad, &out, nullptr, nullptr), PM_STATUS_INVALID_ARGUMENT);
  EXPECT_NE(last().find("viewpoint"), std::string::npos) << last();
  bad.struct_size = 0;
  EXPECT_EQ(pm_pcl_preprocess(in, &bad, &out, nullptr, nullptr), PM_STATUS_INVALID_ARGUMENT);
  EXPECT_NE(last().find("struct_size"), std::string::npos) << last();
  EXPECT_EQ(pm_pcl_preprocess(nullptr, &c, &out, nullptr, nullptr), PM_STATUS_INVALID_ARGUMENT);
  EXPECT_EQ(out, sentinel);
  // An older caller's options ending before the downsampling: the rest from the defaults.
  pm_pcl_preprocess_options old = c;
  old.struct_size = uint32_t(offsetof(pm_pcl_preprocess_options, downsampling));
  old.downsampling = 7;  // past the caller's struct: not read
  out = nullptr;
  ASSERT_EQ(pm_pcl_preprocess(in, &old, &out, nullptr, &report), PM_OK) << last();
  EXPECT_EQ(report.outliers_removed, want.outliers_removed);
  EXPECT_EQ(report.smoothed, 0u);
  EXPECT_EQ(report.normals_estimated, 0);
  pm_cloud_destroy(out);
  pm_cloud_destroy(in);
}
