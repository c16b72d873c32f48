// particlemesh_pcl/io.h: every shared .pcd loads with the counts DATA.md states, bad files
// fail with a message naming the file and the problem, PLY meshes load back in PCL.
#include "particlemesh_pcl/io.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <iterator>

#include <pcl/io/pcd_io.h>
#include <pcl/io/ply_io.h>
#include <pcl/point_types.h>

#include "particlemesh/core/error.h"
#include "particlemesh/io/mesh_io.h"
#include "particlemesh/sample/shapes.h"
#include "particlemesh/surface/triangulate.h"
#include "support/test_support.h"

using namespace particlemesh;
namespace fs = std::filesystem;

namespace {

std::string slurp(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string((std::istreambuf_iterator<char>(in)), {});
}

void write_bytes(const fs::path& p, const std::string& s) {
  std::ofstream out(p, std::ios::binary);
  out << s;
}

// The FormatError/IoError message of loading `path`, "" if it loaded.
std::string load_error(const fs::path& path, Status expected = Status::FormatError) {
  try {
    particlemesh_pcl::loadParticles(path.string());
  } catch (const particlemesh::Error& e) {
    EXPECT_EQ(e.status(), expected) << e.what();
    const std::string msg = e.what();
    EXPECT_EQ(msg.rfind(path.string(), 0), 0u) << "message must start with the file: " << msg;
    EXPECT_EQ(msg.find('\n'), std::string::npos) << "one line: " << msg;
    return msg;
  }
  return "";
}

bool has(const std::string& s, const std::string& needle) { return s.find(needle) != std::string::npos; }

}  // namespace

// DATA.md: point counts, NaN counts, normals of every shared PCD file.
TEST(PcdIO, EverySharedPcdLoadsWithTheDocumentedCounts) {
  PM_REQUIRE_DATA(bun0, "pcd/bun0.pcd");
  struct Expect {
    const char* file;
    size_t points, nan;
    uint32_t width, height;
    bool normals, color;
    const char* encoding;
  };
  const Expect expected[] = {
      {"pcd/bunny.pcd", 397, 0, 397, 1, false, false, "ascii"},
      {"pcd/bun0.pcd", 397, 0, 397, 1, true, false, "ascii"},
      {"pcd/milk.pcd", 13704, 0, 13704, 1, false, false, "binary_compressed"},
      {"pcd/milk_binary.pcd", 13704, 0, 13704, 1, false, false, "binary"},
      {"pcd/kinect_frame_20121214T142255.814212.pcd", 307200, 35625, 640, 480, false, true, "binary_compressed"},
      {"pcd/kinect_frame_20121214T142255.814212_binary.pcd", 307200, 35625, 640, 480, false, true, "binary"},
      {"pcd/colored_cloud.pcd", 1000, 0, 1, 1000, true, true, "binary"},
  };
  size_t files = 0;
  for (const Expect& e : expected) {
    const std::string path = test::shared_data(e.file);
    ASSERT_FALSE(path.empty()) << e.file;
    SCOPED_TRACE(e.file);
    particlemesh_pcl::LoadReport r;
    pcl::Indices map;
    const PointCloud c = particlemesh_pcl::loadParticles(path, &r, &map);
    EXPECT_EQ(r.format, "pcd");
    EXPECT_EQ(r.encoding, e.encoding);
    EXPECT_EQ(r.conversion.input_points, e.points);
    EXPECT_EQ(r.conversion.invalid_points, e.nan);
    EXPECT_EQ(r.conversion.valid_points, e.points - e.nan);
    EXPECT_EQ(c.size(), e.points - e.nan);
    EXPECT_EQ(map.size(), c.size());
    EXPECT_EQ(r.conversion.width, e.width);
    EXPECT_EQ(r.conversion.height, e.height);
    EXPECT_EQ(r.conversion.organized, e.height > 1);
    EXPECT_EQ(c.has_normals(), e.normals);
    EXPECT_EQ(r.conversion.has_color, e.color);
    if (e.normals) {
      for (const Vec3& n : c.normals) ASSERT_NEAR(norm(n), 1.0, 1e-3);  // unit normals in the file
    }
    validate_point_cloud(c);
    ++files;
  }
  // Every .pcd in the folder is one of the above.
  size_t on_disk = 0;
  for (const auto& entry : fs::directory_iterator(fs::path(bun0).parent_path()))
    on_disk += entry.path().extension() == ".pcd";
  EXPECT_EQ(on_disk, files);
}

