// particlemesh_pcl/conversions.h: PCL clouds to particles (channels per point type, NaN
// points dropped with an index map back), meshes to pcl::Vertices / pcl::PolygonMesh and back.
#include "particlemesh_pcl/conversions.h"

#include <gtest/gtest.h>

#include <bit>
#include <cmath>
#include <cstring>
#include <limits>

#include <pcl/conversions.h>
#include <pcl/point_types.h>

#include "particlemesh/core/error.h"
#include "particlemesh/sample/shapes.h"
#include "support/test_support.h"

using namespace particlemesh;
using particlemesh_pcl::ConversionReport;

namespace {

const float kNaN = std::numeric_limits<float>::quiet_NaN();

const VertexAttribute* attribute(const PointCloud& c, const std::string& name) {
  for (const auto& a : c.attributes)
    if (a.name == name) return &a;
  return nullptr;
}

// An organized 4 x 3 cloud whose points (i, j) sit at (i, j, 0.1 i j); the points listed in
// `holes` have NaN coordinates, as a depth sensor writes where it saw nothing.
template <typename PointT>
pcl::PointCloud<PointT> organized(const std::vector<int>& holes) {
  pcl::PointCloud<PointT> c(4, 3);
  for (int j = 0; j < 3; ++j)
    for (int i = 0; i < 4; ++i) {
      PointT& p = c.at(i, j);
      p.x = float(i);
      p.y = float(j);
      p.z = 0.1f * float(i * j);
    }
  for (int h : holes) c[h].x = c[h].y = c[h].z = kNaN;
  return c;
}

}  // namespace

TEST(Conversions, PointXYZPositionsOnly) {
  pcl::PointCloud<pcl::PointXYZ> c;
  c.push_back({1, 2, 3});
  c.push_back({4, 5, 6});
  PointCloud p;
  pcl::Indices map;
  const ConversionReport r = particlemesh_pcl::toParticles(c, p, map);
  EXPECT_EQ(r.input_points, 2u);
  EXPECT_EQ(r.valid_points, 2u);
  EXPECT_EQ(r.invalid_points, 0u);
  EXPECT_FALSE(r.organized);
  EXPECT_FALSE(r.has_normals || r.has_color || r.has_intensity);
  ASSERT_EQ(p.positions.size(), 2u);
  EXPECT_EQ(p.positions[1], Vec3(4, 5, 6));
  EXPECT_TRUE(p.normals.empty());
  EXPECT_TRUE(p.attributes.empty());
  EXPECT_EQ(map, (pcl::Indices{0, 1}));
}

TEST(Conversions, NormalsColourAndIntensityBecomeChannels) {
  pcl::PointCloud<pcl::PointXYZRGBNormal> rgbn;
  pcl::PointXYZRGBNormal q;
  q.x = 1, q.y = 0, q.z = 0;
  q.normal_x = 0, q.normal_y = 0, q.normal_z = 1;
  q.r = 255, q.g = 0, q.b = 51;
  rgbn.push_back(q);
  PointCloud p;
  pcl::Indices map;
  ConversionReport r = particlemesh_pcl::toParticles(rgbn, p, map);
  EXPECT_TRUE(r.has_normals && r.has_color && !r.has_intensity);
  ASSERT_EQ(p.normals.size(), 1u);
  EXPECT_EQ(p.normals[0], Vec3(0, 0, 1));
  const VertexAttribute* col = attribute(p, particlemesh_pcl::kColorAttribute);
  ASSERT_NE(col, nullptr);
  EXPECT_EQ(col->components, 3);
  EXPECT_FLOAT_EQ(col->values[0], 1.f);
  EXPECT_FLOAT_EQ(col->values[1], 0.f);
  EXPECT_FLOAT_EQ(col->values[2], 0.2f);

  pcl::PointCloud<pcl::PointXYZI> xyzi;
  pcl::PointXYZI t;
  t.x = t.y = t.z = 0;
  t.intensity = 42.5f;
  xyzi.push_back(t);
  r = particlemesh_pcl::toParticles(xyzi, p, map);
  EXPECT_TRUE(r.has_intensity && !r.has_color && !r.has_normals);
  const VertexAttribute* in = attribute(p, particlemesh_pcl::kIntensityAttribute);
  ASSERT_NE(in, nullptr);
  EXPECT_EQ(in->values, std::vector<float>{42.5f});

  pcl::PointCloud<pcl::PointXYZRGB> xyzrgb;
  pcl::PointXYZRGB c;
  c.x = c.y = c.z = 0;
  c.r = 10, c.g = 20, c.b = 30;
  xyzrgb.push_back(c);
  r = particlemesh_pcl::toParticles(xyzrgb, p, map);
  EXPECT_TRUE(r.has_color && !r.has_normals);
  EXPECT_FLOAT_EQ(attribute(p, "color")->values[1], 20.f / 255.f);

  pcl::PointCloud<pcl::PointNormal> pn;
  pcl::PointNormal n;
  n.x = n.y = n.z = 0;
  n.normal_x = 1, n.normal_y = 0, n.normal_z = 0;
  pn.push_back(n);
  r = particlemesh_pcl::toParticles(pn, p, map);
  EXPECT_TRUE(r.has_normals && !r.has_color);
  EXPECT_EQ(p.normals[0], Vec3(1, 0, 0));
  validate_point_cloud(p);
}

