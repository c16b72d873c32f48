#include "particlemesh/io/mesh_io.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cfloat>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <random>

#include "particlemesh/core/error.h"
#include "particlemesh/io/atomic_write.h"
#include "particlemesh/mesh/topology_report.h"
#include "particlemesh/sample/shapes.h"
#include "particlemesh/surface/reconstruct.h"
#include "particlemesh/surface/triangulate.h"
#include "support/test_support.h"

using namespace particlemesh;
using particlemesh::test::status_of;
namespace fs = std::filesystem;

namespace {
void write_text(const fs::path& p, const std::string& s) { std::ofstream(p, std::ios::binary) << s; }

}  // namespace

// An attribute whose PLY name the reader would take for positions, normals or colours (in
// any case, or PCL's normal_x ..; "normal!y" is written normal_y) is written under another
// name: it comes back an attribute, and no normals or colours appear (found by fuzzing).
TEST(MeshIO, AttributesNamedLikeNormalsOrColoursComeBackAttributes) {
  TriMesh m;
  m.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  m.triangles = {{0, 1, 2}};
  for (const char* name : {"normal_x", "normal!y", "normal_z", "RED", "Green", "NX", "Y"})
    m.attributes.push_back({name, 1, {1, 2, 3}});
  const auto dir = test::scratch_dir("mesh_io_names");
  for (const MeshFormat format : {MeshFormat::PlyBinary, MeshFormat::PlyAscii}) {
    WriteMeshOptions o;
    o.format = format;
    const std::string path = (dir / "names.ply").string();
    write_mesh(m, path, o);
    const TriMesh back = read_mesh(path);
    EXPECT_TRUE(back.normals.empty());
    EXPECT_EQ(back.positions, m.positions);
    ASSERT_EQ(back.attributes.size(), m.attributes.size());
    for (const VertexAttribute& a : back.attributes) EXPECT_EQ(a.values, (std::vector<float>{1, 2, 3})) << a.name;
  }
}

TEST(MeshIO, NonManifoldRawTrianglesRoundTripInEveryFormat) {
  const auto dir = test::scratch_dir("io");
  const TriangulateResult raw = triangulate_raw(poisson_disk_sample(icosphere_mesh(4), 0.1, 4));
  for (const char* name : {"m.ply", "m.obj"}) {
    const auto path = (dir / name).string();
    write_mesh(raw.mesh, path);
    const TriMesh back = read_mesh(path);
    EXPECT_EQ(back.triangles, raw.mesh.triangles) << name;  // nothing dropped, order kept
    ASSERT_EQ(back.positions.size(), raw.mesh.positions.size());
    for (size_t i = 0; i < back.positions.size(); ++i)
      EXPECT_LT(distance(back.positions[i], raw.mesh.positions[i]), 1e-6);
    EXPECT_EQ(back.normals.size(), raw.mesh.normals.size()) << name;
  }
  const auto ascii = (dir / "a.ply").string();
  write_mesh(raw.mesh, ascii, {MeshFormat::PlyAscii, true, {}});
  std::ifstream in(ascii);
  std::string line;
  std::getline(in, line);
  std::getline(in, line);
  EXPECT_EQ(line, "format ascii 1.0");
  EXPECT_EQ(read_mesh(ascii).triangles, raw.mesh.triangles);
}

TEST(MeshIO, PointCloudsReadPlyAndXyz) {
  const auto dir = test::scratch_dir("clouds");
  PointCloud c = fibonacci_sphere(100);
  write_point_cloud(c, (dir / "c.xyz").string());
  write_point_cloud(c, (dir / "c.ply").string());
  const PointCloud x = read_point_cloud((dir / "c.xyz").string());
  EXPECT_EQ(x.positions, c.positions);  // 17 digits: exact
  EXPECT_EQ(x.normals.size(), 100u);
  const PointCloud p = read_point_cloud((dir / "c.ply").string());
  ASSERT_EQ(p.size(), 100u);
  EXPECT_TRUE(p.has_normals());
  EXPECT_LT(distance(p.positions[42], c.positions[42]), 1e-6);

  write_text(dir / "plain.xyz", "# comment\n0 0 0\n\n1 0 0  # trailing\n0,1,0\n+1.5e0 2 3\n");
  const PointCloud q = read_point_cloud((dir / "plain.xyz").string());
  EXPECT_EQ(q.size(), 4u);
  EXPECT_FALSE(q.has_normals());
  EXPECT_EQ(q.positions[3], (Vec3{1.5, 2, 3}));
}