TEST(PcdIO, EncodingsOfTheSameCloudReadTheSame) {
  PM_REQUIRE_DATA(milk, "pcd/milk.pcd");
  PM_REQUIRE_DATA(milk_bin, "pcd/milk_binary.pcd");
  PM_REQUIRE_DATA(kin, "pcd/kinect_frame_20121214T142255.814212.pcd");
  PM_REQUIRE_DATA(kin_bin, "pcd/kinect_frame_20121214T142255.814212_binary.pcd");
  EXPECT_EQ(particlemesh_pcl::loadParticles(milk).positions, particlemesh_pcl::loadParticles(milk_bin).positions);
  pcl::Indices m1, m2;
  const PointCloud a = particlemesh_pcl::loadParticles(kin, nullptr, &m1);
  const PointCloud b = particlemesh_pcl::loadParticles(kin_bin, nullptr, &m2);
  EXPECT_EQ(a.positions, b.positions);
  EXPECT_EQ(a.attributes[0].values, b.attributes[0].values);
  EXPECT_EQ(m1, m2);
  // The map points at the file's valid points: the organized frame read by PCL directly.
  pcl::PointCloud<pcl::PointXYZRGBA> frame;
  ASSERT_EQ(pcl::io::loadPCDFile(kin, frame), 0);
  EXPECT_EQ(frame.width, 640u);
  for (size_t k = 0; k < m1.size(); k += 997) {
    const auto& p = frame[m1[k]];
    EXPECT_EQ(a.positions[k], Vec3(p.x, p.y, p.z));
  }
  size_t nan = 0;
  for (const auto& p : frame) nan += !std::isfinite(p.x);
  EXPECT_EQ(nan, 35625u);
  // The sensor pose is read (the frame's VIEWPOINT is 0 0 0 0 1 0 0).
  const particlemesh_pcl::PCDFile f = particlemesh_pcl::loadPCDFile(kin);
  EXPECT_EQ(f.header.viewpoint[4], 1.f);
  EXPECT_EQ(f.origin[0], 0.f);
  EXPECT_EQ(f.header.fields, (std::vector<std::string>{"x", "y", "z", "rgba"}));
}

