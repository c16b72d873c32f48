// The C ABI's read-back of a cloud's attributes: query then copy, statuses and
// messages for misuse with outputs untouched, and what pm_cloud_read puts there: a PLY
// file's vertex colours as "color" (3 floats in [0, 1]).
#include "particlemesh/particlemesh.h"

#include <gtest/gtest.h>

#include <cstdint>
#include <cstring>
#include <fstream>
#include <string>
#include <vector>

#include "support/test_support.h"

namespace {

std::string last() { return pm_last_error_message(); }

pm_cloud* three_points() {
  const double p[] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
  pm_cloud* c = nullptr;
  EXPECT_EQ(pm_cloud_create(p, nullptr, 3, &c), PM_OK) << last();
  return c;
}

std::vector<std::string> names(const pm_cloud* c) {
  size_t n = 99;
  EXPECT_EQ(pm_cloud_get_attribute_count(c, &n), PM_OK) << last();
  std::vector<std::string> out;
  for (size_t i = 0; i < n; ++i) {
    const char* name = nullptr;
    EXPECT_EQ(pm_cloud_get_attribute_name(c, i, &name), PM_OK) << last();
    out.emplace_back(name);
  }
  return out;
}

std::vector<float> attribute(const pm_cloud* c, const char* name, int32_t expect_components) {
  int32_t comps = 0;
  EXPECT_EQ(pm_cloud_get_attribute_components(c, name, &comps), PM_OK) << last();
  EXPECT_EQ(comps, expect_components);
  size_t n = 0;
  EXPECT_EQ(pm_cloud_get_count(c, &n), PM_OK);
  std::vector<float> v(n * size_t(comps), -7.0f);
  EXPECT_EQ(pm_cloud_copy_attribute(c, name, v.data(), n), PM_OK) << last();
  return v;
}

}  // namespace

TEST(CapiCloudAttributes, WhatWasSetReadsBackInOrder) {
  pm_cloud* c = three_points();
  EXPECT_TRUE(names(c).empty());
  const float radius[] = {0.5f, 0.25f, 0.125f};
  const float velocity[] = {1, 2, 3, 4, 5, 6, 7, 8, 9};
  ASSERT_EQ(pm_cloud_set_attribute(c, "radius", 1, radius, 3), PM_OK) << last();
  ASSERT_EQ(pm_cloud_set_attribute(c, "velocity", 3, velocity, 3), PM_OK) << last();
  EXPECT_EQ(names(c), (std::vector<std::string>{"radius", "velocity"}));
  EXPECT_EQ(attribute(c, "radius", 1), std::vector<float>(radius, radius + 3));
  EXPECT_EQ(attribute(c, "velocity", 3), std::vector<float>(velocity, velocity + 9));
  // Replacing keeps one attribute of that name, with the new components.
  const float two[] = {1, 1, 2, 2, 3, 3};
  ASSERT_EQ(pm_cloud_set_attribute(c, "radius", 2, two, 3), PM_OK) << last();
  EXPECT_EQ(names(c), (std::vector<std::string>{"radius", "velocity"}));
  EXPECT_EQ(attribute(c, "radius", 2), std::vector<float>(two, two + 6));
  pm_cloud_destroy(c);
}