// The point clouds MeshLab, Blender and CloudCompare export as OBJ: v lines (often with r g b
// in [0, 1]), sometimes one vn per v in the same order, no faces.
TEST(MeshIO, ObjPointCloudsReadVerticesColoursAndNormals) {
  const auto dir = test::scratch_dir("obj_points");
  auto read = [&](const char* name, const std::string& text) {
    write_text(dir / name, text);
    return read_point_cloud((dir / name).string());
  };
  const std::vector<Vec3> p{{0.1, -2, 3}, {1.5, 0, 0.25}, {-1, 1e-3, 0.30000000000000004}};
  const std::string v = "v 0.1 -2 3\nv 1.5 0 0.25\nv -1 1e-3 0.30000000000000004\n";

  const PointCloud plain = read("plain.obj", "# CloudCompare\no cloud\n" + v);
  EXPECT_EQ(plain.positions, p);  // exact, as every reader keeps them
  EXPECT_FALSE(plain.has_normals());
  EXPECT_TRUE(plain.attributes.empty());

  const PointCloud rgb = read("rgb.obj", "v 0.1 -2 3 1 0 0.5\nv 1.5 0 0.25 0 1 0.25\r\nv -1 1e-3 0.30000000000000004 0.2 0.4 0.6\n");
  EXPECT_EQ(rgb.positions, p);
  EXPECT_FALSE(rgb.has_normals());
  ASSERT_EQ(rgb.attributes.size(), 1u);
  EXPECT_EQ(rgb.attributes[0].name, "color");
  EXPECT_EQ(rgb.attributes[0].components, 3);
  EXPECT_EQ(rgb.attributes[0].values, (std::vector<float>{1, 0, 0.5f, 0, 1, 0.25f, 0.2f, 0.4f, 0.6f}));

  // One vn per v, no faces: the normals, in order (a (0, 0, 0) one kept as it is).
  const std::vector<Vec3> n{{0, 0, 1}, {0.6, -0.8, 0}, {0, 0, 0}};
  const PointCloud normals = read("normals.obj", v + "vn 0 0 1\nvn 0.6 -0.8 0\nvn 0 0 0\n");
  EXPECT_EQ(normals.positions, p);
  EXPECT_EQ(normals.normals, n);
  const PointCloud interleaved = read("interleaved.obj", "v 0.1 -2 3\nvn 0 0 1\nv 1.5 0 0.25\nvn 0.6 -0.8 0\n"
                                                         "v -1 1e-3 0.30000000000000004\nvn 0 0 0\n");
  EXPECT_EQ(interleaved.positions, p);
  EXPECT_EQ(interleaved.normals, n);

  // A vn count that is not the v count says nothing about which normal is whose: none.
  for (const char* vn : {"vn 0 0 1\nvn 0.6 -0.8 0\n", "vn 0 0 1\nvn 0.6 -0.8 0\nvn 0 0 0\nvn 1 0 0\n"}) {
    SCOPED_TRACE(vn);
    const PointCloud c = read("mismatch.obj", v + vn);
    EXPECT_EQ(c.positions, p);
    EXPECT_FALSE(c.has_normals());
  }

  // Faces are ignored for particles (as the PLY reader ignores them), the points kept; the
  // normals then belong to the faces' corners, not to the points.
  const PointCloud faces = read("faces.obj", v + "vn 0 0 1\nvn 0.6 -0.8 0\nvn 0 0 0\nf 1//1 2//2 3//3\n");
  EXPECT_EQ(faces.positions, p);
  EXPECT_FALSE(faces.has_normals());
  const PointCloud rgb_faces = read("rgb_faces.obj", "v 0 0 0 1 1 1\nv 1 0 0 0 0 0\nv 0 1 0 0.5 0.5 0.5\nf 1 2 3\n");
  EXPECT_EQ(rgb_faces.positions, (std::vector<Vec3>{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}));
  ASSERT_EQ(rgb_faces.attributes.size(), 1u);
  EXPECT_EQ(rgb_faces.attributes[0].values, (std::vector<float>{1, 1, 1, 0, 0, 0, 0.5f, 0.5f, 0.5f}));

  // Still hardened: a bad value names its line; a file of no v is no cloud.
  std::string msg;
  write_text(dir / "bad.obj", "v 0 0 0\nv 1 0 0 0.5 0.5 x\nv 0 1 0\n");
  EXPECT_EQ(status_of([&] { read_point_cloud((dir / "bad.obj").string()); }, &msg), Status::FormatError);
  EXPECT_NE(msg.find("bad.obj"), std::string::npos) << msg;
  EXPECT_NE(msg.find("line 2: colour 'x' is not a number"), std::string::npos) << msg;
  write_text(dir / "badvn.obj", "v 0 0 0\nvn 0 0\n");
  EXPECT_EQ(status_of([&] { read_point_cloud((dir / "badvn.obj").string()); }, &msg), Status::FormatError);
  EXPECT_NE(msg.find("line 2: 'vn' with 2 values"), std::string::npos) << msg;
  write_text(dir / "nan.obj", "v 0 0 0\nv 1 nan 0\n");
  EXPECT_EQ(status_of([&] { read_point_cloud((dir / "nan.obj").string()); }, &msg), Status::FormatError);
  EXPECT_NE(msg.find("line 2: vertex y is NaN"), std::string::npos) << msg;
  write_text(dir / "none.obj", "# no vertices\nvn 0 0 1\n");
  EXPECT_EQ(status_of([&] { read_point_cloud((dir / "none.obj").string()); }, &msg), Status::InvalidInput);
}