TEST(Conversions, OrganizedCloudWithNaNsMapsBack) {
  //  j=2  8  9 10 11        x = NaN hole
  //  j=1  4  x  6  x
  //  j=0  x  1  2  3
  const std::vector<int> holes{0, 5, 7};
  const auto c = organized<pcl::PointXYZ>(holes);
  PointCloud p;
  pcl::Indices map;
  const ConversionReport r = particlemesh_pcl::toParticles(c, p, map);
  EXPECT_TRUE(r.organized);
  EXPECT_EQ(r.width, 4u);
  EXPECT_EQ(r.height, 3u);
  EXPECT_EQ(r.input_points, 12u);
  EXPECT_EQ(r.invalid_points, 3u);
  EXPECT_EQ(r.valid_points, 9u);
  EXPECT_EQ(map, (pcl::Indices{1, 2, 3, 4, 6, 8, 9, 10, 11}));
  for (size_t k = 0; k < map.size(); ++k) {
    const auto& q = c[map[k]];
    EXPECT_EQ(p.positions[k], Vec3(q.x, q.y, q.z)) << k;
  }
  validate_point_cloud(p);  // nothing non-finite got through

  // An Inf coordinate is invalid too; a subset by indices keeps the given order.
  auto d = organized<pcl::PointXYZ>({});
  d[6].z = std::numeric_limits<float>::infinity();
  const ConversionReport s = particlemesh_pcl::toParticles(d, pcl::Indices{11, 6, 2}, p, map);
  EXPECT_EQ(s.input_points, 3u);
  EXPECT_EQ(s.invalid_points, 1u);
  EXPECT_EQ(map, (pcl::Indices{11, 2}));
  EXPECT_EQ(p.positions[0], Vec3(3, 2, 0.1f * 6));

  EXPECT_THROW(particlemesh_pcl::toParticles(d, pcl::Indices{12}, p, map), particlemesh::Error);
  EXPECT_THROW(particlemesh_pcl::toParticles(d, pcl::Indices{-1}, p, map), particlemesh::Error);
}

TEST(Conversions, InvalidNormalsDropTheWholeChannel) {
  pcl::PointCloud<pcl::PointNormal> c;
  for (int i = 0; i < 4; ++i) {
    pcl::PointNormal n;
    n.x = float(i), n.y = 0, n.z = 0;
    n.normal_x = 0, n.normal_y = 0, n.normal_z = 1;
    c.push_back(n);
  }
  c[2].normal_x = kNaN;  // what PCL's normal estimation leaves where it had too few neighbours
  c[3].x = kNaN;         // an invalid point: dropped, its normal does not count
  PointCloud p;
  pcl::Indices map;
  const ConversionReport r = particlemesh_pcl::toParticles(c, p, map);
  EXPECT_EQ(r.valid_points, 3u);
  EXPECT_EQ(r.invalid_normals, 1u);
  EXPECT_FALSE(r.has_normals);
  EXPECT_TRUE(p.normals.empty());
  c[2].normal_x = 0;
  c[2].normal_z = 0;  // a zero normal is as useless as a NaN one
  EXPECT_EQ(particlemesh_pcl::toParticles(c, p, map).invalid_normals, 1u);
}