TEST(CapiCloudAttributes, MisuseNamesTheProblemAndLeavesOutputsUntouched) {
  pm_cloud* c = three_points();
  const float radius[] = {0.5f, 0.25f, 0.125f};
  ASSERT_EQ(pm_cloud_set_attribute(c, "radius", 1, radius, 3), PM_OK);

  size_t count = 42;
  EXPECT_EQ(pm_cloud_get_attribute_count(nullptr, &count), PM_STATUS_INVALID_ARGUMENT);
  EXPECT_NE(last().find("cloud is NULL"), std::string::npos) << last();
  EXPECT_EQ(count, 42u);
  EXPECT_EQ(pm_cloud_get_attribute_count(c, nullptr), PM_STATUS_INVALID_ARGUMENT);

  const char* name = "untouched";
  EXPECT_EQ(pm_cloud_get_attribute_name(c, 1, &name), PM_STATUS_INVALID_ARGUMENT);
  EXPECT_NE(last().find("index 1 is out of range: the cloud has 1 attributes"), std::string::npos) << last();
  EXPECT_STREQ(name, "untouched");

  int32_t comps = -1;
  EXPECT_EQ(pm_cloud_get_attribute_components(c, "colour", &comps), PM_STATUS_INVALID_ARGUMENT);
  EXPECT_NE(last().find("the cloud has no attribute 'colour'"), std::string::npos) << last();
  EXPECT_EQ(comps, -1);
  EXPECT_EQ(pm_cloud_get_attribute_components(c, nullptr, &comps), PM_STATUS_INVALID_ARGUMENT);
  EXPECT_NE(last().find("name is NULL"), std::string::npos) << last();

  std::vector<float> out(3, -7.0f);
  EXPECT_EQ(pm_cloud_copy_attribute(c, "radius", out.data(), 2), PM_STATUS_INVALID_ARGUMENT);
  EXPECT_NE(last().find("capacity_points 2 is less than the 3 points"), std::string::npos) << last();
  EXPECT_EQ(out, std::vector<float>(3, -7.0f));
  EXPECT_EQ(pm_cloud_copy_attribute(c, "radius", nullptr, 3), PM_STATUS_INVALID_ARGUMENT);
  EXPECT_EQ(pm_cloud_copy_attribute(c, "nope", out.data(), 3), PM_STATUS_INVALID_ARGUMENT);
  EXPECT_EQ(out, std::vector<float>(3, -7.0f));
  // A successful call clears the message.
  EXPECT_EQ(pm_cloud_get_attribute_count(c, &count), PM_OK);
  EXPECT_EQ(count, 1u);
  EXPECT_STREQ(pm_last_error_message(), "");
  pm_cloud_destroy(c);
}

namespace {

// A PLY with vertex positions, normals and colours of the given property type.
std::string write_coloured_ply(const std::string& name, bool binary, const char* colour_type) {
  const auto dir = particlemesh::test::scratch_dir("ply");
  const std::string path = (dir / name).string();
  std::ofstream f(path, std::ios::binary);
  const bool as_float = std::strcmp(colour_type, "float") == 0;
  f << "ply\nformat " << (binary ? "binary_little_endian" : "ascii") << " 1.0\nelement vertex 3\n"
    << "property float x\nproperty float y\nproperty float z\n"
    << "property float nx\nproperty float ny\nproperty float nz\n"
    << "property " << colour_type << " red\nproperty " << colour_type << " green\nproperty " << colour_type
    << " blue\nend_header\n";
  const unsigned char rgb[3][3] = {{255, 0, 0}, {0, 128, 0}, {10, 20, 250}};
  for (int v = 0; v < 3; ++v) {
    const float xyz[6] = {float(v), float(v * v), 0.5f, 0, 0, 1};
    if (binary) {
      f.write(reinterpret_cast<const char*>(xyz), sizeof xyz);
      for (int k = 0; k < 3; ++k) {
        if (as_float) {
          const float x = rgb[v][k] / 255.0f;
          f.write(reinterpret_cast<const char*>(&x), sizeof x);
        } else {
          f.put(char(rgb[v][k]));
        }
      }
    } else {
      for (float x : xyz) f << x << ' ';
      for (int k = 0; k < 3; ++k) {
        if (as_float) f << rgb[v][k] / 255.0f << ' ';
        else f << int(rgb[v][k]) << ' ';
      }
      f << '\n';
    }
  }
  return path;
}

}  // namespace