// Which reader takes a path, by its extension alone (the table read_mesh and read_point_cloud
// look up): what `inspect` asks before it reads.
TEST(MeshIO, FormatsReadAsMeshesOrPoints) {
  EXPECT_TRUE(reads_format("a/b.PLY", false) && reads_format("a/b.PLY", true));
  EXPECT_TRUE(reads_format("m.obj", false) && reads_format("m.obj", true));  // OBJ point clouds too
  // A mesh's vertices as particles (re-meshing a model from its vertices): OFF and STL too.
  EXPECT_TRUE(reads_format("m.off", false) && reads_format("m.off", true));
  EXPECT_TRUE(reads_format("m.STL", false) && reads_format("m.stl", true));
  EXPECT_TRUE(!reads_format("f.bgeo.gz", false) && reads_format("f.bgeo.gz", true));
  EXPECT_TRUE(reads_format("f.vtu", false) && reads_format("f.vtu", true));
  EXPECT_FALSE(reads_format("f.pcd", true));  // the PCL bridge's, not the core reader's
  EXPECT_TRUE(reads_format("x.csv", true) && reads_format("x.TXT", true) && !reads_format("x.csv", false));
  EXPECT_FALSE(reads_format("noextension", false) || reads_format("x.doc", true));
}

TEST(MeshIO, SharedDataLoads) {
  PM_REQUIRE_DATA(points, "points/bunny_poisson.ply");
  PM_REQUIRE_DATA(obj, "meshes/spot.obj");
  const PointCloud c = read_point_cloud(points);
  EXPECT_EQ(c.size(), 8779u);
  EXPECT_TRUE(c.has_normals());
  const TriMesh m = read_mesh(obj);
  EXPECT_EQ(m.positions.size(), 2930u);
  EXPECT_EQ(m.triangles.size(), 5856u);
}