TEST(Conversions, BlobCloudAnyFieldTypes) {
  // x y z as float64, intensity as uint16, rgb as uint32 (the PCD "TYPE U" variant).
  pcl::PCLPointCloud2 b;
  auto field = [&](const char* name, uint32_t offset, uint8_t type) {
    pcl::PCLPointField f;
    f.name = name;
    f.offset = offset;
    f.datatype = type;
    f.count = 1;
    b.fields.push_back(f);
  };
  field("x", 0, pcl::PCLPointField::FLOAT64);
  field("y", 8, pcl::PCLPointField::FLOAT64);
  field("z", 16, pcl::PCLPointField::FLOAT64);
  field("rgb", 24, pcl::PCLPointField::UINT32);
  field("intensity", 28, pcl::PCLPointField::UINT16);
  b.point_step = 32;
  b.width = 3;
  b.height = 1;
  b.row_step = 96;
  b.data.assign(96, 0);
  for (int i = 0; i < 3; ++i) {
    const double xyz[3] = {0.5 + i, i == 1 ? std::nan("") : 2.0, -1.0};
    const uint32_t rgb = 0x00ff8000u + uint32_t(i);
    const uint16_t in = uint16_t(1000 + i);
    std::memcpy(&b.data[32 * i], xyz, 24);
    std::memcpy(&b.data[32 * i + 24], &rgb, 4);
    std::memcpy(&b.data[32 * i + 28], &in, 2);
  }
  PointCloud p;
  pcl::Indices map;
  const ConversionReport r = particlemesh_pcl::toParticles(b, p, map);
  EXPECT_EQ(r.invalid_points, 1u);
  EXPECT_EQ(map, (pcl::Indices{0, 2}));
  EXPECT_EQ(p.positions[1], Vec3(2.5, 2.0, -1.0));  // float64 kept exactly
  EXPECT_EQ(attribute(p, "intensity")->values, (std::vector<float>{1000, 1002}));
  const auto& col = attribute(p, "color")->values;
  EXPECT_FLOAT_EQ(col[0], 1.f);
  EXPECT_FLOAT_EQ(col[1], 128.f / 255.f);
  EXPECT_FLOAT_EQ(col[5], 2.f / 255.f);

  // Missing z, or data shorter than the layout says: FormatError, not a read past the end.
  pcl::PCLPointCloud2 noz = b;
  noz.fields.erase(noz.fields.begin() + 2);
  try {
    particlemesh_pcl::toParticles(noz, p, map);
    FAIL() << "no error";
  } catch (const particlemesh::Error& e) {
    EXPECT_EQ(e.status(), Status::FormatError);
    EXPECT_NE(std::string(e.what()).find("missing field 'z'"), std::string::npos) << e.what();
  }
  pcl::PCLPointCloud2 shortb = b;
  shortb.data.resize(80);
  EXPECT_THROW(particlemesh_pcl::toParticles(shortb, p, map), particlemesh::Error);
}

TEST(Conversions, PolygonsIndexTheOriginalCloud) {
  TriMesh m;
  m.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 1, 0}};
  m.triangles = {{0, 1, 2}, {1, 3, 2}};
  std::vector<pcl::Vertices> polys;
  particlemesh_pcl::toPolygons(m, {10, 11, 20, 21}, polys);
  ASSERT_EQ(polys.size(), 2u);
  EXPECT_EQ(polys[0].vertices, (pcl::Indices{10, 11, 20}));
  EXPECT_EQ(polys[1].vertices, (pcl::Indices{11, 21, 20}));
  particlemesh_pcl::toPolygons(m, {}, polys);
  EXPECT_EQ(polys[1].vertices, (pcl::Indices{1, 3, 2}));
  EXPECT_THROW(particlemesh_pcl::toPolygons(m, {1, 2}, polys), particlemesh::Error);
}