TEST(PcdIO, MalformedFilesNameTheFileAndTheProblem) {
  PM_REQUIRE_DATA(bunny, "pcd/bunny.pcd");
  PM_REQUIRE_DATA(milk, "pcd/milk.pcd");
  PM_REQUIRE_DATA(milk_bin, "pcd/milk_binary.pcd");
  const auto dir = test::scratch_dir("bad");
  const std::string ascii = slurp(bunny), compressed = slurp(milk), binary = slurp(milk_bin);
  auto replaced = [](std::string s, const std::string& from, const std::string& to) {
    const size_t at = s.find(from);
    EXPECT_NE(at, std::string::npos) << from;
    return s.replace(at, from.size(), to);
  };

  // Truncated: data cut short in each encoding, and a header cut before DATA.
  write_bytes(dir / "cut_binary.pcd", binary.substr(0, 5000));
  EXPECT_TRUE(has(load_error(dir / "cut_binary.pcd"), "truncated data: 4"));
  write_bytes(dir / "cut_compressed.pcd", compressed.substr(0, 3000));
  EXPECT_TRUE(has(load_error(dir / "cut_compressed.pcd"), "truncated data: compressed block"));
  write_bytes(dir / "cut_ascii.pcd", ascii.substr(0, ascii.size() / 3));
  const std::string cut_ascii = load_error(dir / "cut_ascii.pcd");
  EXPECT_TRUE(has(cut_ascii, "truncated data:") && has(cut_ascii, "POINTS says 397")) << cut_ascii;
  write_bytes(dir / "cut_header.pcd", ascii.substr(0, ascii.find("POINTS")));
  EXPECT_TRUE(has(load_error(dir / "cut_header.pcd"), "truncated header: no DATA line"));

  // Wrong header: not a PCD file at all, an empty file (both crash PCL 1.13's own reader),
  // an unknown DATA encoding, a bad TYPE.
  write_bytes(dir / "garbage.pcd", "hello world\n");
  EXPECT_TRUE(has(load_error(dir / "garbage.pcd"), "not a PCD file: header line 1 starts with 'hello'"));
  write_bytes(dir / "empty.pcd", "");
  EXPECT_TRUE(has(load_error(dir / "empty.pcd"), "empty file"));
  write_bytes(dir / "ply.pcd", "ply\nformat binary_little_endian 1.0\nelement vertex 3\nend_header\n\x01\x02");
  EXPECT_TRUE(has(load_error(dir / "ply.pcd"), "not a PCD file"));
  write_bytes(dir / "data.pcd", replaced(ascii, "DATA ascii", "DATA zipped"));
  EXPECT_TRUE(has(load_error(dir / "data.pcd"), "DATA 'zipped'"));
  write_bytes(dir / "type.pcd", replaced(ascii, "TYPE F F F", "TYPE F X F"));
  EXPECT_TRUE(has(load_error(dir / "type.pcd"), "type 'X'"));

  // Missing fields.
  write_bytes(dir / "fields.pcd", replaced(ascii, "FIELDS x y z", "FIELDS a b c"));
  EXPECT_TRUE(has(load_error(dir / "fields.pcd"), "missing field 'x' (FIELDS: a b c)"));
  write_bytes(dir / "noz.pcd", replaced(replaced(replaced(replaced(ascii, "FIELDS x y z", "FIELDS x y"), "SIZE 4 4 4", "SIZE 4 4"),
                                                 "TYPE F F F", "TYPE F F"), "COUNT 1 1 1", "COUNT 1 1"));
  EXPECT_TRUE(has(load_error(dir / "noz.pcd"), "missing field 'z'"));

  // Count mismatches: POINTS vs WIDTH x HEIGHT, SIZE entries vs FIELDS, values per line,
  // the compressed block's size vs POINTS.
  write_bytes(dir / "points.pcd", replaced(ascii, "POINTS 397", "POINTS 500"));
  EXPECT_TRUE(has(load_error(dir / "points.pcd"), "count mismatch: WIDTH 397 x HEIGHT 1 = 397 points, but POINTS says 500"));
  write_bytes(dir / "size.pcd", replaced(ascii, "SIZE 4 4 4", "SIZE 4 4"));
  EXPECT_TRUE(has(load_error(dir / "size.pcd"), "header count mismatch: SIZE has 2 entries, FIELDS has 3"));
  std::string short_line = ascii;
  const size_t first = short_line.find("DATA ascii\n") + 11;
  short_line.erase(short_line.rfind(' ', short_line.find('\n', first)), short_line.find('\n', first) - short_line.rfind(' ', short_line.find('\n', first)));
  write_bytes(dir / "values.pcd", short_line);
  EXPECT_TRUE(has(load_error(dir / "values.pcd"), "line 11 has 2 values, FIELDS/COUNT need 3"));
  write_bytes(dir / "unpack.pcd", replaced(replaced(compressed, "POINTS 13704", "POINTS 13700"), "WIDTH 13704", "WIDTH 13700"));
  EXPECT_TRUE(has(load_error(dir / "unpack.pcd"), "count mismatch: compressed block unpacks to 164448 bytes"));
  write_bytes(dir / "word.pcd", replaced(ascii, "\n0.", "\nzero "));
  EXPECT_TRUE(has(load_error(dir / "word.pcd"), "is not a number"));

  // A file that is not there, and a PCD whose every point is NaN.
  EXPECT_TRUE(has(load_error(dir / "missing.pcd", Status::IoError), "no such file"));
  write_bytes(dir / "allnan.pcd", "VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH 2\nHEIGHT 1\n"
                                  "POINTS 2\nDATA ascii\nnan nan nan\nnan 0 0\n");
  EXPECT_TRUE(has(load_error(dir / "allnan.pcd", Status::InvalidInput), "no valid point"));

  // The originals load, so each failure above is the edit's doing.
  for (const auto& good : {bunny, milk, milk_bin}) EXPECT_NO_THROW(particlemesh_pcl::loadParticles(good));
}