TEST(MeshIO, BadFilesGiveErrorsNamingFileAndProblem) {
  const auto dir = test::scratch_dir("bad");
  std::string msg;
  EXPECT_EQ(status_of([&] { read_point_cloud((dir / "missing.xyz").string()); }, &msg), Status::IoError);
  EXPECT_NE(msg.find("missing.xyz"), std::string::npos);
  write_text(dir / "empty.xyz", "");
  EXPECT_EQ(status_of([&] { read_point_cloud((dir / "empty.xyz").string()); }, &msg), Status::FormatError);
  write_text(dir / "comments.xyz", "# nothing\n\n");
  EXPECT_EQ(status_of([&] { read_point_cloud((dir / "comments.xyz").string()); }, &msg), Status::InvalidInput);
  write_text(dir / "word.xyz", "0 0 0\n1 abc 0\n");
  EXPECT_EQ(status_of([&] { read_point_cloud((dir / "word.xyz").string()); }, &msg), Status::FormatError);
  EXPECT_NE(msg.find("line 2"), std::string::npos) << msg;
  write_text(dir / "cols.xyz", "0 0 0\n1 0 0 0 0 1\n");
  EXPECT_EQ(status_of([&] { read_point_cloud((dir / "cols.xyz").string()); }, &msg), Status::FormatError);
  EXPECT_NE(msg.find("line 2"), std::string::npos) << msg;
  write_text(dir / "two.xyz", "0 0\n");
  EXPECT_EQ(status_of([&] { read_point_cloud((dir / "two.xyz").string()); }, &msg), Status::FormatError);
  write_text(dir / "nan.xyz", "0 0 0\n1 1 1\nnan 0 0\n");
  EXPECT_EQ(status_of([&] { read_point_cloud((dir / "nan.xyz").string()); }, &msg), Status::InvalidInput);
  EXPECT_NE(msg.find("positions[2].x is NaN"), std::string::npos) << msg;
  write_text(dir / "x.e57", "0 0 0\n");
  EXPECT_EQ(status_of([&] { read_point_cloud((dir / "x.e57").string()); }, &msg), Status::FormatError);
  EXPECT_NE(msg.find("unsupported"), std::string::npos);

  // A binary PLY cut short: the reader must fail, not return zeros.
  write_point_cloud(fibonacci_sphere(1000), (dir / "full.ply").string());
  std::ifstream full(dir / "full.ply", std::ios::binary);
  std::string bytes((std::istreambuf_iterator<char>(full)), {});
  write_text(dir / "cut.ply", bytes.substr(0, bytes.size() / 2));
  EXPECT_EQ(status_of([&] { read_point_cloud((dir / "cut.ply").string()); }, &msg), Status::FormatError);
  EXPECT_NE(msg.find("cut.ply"), std::string::npos);
  write_text(dir / "garbage.ply", "this is not a ply file\n");
  EXPECT_EQ(status_of([&] { read_mesh((dir / "garbage.ply").string()); }, &msg), Status::FormatError);

  // OBJ face corners without a vertex index aborted OpenMesh's reader (an assert; found by
  // fuzzing), and a corner that is not a number was read as an uninitialized index.
  const std::string verts = "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvn 0 0 1\n";
  for (const char* face : {"f /1/1 2//1 3//1", "f 1 //1 3", "f x 2 3", "f 1/vt 2 3", "f 1/1/1/1 2 3", "f 1 2 3.5"}) {
    SCOPED_TRACE(face);
    write_text(dir / "bad.obj", verts + face + "\n");
    EXPECT_EQ(status_of([&] { read_mesh((dir / "bad.obj").string()); }, &msg), Status::FormatError);
    EXPECT_NE(msg.find("line 6: face corner"), std::string::npos) << msg;
  }
  for (const char* face : {"f 1 2 3", "f 1/1 2/1 3/1", "f 1//1 2//1 3//1", "f 1/1/1 2/1/1 3/1/1", "f -3 -2 -1", "f 1/ 2/ 3/"}) {
    SCOPED_TRACE(face);
    write_text(dir / "good.obj", verts + face + "\r\n");
    const TriMesh m = read_mesh((dir / "good.obj").string());
    ASSERT_EQ(m.triangles.size(), 1u);
    EXPECT_EQ(m.triangles[0], (Triangle{0, 1, 2}));
  }
  write_text(dir / "range.obj", verts + "f 1 2 9\n");
  EXPECT_EQ(status_of([&] { read_mesh((dir / "range.obj").string()); }, &msg), Status::FormatError);
  EXPECT_NE(msg.find("line 6: face corner '9' names vertex 9, but only 3 are defined so far"), std::string::npos) << msg;
}