TEST(Conversions, PolygonMeshRoundTripKeepsEverything) {
  TriMesh m = icosphere_mesh(2);
  m.normals.clear();
  for (const Vec3& p : m.positions) m.normals.push_back(normalized(p));
  VertexAttribute col{"color", 3, {}};
  VertexAttribute in{"intensity", 1, {}};
  for (size_t i = 0; i < m.positions.size(); ++i) {
    col.values.insert(col.values.end(), {float(i % 256) / 255.f, 0.5f, 1.f});
    in.values.push_back(float(i));
  }
  m.attributes = {col, in};
  pcl::PolygonMesh pm;
  particlemesh_pcl::toPolygonMesh(m, pm);
  EXPECT_EQ(pm.cloud.width * pm.cloud.height, m.positions.size());
  EXPECT_EQ(pm.polygons.size(), m.triangles.size());
  std::vector<std::string> names;
  for (const auto& f : pm.cloud.fields) names.push_back(f.name);
  EXPECT_EQ(names, (std::vector<std::string>{"x", "y", "z", "normal_x", "normal_y", "normal_z", "rgb", "intensity"}));

  // PCL's own conversion reads the fields as a PointXYZRGBNormal does.
  pcl::PointCloud<pcl::PointXYZRGBNormal> typed;
  pcl::fromPCLPointCloud2(pm.cloud, typed);
  EXPECT_FLOAT_EQ(typed[5].x, float(m.positions[5].x));
  EXPECT_FLOAT_EQ(typed[5].normal_z, float(m.normals[5].z));
  EXPECT_EQ(typed[5].r, 5);
  EXPECT_EQ(typed[5].g, 128);
  EXPECT_EQ(typed[5].b, 255);

  TriMesh back;
  particlemesh_pcl::fromPolygonMesh(pm, back);
  EXPECT_EQ(back.triangles, m.triangles);
  ASSERT_EQ(back.positions.size(), m.positions.size());
  ASSERT_EQ(back.normals.size(), m.normals.size());
  for (size_t i = 0; i < m.positions.size(); ++i) {
    EXPECT_LT(distance(back.positions[i], m.positions[i]), 1e-6);
    EXPECT_LT(distance(back.normals[i], m.normals[i]), 1e-6);
  }
  ASSERT_EQ(back.attributes.size(), 2u);
  EXPECT_NEAR(back.attributes[0].values[3 * 7], 7.f / 255.f, 1e-6);
  EXPECT_EQ(back.attributes[1].values, in.values);

  // A PolygonMesh whose cloud holds other fields (PCL's curvature; a vector stored as name_0,
  // name_1, name_2, as particlemesh's PLY writer names it): each an attribute of its name, the
  // vector one attribute again.
  pcl::PCLPointCloud2& c = pm.cloud;
  const auto base = c.point_step;
  for (const char* name : {"curvature", "velocity_0", "velocity_1", "velocity_2"}) {
    pcl::PCLPointField f;
    f.name = name;
    f.offset = c.point_step;
    f.datatype = pcl::PCLPointField::FLOAT32;
    f.count = 1;
    c.fields.push_back(f);
    c.point_step += 4;
  }
  std::vector<std::uint8_t> data(size_t(c.point_step) * c.width);
  for (size_t i = 0; i < c.width; ++i) {
    std::memcpy(data.data() + i * c.point_step, c.data.data() + i * base, base);
    const float extra[4] = {0.25f, float(i), -float(i), 2.0f};
    std::memcpy(data.data() + i * c.point_step + base, extra, sizeof extra);
  }
  c.data = std::move(data);
  c.row_step = c.point_step * c.width;
  particlemesh_pcl::fromPolygonMesh(pm, back);
  ASSERT_EQ(back.attributes.size(), 4u);
  EXPECT_EQ(back.attributes[2].name, "curvature");
  EXPECT_EQ(back.attributes[2].values[3], 0.25f);
  EXPECT_EQ(back.attributes[3].name, "velocity");
  EXPECT_EQ(back.attributes[3].components, 3);
  EXPECT_EQ(back.attributes[3].values[3 * 9], 9.f);
  EXPECT_EQ(back.attributes[3].values[3 * 9 + 1], -9.f);
  EXPECT_EQ(back.attributes[3].values[3 * 9 + 2], 2.f);

  // Quads are fanned; an index outside the cloud is a FormatError.
  pcl::PolygonMesh quad;
  particlemesh_pcl::toPolygonMesh(m, quad);
  quad.polygons.assign(1, pcl::Vertices());
  quad.polygons[0].vertices = {0, 1, 2, 3};
  particlemesh_pcl::fromPolygonMesh(quad, back);
  EXPECT_EQ(back.triangles, (std::vector<Triangle>{{0, 1, 2}, {0, 2, 3}}));
  quad.polygons[0].vertices = {0, 1, 100000};
  EXPECT_THROW(particlemesh_pcl::fromPolygonMesh(quad, back), particlemesh::Error);
}