// PDAL names the coordinates X Y Z and the intensity Intensity: read as x y z and intensity,
// in every encoding; a file with both keeps the lower-case ones.
TEST(PcdIO, UpperCaseCoordinatesAsPdalWritesThem) {
  const auto dir = test::scratch_dir("upper");
  const std::string head = "VERSION 0.7\nFIELDS X Y Z Intensity\nSIZE 8 8 8 4\nTYPE F F F F\nCOUNT 1 1 1 1\n"
                           "WIDTH 3\nHEIGHT 1\nPOINTS 3\n";
  write_bytes(dir / "ascii.pcd", head + "DATA ascii\n1 2 3 10\n4 5 6 20\n7 8 9.5 30\n");
  const double xyz[3][3] = {{1, 2, 3}, {4, 5, 6}, {7, 8, 9.5}};
  const float intensity[3] = {10, 20, 30};
  std::string body;
  for (int i = 0; i < 3; ++i) {
    body.append(reinterpret_cast<const char*>(xyz[i]), sizeof xyz[i]);
    body.append(reinterpret_cast<const char*>(&intensity[i]), sizeof intensity[i]);
  }
  write_bytes(dir / "binary.pcd", head + "DATA binary\n" + body);
  for (const char* name : {"ascii.pcd", "binary.pcd"}) {
    const PointCloud c = particlemesh_pcl::loadParticles((dir / name).string());
    ASSERT_EQ(c.size(), 3u) << name;
    EXPECT_EQ(c.positions[2], (Vec3{7, 8, 9.5})) << name;
    ASSERT_EQ(c.attributes.size(), 1u) << name;
    EXPECT_EQ(c.attributes[0].name, "intensity") << name;
    EXPECT_EQ(c.attributes[0].values[1], 20.0f) << name;
  }
  write_bytes(dir / "both.pcd", "VERSION 0.7\nFIELDS x y z X\nSIZE 4 4 4 4\nTYPE F F F F\nCOUNT 1 1 1 1\n"
                                "WIDTH 1\nHEIGHT 1\nPOINTS 1\nDATA ascii\n1 2 3 9\n");
  const PointCloud both = particlemesh_pcl::loadParticles((dir / "both.pcd").string());
  EXPECT_EQ(both.positions[0], (Vec3{1, 2, 3}));
}

// A segmentation's label, a descriptor of several values, PCL's curvature: every field that is
// not a coordinate, normal, colour or intensity is a channel of its name (as a PLY file's other
// vertex properties are), in the file's order, in ascii and binary alike; "_" (PCL's padding)
// is none.
TEST(PcdIO, EveryOtherFieldIsAChannelOfItsName) {
  const auto dir = test::scratch_dir("fields");
  const std::string head = "VERSION 0.7\nFIELDS x y z label _ desc curvature\nSIZE 4 4 4 4 1 2 8\nTYPE F F F U U I F\n"
                           "COUNT 1 1 1 1 4 3 1\nWIDTH 2\nHEIGHT 1\nPOINTS 2\n";
  write_bytes(dir / "ascii.pcd", head + "DATA ascii\n0 0 0 7 0 0 0 0 -1 2 3 0.25\n1 0 0 9 0 0 0 0 4 5 -6 0.5\n");
  std::string body;
  auto put = [&body](const auto& v) { body.append(reinterpret_cast<const char*>(&v), sizeof v); };
  for (int i = 0; i < 2; ++i) {
    put(float(i)), put(0.0f), put(0.0f), put(uint32_t(i ? 9 : 7));
    body.append(4, '\0');
    const int16_t d[2][3] = {{-1, 2, 3}, {4, 5, -6}};
    for (int16_t v : d[i]) put(v);
    put(i ? 0.5 : 0.25);
  }
  write_bytes(dir / "binary.pcd", head + "DATA binary\n" + body);
  for (const char* name : {"ascii.pcd", "binary.pcd"}) {
    SCOPED_TRACE(name);
    const PointCloud c = particlemesh_pcl::loadParticles((dir / name).string());
    ASSERT_EQ(c.size(), 2u);
    EXPECT_EQ(c.positions[1], (Vec3{1, 0, 0}));
    ASSERT_EQ(c.attributes.size(), 3u);
    EXPECT_EQ(c.attributes[0].name, "label");
    EXPECT_EQ(c.attributes[0].values, (std::vector<float>{7, 9}));
    EXPECT_EQ(c.attributes[1].name, "desc");
    EXPECT_EQ(c.attributes[1].components, 3);
    EXPECT_EQ(c.attributes[1].values, (std::vector<float>{-1, 2, 3, 4, 5, -6}));
    EXPECT_EQ(c.attributes[2].name, "curvature");
    EXPECT_EQ(c.attributes[2].values, (std::vector<float>{0.25f, 0.5f}));
    validate_point_cloud(c);
  }
}