TEST(MeshIO, FailedWritesLeaveNothingBehind) {
  const auto dir = test::scratch_dir("atomic");
  TriMesh m = icosphere_mesh(1);
  std::string msg;
  EXPECT_EQ(status_of([&] { write_mesh(m, (dir / "no" / "such" / "m.ply").string()); }, &msg), Status::IoError);
  EXPECT_EQ(status_of([&] { write_mesh(m, (dir / "m.stl2").string()); }), Status::InvalidArgument);
  m.triangles.push_back({0, 1, 999});
  EXPECT_EQ(status_of([&] { write_mesh(m, (dir / "bad.ply").string()); }), Status::InvalidArgument);
  EXPECT_TRUE(fs::is_empty(dir)) << "a temporary or partial file was left";
  // A successful write replaces the old file in one step and leaves no temporary.
  write_file_atomically((dir / "r.json").string(), "old");
  write_file_atomically((dir / "r.json").string(), "new");
  std::ifstream in(dir / "r.json");
  std::string s;
  in >> s;
  EXPECT_EQ(s, "new");
  EXPECT_EQ(std::distance(fs::directory_iterator(dir), fs::directory_iterator()), 1);
}

namespace {
/// A PLY of points whose x y z (and nx ny nz) have PLY type `type` (double, int, ...), in
/// `format` (ascii, binary_little_endian, binary_big_endian).
template <class T>
void write_typed_ply(const fs::path& p, const std::vector<Vec3>& points, const std::vector<Vec3>& normals,
                     const std::string& type, const std::string& format) {
  std::ofstream out(p, std::ios::binary);
  out << "ply\nformat " << format << " 1.0\nelement vertex " << points.size()
      << "\nproperty " << type << " x\nproperty " << type << " y\nproperty " << type << " z\n";
  if (!normals.empty()) out << "property " << type << " nx\nproperty " << type << " ny\nproperty " << type << " nz\n";
  out << "end_header\n";
  auto put = [&](double v) {
    const T t = T(v);
    if (format == "ascii") {
      char s[40];
      std::snprintf(s, sizeof s, "%.17g ", double(t));
      out << s;
      return;
    }
    char b[sizeof(T)];
    std::memcpy(b, &t, sizeof t);
    if (format == "binary_big_endian") std::reverse(b, b + sizeof b);
    out.write(b, sizeof b);
  };
  for (size_t i = 0; i < points.size(); ++i) {
    for (double v : {points[i].x, points[i].y, points[i].z}) put(v);
    if (!normals.empty())
      for (double v : {normals[i].x, normals[i].y, normals[i].z}) put(v);
    if (format == "ascii") out << "\n";
  }
}
}  // namespace

