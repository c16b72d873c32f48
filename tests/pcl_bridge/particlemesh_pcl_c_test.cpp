// particlemesh_pcl/particlemesh_pcl_c.h: pm_pcl_read_cloud gives the same particles as
// loadParticles as an ordinary pm_cloud (normals, "color" in [0, 1], NaN points dropped and
// counted), bad files fail with a status and a message naming the file, outputs untouched,
// no exception crosses.
#include "particlemesh_pcl/particlemesh_pcl_c.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstddef>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "particlemesh_pcl/io.h"
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
  ASSERT_EQ(count, 1u);
  const char* name = nullptr;
  ASSERT_EQ(pm_cloud_get_attribute_name(c, 0, &name), PM_OK);
  EXPECT_STREQ(name, "color");
  const std::vector<float> colour = copy_attribute(c, "color", 3);
  ASSERT_EQ(ref.attributes.size(), 1u);
  EXPECT_EQ(colour, ref.attributes[0].values);
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