TEST(PcdIO, OtherFormatsGoThroughTheCoreReader) {
  const auto dir = test::scratch_dir("xyz");
  write_point_cloud(fibonacci_sphere(100), (dir / "s.xyz").string());
  particlemesh_pcl::LoadReport r;
  const PointCloud c = particlemesh_pcl::loadParticles((dir / "s.xyz").string(), &r);
  EXPECT_EQ(c.size(), 100u);
  EXPECT_EQ(r.format, "xyz");
  EXPECT_EQ(r.conversion.valid_points, 100u);
}

// Our own binary PLY (OpenMesh's writer) loads with pcl::io::loadPLYFile into a
// pcl::PolygonMesh with the same triangles, and savePLYFile's output does too.
TEST(PlyIO, MeshesLoadInPclWithTheSameTriangles) {
  const auto dir = test::scratch_dir("ply");
  const TriangulateResult r = triangulate_raw(fibonacci_sphere(2000));
  ASSERT_GT(r.mesh.triangles.size(), 3000u);
  write_mesh(r.mesh, (dir / "ours.ply").string());
  pcl::PolygonMesh loaded;
  ASSERT_GE(pcl::io::loadPLYFile((dir / "ours.ply").string(), loaded), 0);
  TriMesh back;
  particlemesh_pcl::fromPolygonMesh(loaded, back);
  EXPECT_EQ(back.triangles, r.mesh.triangles);
  ASSERT_EQ(back.positions.size(), r.mesh.positions.size());
  for (size_t i = 0; i < back.positions.size(); ++i) ASSERT_LT(distance(back.positions[i], r.mesh.positions[i]), 1e-6);

  pcl::PolygonMesh pm;
  particlemesh_pcl::toPolygonMesh(r.mesh, pm);
  particlemesh_pcl::savePLYFile((dir / "pcl.ply").string(), pm);
  pcl::PolygonMesh again;
  ASSERT_GE(pcl::io::loadPLYFile((dir / "pcl.ply").string(), again), 0);
  particlemesh_pcl::fromPolygonMesh(again, back);
  EXPECT_EQ(back.triangles, r.mesh.triangles);
  // ... and the core reader reads PCL's file as well.
  EXPECT_EQ(read_mesh((dir / "pcl.ply").string()).triangles, r.mesh.triangles);
  // Only the two files: no temporary left behind; a failed write leaves nothing.
  EXPECT_EQ(std::distance(fs::directory_iterator(dir), fs::directory_iterator()), 2);
  EXPECT_THROW(particlemesh_pcl::savePLYFile((dir / "no" / "m.ply").string(), pm), particlemesh::Error);
  EXPECT_EQ(std::distance(fs::directory_iterator(dir), fs::directory_iterator()), 2);
}

// A pcl::PointCloud<pcl::PointNormal> saved by PCL's own PLY writer (ASCII and binary: nx ny nz,
// the curvature, and a "camera" element after the vertices) reads with its normals and its
// curvature as a channel.
TEST(PlyIO, PclPointNormalFilesReadWithTheirNormals) {
  const auto dir = test::scratch_dir("pcl_point_normal_ply");
  const PointCloud s = fibonacci_sphere(200);
  pcl::PointCloud<pcl::PointNormal> cloud;
  for (size_t i = 0; i < s.size(); ++i) {
    pcl::PointNormal p;
    p.x = float(s.positions[i].x), p.y = float(s.positions[i].y), p.z = float(s.positions[i].z);
    p.normal_x = p.x, p.normal_y = p.y, p.normal_z = p.z;
    p.curvature = 0.5f;
    cloud.push_back(p);
  }
  for (const bool binary : {false, true}) {
    SCOPED_TRACE(binary ? "binary" : "ascii");
    const std::string path = (dir / (binary ? "b.ply" : "a.ply")).string();
    ASSERT_EQ(pcl::io::savePLYFile(path, cloud, binary), 0);
    const PointCloud back = read_point_cloud(path);
    ASSERT_EQ(back.size(), s.size());
    ASSERT_EQ(back.normals.size(), s.size());
    for (size_t i = 0; i < s.size(); ++i) {
      ASSERT_LT(distance(back.positions[i], s.positions[i]), 1e-6);
      ASSERT_LT(distance(back.normals[i], s.positions[i]), 1e-6);
    }
    ASSERT_EQ(back.attributes.size(), 1u);
    EXPECT_EQ(back.attributes[0].name, "curvature");
    EXPECT_EQ(back.attributes[0].values[0], 0.5f);
  }
}