// OpenMesh's readers keep float32: a georeferenced scan (coordinates ~5e6, float32 steps of
// 0.5) came out on a lattice coarser than its spacing, and binary integer coordinates as 0.
TEST(MeshIO, CoordinatesKeepTheirPrecision) {
  const auto dir = test::scratch_dir("precision");
  const Vec3 offset{512345.678, 5412345.678, 250.5};
  PointCloud sphere = fibonacci_sphere(4000, 5.0);  // spacing ~0.28
  PointCloud far = sphere;
  for (Vec3& p : far.positions) p = p + offset;
  for (const char* format : {"ascii", "binary_little_endian", "binary_big_endian"}) {
    const fs::path path = dir / (std::string(format) + ".ply");
    write_typed_ply<double>(path, far.positions, far.normals, "double", format);
    const PointCloud back = read_point_cloud(path.string());
    EXPECT_EQ(back.positions, far.positions) << format;
    EXPECT_EQ(back.normals, far.normals) << format;
  }
  // Integer coordinates (binary: OpenMesh read them as 0), small ones exactly.
  const std::vector<Vec3> grid = {{1, 2, 3}, {-30000, 7, 1}, {4, 5, 6}};
  for (const char* format : {"ascii", "binary_little_endian", "binary_big_endian"}) {
    const fs::path path = dir / (std::string(format) + "_int.ply");
    write_typed_ply<int32_t>(path, grid, {}, "int", format);
    EXPECT_EQ(read_point_cloud(path.string()).positions, grid) << format;
    write_typed_ply<int16_t>(path, grid, {}, "short", format);
    EXPECT_EQ(read_point_cloud(path.string()).positions, grid) << format;
  }
  // OpenMesh's reader complained on std::cerr three times per vertex of such a file; quiet
  // now, and std::cerr works again afterwards.
  write_typed_ply<int32_t>(dir / "many_int.ply", std::vector<Vec3>(200, Vec3{1, 2, 3}), {}, "int", "binary_little_endian");
  testing::internal::CaptureStderr();
  EXPECT_EQ(read_point_cloud((dir / "many_int.ply").string()).positions[199], (Vec3{1, 2, 3}));
  std::cerr << "after";
  EXPECT_EQ(testing::internal::GetCapturedStderr(), "after");
  // float32 files read as before.
  write_typed_ply<float>(dir / "f.ply", grid, {}, "float", "binary_little_endian");
  EXPECT_EQ(read_point_cloud((dir / "f.ply").string()).positions, grid);

  // The far cloud meshes as the sphere it is, every point used (from float32 coordinates its
  // points collapsed onto 0.5-unit steps: duplicates, no sphere).
  const SurfaceResult r = reconstruct_surface(read_point_cloud((dir / "binary_little_endian.ply").string()));
  const TopologyReport t = topology_report(r.mesh);
  EXPECT_TRUE(t.closed);
  EXPECT_EQ(t.components, 1u);
  EXPECT_EQ(t.euler_characteristic, 2);
  EXPECT_EQ(t.vertices_used, 4000u);
  EXPECT_TRUE(t.outward);

  // Written back: float64 positions where float32 would round them (PLY, OBJ, ASCII PLY),
  // read back exactly; a mesh near the origin stays float32.
  for (const char* name : {"far.ply", "far.obj"}) {
    const std::string path = (dir / name).string();
    write_mesh(r.mesh, path);
    const TriMesh back = read_mesh(path);
    EXPECT_EQ(back.positions, r.mesh.positions) << name;
    EXPECT_EQ(back.triangles, r.mesh.triangles) << name;
  }
  write_mesh(r.mesh, (dir / "far_ascii.ply").string(), {MeshFormat::PlyAscii, true, {}});
  EXPECT_EQ(read_mesh((dir / "far_ascii.ply").string()).positions, r.mesh.positions);
  auto header_says = [&](const std::string& path, const std::string& line) {
    std::ifstream in(path);
    for (std::string l; std::getline(in, l) && l != "end_header";)
      if (l == line) return true;
    return false;
  };
  EXPECT_TRUE(header_says((dir / "far.ply").string(), "property double x"));
  const SurfaceResult near = reconstruct_surface(sphere);
  write_mesh(near.mesh, (dir / "near.ply").string());
  EXPECT_TRUE(header_says((dir / "near.ply").string(), "property float x"));
}

TEST(MeshIO, BinaryPlyHasOpenMeshsLayoutByteForByte) {
  // The binary PLY writer fills the file on all cores; its bytes are those of OpenMesh's PLY
  // writer (which wrote these files before): this header, float32 x y z (nx ny nz), then
  // faces as a uchar count and three int32 indices. OpenMesh's reader reads it back.
  const fs::path dir = test::scratch_dir("ply");
  TriMesh m = torus_mesh(1.0, 0.3, 40, 20);
  const std::string path = (dir / "torus.ply").string();
  write_mesh(m, path);
  std::ifstream in(path, std::ios::binary);
  const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const std::string header = "ply\nformat binary_little_endian 1.0\nelement vertex 800\nproperty float x\n"
                             "property float y\nproperty float z\nproperty float nx\nproperty float ny\n"
                             "property float nz\nelement face 1600\nproperty list uchar int vertex_indices\n"
                             "end_header\n";
  ASSERT_EQ(bytes.substr(0, header.size()), header);
  ASSERT_EQ(bytes.size(), header.size() + 800 * 24 + 1600 * 13);
  for (size_t i = 0; i < 800; ++i) {
    float v[6];
    std::memcpy(v, bytes.data() + header.size() + 24 * i, sizeof v);
    ASSERT_EQ(v[0], float(m.positions[i].x));
    ASSERT_EQ(v[2], float(m.positions[i].z));
    ASSERT_EQ(v[3], float(m.normals[i].x));
    ASSERT_EQ(v[5], float(m.normals[i].z));
  }
  for (size_t f = 0; f < 1600; ++f) {
    const char* d = bytes.data() + header.size() + 800 * 24 + 13 * f;
    ASSERT_EQ(d[0], 3);
    uint32_t t[3];
    std::memcpy(t, d + 1, sizeof t);
    ASSERT_EQ(t[0], m.triangles[f][0]);
    ASSERT_EQ(t[2], m.triangles[f][2]);
  }
  const TriMesh back = read_mesh(path);
  EXPECT_EQ(back.triangles, m.triangles);
  ASSERT_EQ(back.positions.size(), m.positions.size());
  for (size_t i = 0; i < m.positions.size(); ++i) EXPECT_EQ(back.positions[i].y, double(float(m.positions[i].y)));
  // Without normals: no normal properties, 12 bytes per vertex.
  m.normals.clear();
  write_mesh(m, path);
  std::ifstream in2(path, std::ios::binary);
  const std::string bytes2((std::istreambuf_iterator<char>(in2)), std::istreambuf_iterator<char>());
  EXPECT_EQ(bytes2.find("property float nx"), std::string::npos);
  EXPECT_EQ(bytes2.size(), header.size() - 3 * std::string("property float nx\n").size() + 800 * 12 + 1600 * 13);
}