TEST(CapiCloudAttributes, PlyVertexColoursBecomeTheColorAttribute) {
  const float expect[] = {1, 0, 0, 0, 128 / 255.f, 0, 10 / 255.f, 20 / 255.f, 250 / 255.f};
  struct Case { const char* name; bool binary; const char* type; float tolerance; };
  for (const Case& k : {Case{"ascii_uchar.ply", false, "uchar", 1e-6f}, Case{"binary_uchar.ply", true, "uchar", 1e-6f},
                        Case{"binary_float.ply", true, "float", 1.0f / 255}}) {
    SCOPED_TRACE(k.name);
    const std::string path = write_coloured_ply(k.name, k.binary, k.type);
    pm_cloud* c = nullptr;
    ASSERT_EQ(pm_cloud_read(path.c_str(), &c), PM_OK) << last();
    size_t n = 0;
    ASSERT_EQ(pm_cloud_get_count(c, &n), PM_OK);
    EXPECT_EQ(n, 3u);
    int32_t has_normals = 0;
    EXPECT_EQ(pm_cloud_has_normals(c, &has_normals), PM_OK);
    EXPECT_EQ(has_normals, 1);
    EXPECT_EQ(names(c), std::vector<std::string>{"color"});
    const std::vector<float> got = attribute(c, "color", 3);
    for (size_t i = 0; i < 9; ++i) EXPECT_NEAR(got[i], expect[i], k.tolerance) << i;
    std::vector<float> p(9);
    ASSERT_EQ(pm_cloud_copy_positions_f32(c, p.data(), 3), PM_OK);
    EXPECT_EQ(p, (std::vector<float>{0, 0, 0.5f, 1, 1, 0.5f, 2, 4, 0.5f}));
    pm_cloud_destroy(c);
  }
}

TEST(CapiCloudAttributes, PlyWithoutColoursHasNoAttribute) {
  PM_REQUIRE_DATA(path, "points/spot_poisson.ply");
  pm_cloud* c = nullptr;
  ASSERT_EQ(pm_cloud_read(path.c_str(), &c), PM_OK) << last();
  EXPECT_TRUE(names(c).empty());
  pm_cloud_destroy(c);
}

// What the file holds per particle but no channel carries is named, line by line; a cloud not
// read from a file (or whose file was read whole) names nothing.
TEST(CapiCloudAttributes, WhatAFileHoldsButIsNotReadIsNamed) {
  const std::string path = (particlemesh::test::scratch_dir("capi_not_read") / "lists.ply").string();
  std::ofstream(path) << "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
                         "property float z\nproperty list uchar int ids\nproperty float mass\nend_header\n"
                         "0 0 0 1 7 1\n1 0 0 0 2\n0 1 0 2 8 9 3\n";
  pm_cloud* c = nullptr;
  ASSERT_EQ(pm_cloud_read(path.c_str(), &c), PM_OK) << last();
  EXPECT_EQ(names(c), std::vector<std::string>{"mass"});
  size_t n = 99;
  ASSERT_EQ(pm_cloud_get_not_read_count(c, &n), PM_OK) << last();
  ASSERT_EQ(n, 1u);
  const char* text = nullptr;
  ASSERT_EQ(pm_cloud_get_not_read(c, 0, &text), PM_OK) << last();
  EXPECT_STREQ(text, "vertex list property 'ids' (lists)");
  const char* untouched = "x";
  const char* out = untouched;
  EXPECT_EQ(pm_cloud_get_not_read(c, 1, &out), PM_STATUS_INVALID_ARGUMENT);
  EXPECT_NE(last().find("index 1 is out of range"), std::string::npos) << last();
  EXPECT_EQ(out, untouched);
  EXPECT_EQ(pm_cloud_get_not_read(c, 0, nullptr), PM_STATUS_INVALID_ARGUMENT);
  EXPECT_EQ(pm_cloud_get_not_read_count(nullptr, &n), PM_STATUS_INVALID_ARGUMENT);
  EXPECT_EQ(pm_cloud_get_not_read_count(c, nullptr), PM_STATUS_INVALID_ARGUMENT);
  pm_cloud_destroy(c);
  pm_cloud* made = three_points();
  ASSERT_EQ(pm_cloud_get_not_read_count(made, &n), PM_OK);
  EXPECT_EQ(n, 0u);
  pm_cloud_destroy(made);
}