// The writers' choice of float64 positions (where float32 would round them by more than 1e-6
// of the mesh's size, or overflow) against a plain serial statement of the rule, on small
// meshes where the deciding point may be anywhere (the first, the last, a leftover of the
// writer's four-at-a-time scan) and with NaN, signed zeros, subnormals and huge values.
TEST(MeshIO, Float64PositionsExactlyWhereFloat32WouldRoundThem) {
  auto reference = [](const std::vector<Vec3>& P) {
    if (P.empty()) return false;
    Vec3 lo = P[0], hi = P[0];
    double largest = 0, smallest = DBL_MAX;
    for (const Vec3& p : P) {
      lo = {std::min(lo.x, p.x), std::min(lo.y, p.y), std::min(lo.z, p.z)};
      hi = {std::max(hi.x, p.x), std::max(hi.y, p.y), std::max(hi.z, p.z)};
      for (const double v : {p.x, p.y, p.z}) {
        largest = std::max(largest, std::abs(v));
        smallest = std::min(smallest, std::abs(v) > 0 ? std::abs(v) : DBL_MAX);
      }
    }
    if (largest > FLT_MAX) return true;
    double rounding = largest * 0x1p-24;
    if (smallest < FLT_MIN) rounding = std::max(rounding, 0x1p-150);
    return rounding > 1e-6 * norm(hi - lo);
  };
  const fs::path dir = test::scratch_dir("float64");
  const std::string path = (dir / "m.ply").string();
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> unit(-1, 1);
  const double specials[] = {std::nan(""), -0.0, 0.0, 1e-39, 1e39, -1e39, 1e-300};
  int doubles = 0, floats = 0;
  for (size_t n = 1; n <= 11; ++n)
    for (int trial = 0; trial < 36; ++trial) {
      const double base = std::array<double, 4>{0, 1, 1000, 1e6}[rng() % 4];
      const double spread = std::pow(10.0, double(rng() % 9) - 4);
      TriMesh m;
      for (size_t i = 0; i < n; ++i) m.positions.push_back({base + spread * unit(rng), base, base - spread * unit(rng)});
      if (trial % 3 == 1) {  // one far or odd coordinate, anywhere
        const size_t i = rng() % n;
        const double v = trial % 2 ? specials[rng() % 7] : base + 1e3 * spread * unit(rng);
        Vec3& p = m.positions[i];
        (rng() % 3 == 0 ? p.x : rng() % 2 ? p.y : p.z) = v;
      }
      write_mesh(m, path);
      std::ifstream in(path);
      std::string line;
      for (int k = 0; k < 4; ++k) std::getline(in, line);  // ply, format, element vertex, first property
      const bool want = reference(m.positions);
      EXPECT_EQ(line, want ? "property double x" : "property float x") << n << " points, trial " << trial;
      (want ? doubles : floats) += 1;
    }
  EXPECT_GT(doubles, 60);  // both answers are exercised
  EXPECT_GT(floats, 60);
}
