// The file readers (native/src/io/*_reader.cpp): each file read once, front to back, every
// value exact, every malformed file refused with the file, the element or line, and the
// problem named. The PLY cases are the ones a hostile user found: a list property inside the
// vertex element, no z, upper-case X Y Z, faces before vertices, counts smaller than the data.
#include <gtest/gtest.h>

#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <string>
#include <sys/stat.h>
#include <thread>
#include <tuple>

#include "particlemesh/core/error.h"
#include "particlemesh/io/frame_collection.h"
#include "particlemesh/io/mesh_io.h"
#include "particlemesh/mesh/topology_report.h"
#include "particlemesh/sample/shapes.h"
#include <zlib.h>

#include "support/compressed_vtu.h"
#include "support/houdini_scf.h"
#include "support/test_support.h"

using namespace particlemesh;
using particlemesh::test::status_of;
namespace fs = std::filesystem;

namespace {

std::string write(const fs::path& p, const std::string& bytes) {
  std::ofstream(p, std::ios::binary).write(bytes.data(), std::streamsize(bytes.size()));
  return p.string();
}

/// The attribute of that name, or nullptr.
const VertexAttribute* attribute(const PointCloud& c, const std::string& name) {
  for (const VertexAttribute& a : c.attributes)
    if (a.name == name) return &a;
  return nullptr;
}

/// An ASCII PLY header: two vertices with these float properties.
std::string two_vertex_ply_header(std::initializer_list<const char*> props) {
  std::string h = "ply\nformat ascii 1.0\nelement vertex 2\n";
  for (const char* p : props) h += std::string("property float ") + p + "\n";
  return h + "end_header\n";
}

/// `read(path)` of a FIFO at `fifo` (made afresh) that a thread writes `bytes` into: how a
/// reader takes a stream whose length it does not know. The status, its message in `msg`.
template <class F>
Status read_through_fifo(const fs::path& fifo, const std::string& bytes, F&& read, std::string& msg) {
  fs::remove(fifo);
  if (::mkfifo(fifo.c_str(), 0600) != 0) {
    msg = "mkfifo failed";
    return Status::IoError;
  }
  std::thread writer([&] { std::ofstream(fifo, std::ios::binary).write(bytes.data(), std::streamsize(bytes.size())); });
  const Status s = status_of([&] { read(fifo.string()); }, &msg);
  writer.join();
  return s;
}

template <class T>
void append(std::string& s, T v) {
  s.append(reinterpret_cast<const char*>(&v), sizeof v);
}


#define EXPECT_REFUSED(call, status, text)                                   \
  do {                                                                       \
    std::string msg_;                                                        \
    EXPECT_EQ(status_of([&] { (void)(call); }, &msg_), (status)) << msg_;    \
    EXPECT_NE(msg_.find(text), std::string::npos) << "message: " << msg_;    \
  } while (0)

const std::string kTriangle = "element face 1\nproperty list uchar int vertex_indices\n";

}  // namespace

// A list property inside the vertex element (a per-vertex neighbour list, say): its items are
// skipped, the coordinates after it read right. Before: ASCII coordinates shifted silently
// (exit 0), binary "positions[176].x is NaN".
TEST(PlyReader, ListPropertyInsideTheVertexElement) {
  const auto dir = test::scratch_dir("list");
  const std::string head = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty list uchar int ids\n"
                           "property float y\nproperty float z\n" + kTriangle + "end_header\n";
  const TriMesh a = read_mesh(write(dir / "a.ply", head + "0 2 7 8 0 0\n1 0 0 0\n0 3 1 2 3 1 0\n3 0 1 2\n"));
  ASSERT_EQ(a.positions.size(), 3u);
  EXPECT_EQ(a.positions[0], (Vec3{0, 0, 0}));
  EXPECT_EQ(a.positions[1], (Vec3{1, 0, 0}));
  EXPECT_EQ(a.positions[2], (Vec3{0, 1, 0}));
  EXPECT_EQ(a.triangles, (std::vector<Triangle>{{0, 1, 2}}));
  std::string b = "ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\nproperty list uchar int ids\n"
                  "property float y\nproperty float z\n" + kTriangle + "end_header\n";
  const float xyz[3][3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  for (int v = 0; v < 3; ++v) {
    append(b, xyz[v][0]);
    b += char(v);  // v list items
    for (int k = 0; k < v; ++k) append(b, int32_t(100 + k));
    append(b, xyz[v][1]);
    append(b, xyz[v][2]);
  }
  b += char(3);
  for (int32_t i : {0, 1, 2}) append(b, i);
  const PointCloud c = read_point_cloud(write(dir / "b.ply", b));
  ASSERT_EQ(c.size(), 3u);
  EXPECT_EQ(c.positions[1], (Vec3{1, 0, 0}));
  EXPECT_EQ(c.positions[2], (Vec3{0, 1, 0}));
  // Not a channel (a list per vertex), and said so.
  EXPECT_EQ(c.not_read, std::vector<std::string>{"vertex list property 'ids' (lists)"});
  EXPECT_TRUE(c.attributes.empty());
  // A file may declare thousands: 32 are named, the rest counted (no quadratic search).
  std::string many = "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nproperty float z\n";
  for (int k = 0; k < 40; ++k) many += "property list uchar int l" + std::to_string(k) + "\n";
  many += "end_header\n0 0 0";
  for (int k = 0; k < 40; ++k) many += " 0";
  const PointCloud d = read_point_cloud(write(dir / "many.ply", many + "\n"));
  ASSERT_EQ(d.not_read.size(), 33u);
  EXPECT_EQ(d.not_read[31], "vertex list property 'l31' (lists)");
  EXPECT_EQ(d.not_read[32], "and 8 more");
  EXPECT_EQ(read_mesh((dir / "b.ply").string()).triangles.size(), 1u);
}

// No z: refused by name (before: z = 0, exit 0). X Y Z in upper case: read (before: "all
// points coincide", the file not named). Exact-case names win over other cases.
TEST(PlyReader, CoordinatePropertiesByName) {
  const auto dir = test::scratch_dir("names");
  EXPECT_REFUSED(read_point_cloud(write(dir / "noz.ply", "ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\n"
                                                         "property float y\nend_header\n0 0\n1 1\n")),
                 Status::FormatError, "noz.ply': the 'vertex' element has no 'z' property (it has: x y)");
  const PointCloud up = read_point_cloud(write(dir / "up.ply", "ply\nformat ascii 1.0\nelement vertex 2\nproperty double X\n"
                                                               "property double Y\nproperty double Z\nend_header\n"
                                                               "0.1 0.2 0.30000000000000004\n1 2 3\n"));
  ASSERT_EQ(up.size(), 2u);
  EXPECT_EQ(up.positions[0], (Vec3{0.1, 0.2, 0.30000000000000004}));
  const PointCloud both = read_point_cloud(write(dir / "both.ply", "ply\nformat ascii 1.0\nelement vertex 1\nproperty float X\n"
                                                                   "property float x\nproperty float y\nproperty float z\n"
                                                                   "end_header\n9 1 2 3\n"));
  EXPECT_EQ(both.positions[0], (Vec3{1, 2, 3}));
  ASSERT_EQ(both.attributes.size(), 1u);  // "X" is kept, as an attribute
  EXPECT_EQ(both.attributes[0].name, "X");
  EXPECT_EQ(both.attributes[0].values, std::vector<float>{9});
}

// A face element before the vertex element is valid PLY (before: "a face refers to a vertex
// that does not exist"). Faces with fewer than three corners are named, never dropped.
TEST(PlyReader, ElementOrderAndFaceCorners) {
  const auto dir = test::scratch_dir("order");
  const TriMesh m = read_mesh(write(dir / "f.ply", "ply\nformat ascii 1.0\n" + kTriangle +
                                                       "element vertex 3\nproperty float x\nproperty float y\n"
                                                       "property float z\nend_header\n3 2 1 0\n0 0 0\n1 0 0\n0 1 0\n"));
  EXPECT_EQ(m.triangles, (std::vector<Triangle>{{2, 1, 0}}));
  EXPECT_EQ(m.positions[1], (Vec3{1, 0, 0}));
  const std::string v3 = "element vertex 3\nproperty float x\nproperty float y\nproperty float z\n";
  EXPECT_REFUSED(read_mesh(write(dir / "two.ply", "ply\nformat ascii 1.0\n" + v3 + kTriangle +
                                                      "end_header\n0 0 0\n1 0 0\n0 1 0\n2 0 1\n")),
                 Status::FormatError, "'face' element 0 has 2 corners (a face needs at least 3)");
  EXPECT_REFUSED(read_mesh(write(dir / "far.ply", "ply\nformat ascii 1.0\n" + v3 + kTriangle +
                                                      "end_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 3\n")),
                 Status::FormatError, "a face refers to vertex 3, but the file has 3 vertices");
  // A quad is fanned.
  EXPECT_EQ(read_mesh(write(dir / "quad.ply", "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\n"
                                              "property float z\n" + kTriangle + "end_header\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n4 0 1 2 3\n"))
                .triangles,
            (std::vector<Triangle>{{0, 1, 2}, {0, 2, 3}}));
  // Triangle strips (a "tristrips" element, -1 restarting a strip), as the Stanford
  // repository's older models hold them: every other triangle turned to keep the strip's
  // orientation; the joins' triangles with a repeated corner dropped.
  const std::string v6 = "element vertex 6\nproperty float x\nproperty float y\nproperty float z\n";
  const std::string grid = "0 0 0\n0 1 0\n1 0 0\n1 1 0\n2 0 0\n2 1 0\n";
  const std::string strips = "element tristrips 1\nproperty list int int vertex_indices\n";
  const TriMesh s = read_mesh(write(dir / "strips.ply", "ply\nformat ascii 1.0\n" + v6 + strips + "end_header\n" + grid +
                                                          "11 0 1 2 3 -1 2 3 4 4 4 5\n"));
  EXPECT_EQ(s.triangles, (std::vector<Triangle>{{0, 1, 2}, {2, 1, 3}, {2, 3, 4}}));
  EXPECT_REFUSED(read_mesh(write(dir / "strips_bad.ply", "ply\nformat ascii 1.0\n" + v6 + strips + "end_header\n" +
                                                             grid + "4 0 1 2 -2\n")),
                 Status::FormatError, "'tristrips' element 0 refers to vertex -2 (indices start at 0; -1 ends a strip)");
}

// Header counts smaller than the data: refused, ASCII and binary (before: the rest ignored
// silently). Trailing whitespace (a last newline) is fine.
TEST(PlyReader, DataBeyondTheHeaderCounts) {
  const auto dir = test::scratch_dir("more");
  const std::string a = "ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty float y\nproperty float z\n"
                        "end_header\n0 0 0\n1 0 0\n";
  EXPECT_EQ(read_point_cloud(write(dir / "ok.ply", a + "\n \n")).size(), 2u);
  EXPECT_REFUSED(read_point_cloud(write(dir / "a.ply", a + "0 1 0\n")), Status::FormatError,
                 "a.ply': more data after the 2 'vertex' elements the header declares");
  std::string b = "ply\nformat binary_little_endian 1.0\nelement vertex 2\nproperty float x\nproperty float y\n"
                  "property float z\nend_header\n";
  for (int i = 0; i < 9; ++i) append(b, float(i));
  EXPECT_REFUSED(read_point_cloud(write(dir / "b.ply", b)), Status::FormatError, "more data after the 2 'vertex' elements");
  EXPECT_REFUSED(read_mesh((dir / "b.ply").string()), Status::FormatError, "a count in the header is too small");
}

// Values: doubles far beyond float32 (4e38 and more) are read exactly and the faces kept
// (before: every face dropped, inspect said 0 triangles with exit 0); NaN and values beyond
// double are named.
TEST(PlyReader, ValuesBeyondFloat) {
  const auto dir = test::scratch_dir("values");
  std::string b = "ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty double x\nproperty double y\n"
                  "property double z\n" + kTriangle + "end_header\n";
  for (double v : {4e38, 0.0, 0.0, 5e38, 0.0, 0.0, 4e38, 1e38, 0.0}) append(b, v);
  b += char(3);
  for (int32_t i : {0, 1, 2}) append(b, i);
  const TriMesh m = read_mesh(write(dir / "big.ply", b));
  ASSERT_EQ(m.triangles.size(), 1u);
  EXPECT_EQ(m.positions[1].x, 5e38);
  EXPECT_EQ(topology_report(m).triangles, 1u);
  const std::string h = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n" +
                        kTriangle + "end_header\n";
  EXPECT_REFUSED(read_mesh(write(dir / "inf.ply", h + "0 0 0\n1e400 0 0\n0 1 0\n3 0 1 2\n")), Status::FormatError,
                 "'vertex' element 1: x = 1e400 is beyond the range of double");
  EXPECT_REFUSED(read_mesh(write(dir / "nan.ply", h + "0 0 0\n1 nan 0\n0 1 0\n3 0 1 2\n")), Status::FormatError,
                 "vertex 1: y is NaN");
}

// Colours and other vertex properties come out as attributes (the first for the surface
// stages and the writers, the rest for whoever reads them), and a mesh written with colours
// reads back with them.
TEST(PlyReader, ColoursAndOtherPropertiesAreAttributes) {
  const auto dir = test::scratch_dir("attrs");
  const PointCloud c = read_point_cloud(write(dir / "c.ply", "ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\n"
                                                             "property float y\nproperty float z\nproperty uchar red\n"
                                                             "property uchar green\nproperty uchar blue\nproperty float "
                                                             "density\nend_header\n0 0 0 255 0 51 7.5\n1 0 0 0 255 0 8\n"));
  ASSERT_EQ(c.attributes.size(), 2u);
  EXPECT_EQ(c.attributes[0].name, "color");
  EXPECT_EQ(c.attributes[0].components, 3);
  EXPECT_FLOAT_EQ(c.attributes[0].values[2], 0.2f);
  EXPECT_EQ(c.attributes[1].name, "density");
  EXPECT_EQ(c.attributes[1].values, (std::vector<float>{7.5f, 8.0f}));
  TriMesh m = icosphere_mesh(1);
  m.attributes.push_back({"color", 3, {}});
  for (size_t i = 0; i < m.positions.size(); ++i)
    m.attributes[0].values.insert(m.attributes[0].values.end(), {float(i % 2), 0.5f, 1.0f});
  for (const char* name : {"m.ply", "a.ply"}) {
    write_mesh(m, (dir / name).string(), {std::string(name) == "a.ply" ? MeshFormat::PlyAscii : MeshFormat::Auto, true, {}});
    const TriMesh back = read_mesh((dir / name).string());
    ASSERT_EQ(back.attributes.size(), 1u) << name;
    ASSERT_EQ(back.attributes[0].values.size(), m.attributes[0].values.size());
    for (size_t i = 0; i < back.attributes[0].values.size(); ++i)
      EXPECT_NEAR(back.attributes[0].values[i], m.attributes[0].values[i], 0.5 / 255 + 1e-6) << name << " " << i;
  }
  // Other attributes are float properties; names are kept unique ("x" is taken).
  m.attributes.push_back({"x", 1, std::vector<float>(m.positions.size(), 2.5f)});
  m.attributes.push_back({"v", 2, std::vector<float>(2 * m.positions.size(), -1.0f)});
  write_mesh(m, (dir / "more.ply").string());
  const TriMesh back = read_mesh((dir / "more.ply").string());
  ASSERT_EQ(back.attributes.size(), 3u);
  EXPECT_EQ(back.attributes[1].name, "x_");
  EXPECT_EQ(back.attributes[1].values[7], 2.5f);
  // The vector channel, written as v_0 v_1, comes back as the 2-component channel it was.
  EXPECT_EQ(back.attributes[2].name, "v");
  EXPECT_EQ(back.attributes[2].components, 2);
  EXPECT_EQ(back.attributes[2].values, m.attributes[2].values);
}

// Binary vertices are read in blocks of records (a million a few times faster than value by
// value): the same particles, normals, colours and channels, exactly, whether the file is
// ASCII, little- or big-endian, or a FIFO (read value by value, its length unknown), with
// mixed types, and more vertices than one block holds.
TEST(PlyReader, BinaryVerticesInBlocksAreTheValuesOfEveryEncoding) {
  const auto dir = test::scratch_dir("blocks");
  const size_t n = 70000;  // ~2.7 blocks of 1 MiB at 40 bytes a record
  const char* header =
      "element vertex 70000\nproperty double x\nproperty float y\nproperty short z\nproperty uchar red\n"
      "property uchar green\nproperty uchar blue\nproperty float nx\nproperty float ny\nproperty float nz\n"
      "property ushort density\nproperty char flag\nproperty int id\nend_header\n";
  std::string le = std::string("ply\nformat binary_little_endian 1.0\n") + header;
  std::string be = std::string("ply\nformat binary_big_endian 1.0\n") + header;
  std::string ascii = std::string("ply\nformat ascii 1.0\n") + header;
  auto both = [&](auto v) {
    append(le, v);
    char b[sizeof v];
    std::memcpy(b, &v, sizeof v);
    std::reverse(b, b + sizeof v);
    be.append(b, sizeof v);
  };
  char line[256];
  for (size_t i = 0; i < n; ++i) {
    const double x = double(i) * 0.5 + 0.25;
    const float y = float(i) / 7.0f, nx = float(i % 3) - 1.0f, ny = 0.5f, nz = -float(i) * 1e-3f;
    const auto z = int16_t(int(i % 30000) - 15000);
    const auto r = uint8_t(i % 256), g = uint8_t(i * 7 % 256), b = uint8_t(255 - i % 256);
    const auto density = uint16_t(i * 13 % 65536);
    const auto flag = int8_t(int(i % 100) - 50);
    const auto id = int32_t(i);
    both(x), both(y), both(z), both(r), both(g), both(b), both(nx), both(ny), both(nz), both(density), both(flag), both(id);
    std::snprintf(line, sizeof line, "%.17g %.17g %d %u %u %u %.17g %.17g %.17g %u %d %d\n", x, double(y), int(z), unsigned(r),
                  unsigned(g), unsigned(b), double(nx), double(ny), double(nz), unsigned(density), int(flag), int(id));
    ascii += line;
  }
  const PointCloud want = read_point_cloud(write(dir / "a.ply", ascii));
  ASSERT_EQ(want.size(), n);
  ASSERT_TRUE(want.has_normals());
  EXPECT_EQ(want.positions[12345].x, 12345 * 0.5 + 0.25);
  EXPECT_EQ(want.positions[12345].z, double(int(12345 % 30000) - 15000));
  ASSERT_NE(attribute(want, "color"), nullptr);
  ASSERT_NE(attribute(want, "density"), nullptr);
  ASSERT_NE(attribute(want, "flag"), nullptr);
  auto same = [&](const PointCloud& c, const std::string& what) {
    ASSERT_EQ(c.size(), n) << what;
    ASSERT_EQ(c.normals.size(), n) << what;
    size_t first_wrong = n;  // the first vertex whose position or normal differs
    for (size_t i = n; i-- > 0;)
      if (!(c.positions[i] == want.positions[i]) || !(c.normals[i] == want.normals[i])) first_wrong = i;
    EXPECT_EQ(first_wrong, n) << what;
    ASSERT_EQ(c.attributes.size(), want.attributes.size()) << what;
    for (size_t k = 0; k < c.attributes.size(); ++k) {
      EXPECT_EQ(c.attributes[k].name, want.attributes[k].name) << what;
      EXPECT_TRUE(c.attributes[k].values == want.attributes[k].values) << what << " " << c.attributes[k].name;
    }
  };
  same(read_point_cloud(write(dir / "le.ply", le)), "little-endian");
  same(read_point_cloud(write(dir / "be.ply", be)), "big-endian");
  PointCloud piped;
  std::string msg;
  ASSERT_EQ(read_through_fifo(dir / "pipe.ply", le, [&](const std::string& f) { piped = read_point_cloud(f); }, msg),
            Status::Ok) << msg;
  same(piped, "FIFO");
  // One record short: refused before anything is read, naming the count.
  EXPECT_REFUSED(read_point_cloud(write(dir / "short.ply", le.substr(0, le.size() - 1))), Status::FormatError,
                 "truncated: the header promises 70000 'vertex' elements");
}

// Binary faces of indices only are parsed a buffer at a time: the same triangles as the ASCII
// file and a FIFO give, for int and uint indices in either byte order, with triangles, quads
// and a polygon of 220 corners among them (records cut by every buffer's end); a bad face
// anywhere (too few corners, a negative index, 2^32 - 1) is named as before, with its element
// number, and so is a file cut inside its last face.
TEST(PlyReader, BinaryFacesInBlocksAreTheFacesOfEveryEncoding) {
  const auto dir = test::scratch_dir("faces");
  const uint32_t vertices = 3000;
  std::vector<std::vector<uint32_t>> faces;
  for (uint32_t f = 0; f < 20000; ++f) {
    const uint32_t n = f == 7777 ? 220 : 3 + (f % 7 == 0);  // triangles, quads, one long polygon
    std::vector<uint32_t> c;
    for (uint32_t k = 0; k < n; ++k) c.push_back((f * 31 + k * 17) % vertices);
    faces.push_back(c);
  }
  auto header = [&](const char* format, const char* index_type, size_t count) {
    return std::string("ply\nformat ") + format + " 1.0\nelement vertex " + std::to_string(vertices) +
           "\nproperty float x\nproperty float y\nproperty float z\nelement face " + std::to_string(count) +
           "\nproperty list uchar " + index_type + " vertex_indices\nend_header\n";
  };
  auto binary = [&](bool big_endian, const char* index_type, const std::vector<std::vector<uint32_t>>& fs) {
    std::string b = header(big_endian ? "binary_big_endian" : "binary_little_endian", index_type, fs.size());
    auto put = [&](auto v) {
      char raw[sizeof v];
      std::memcpy(raw, &v, sizeof v);
      if (big_endian) std::reverse(raw, raw + sizeof v);
      b.append(raw, sizeof v);
    };
    for (uint32_t v = 0; v < vertices; ++v) put(float(v)), put(float(v % 13)), put(float(v % 7));
    for (const auto& c : fs) {
      b += char(uint8_t(c.size()));
      for (uint32_t v : c) put(v);
    }
    return b;
  };
  std::string ascii = header("ascii", "int", faces.size());
  for (uint32_t v = 0; v < vertices; ++v)
    ascii += std::to_string(v) + " " + std::to_string(v % 13) + " " + std::to_string(v % 7) + "\n";
  for (const auto& c : faces) {
    ascii += std::to_string(c.size());
    for (uint32_t v : c) ascii += " " + std::to_string(v);
    ascii += "\n";
  }
  const TriMesh want = read_mesh(write(dir / "a.ply", ascii));
  size_t fanned = 0;
  for (const auto& c : faces) fanned += c.size() - 2;
  ASSERT_EQ(want.triangles.size(), fanned);
  for (const bool big_endian : {false, true})
    for (const char* type : {"int", "uint"}) {
      const std::string what = std::string(big_endian ? "big-endian " : "little-endian ") + type;
      const std::string b = binary(big_endian, type, faces);
      EXPECT_EQ(read_mesh(write(dir / "b.ply", b)).triangles, want.triangles) << what;
      TriMesh piped;
      std::string msg;
      ASSERT_EQ(read_through_fifo(dir / "pipe.ply", b, [&](const std::string& f) { piped = read_mesh(f); }, msg),
                Status::Ok) << msg << " " << what;
      EXPECT_EQ(piped.triangles, want.triangles) << what << " (FIFO)";
    }
  // Bad faces, named by their element number, wherever they lie.
  for (const size_t at : {size_t(0), size_t(4000), size_t(19999)}) {
    auto bad = faces;
    bad[at] = {1, 2};
    EXPECT_REFUSED(read_mesh(write(dir / "c.ply", binary(false, "int", bad))), Status::FormatError,
                   "'face' element " + std::to_string(at) + " has 2 corners (a face needs at least 3)");
    bad[at] = {1, 2, uint32_t(-5)};
    EXPECT_REFUSED(read_mesh(write(dir / "d.ply", binary(true, "int", bad))), Status::FormatError,
                   "'face' element " + std::to_string(at) + " refers to vertex -5 (indices start at 0)");
    bad[at] = {1, 2, UINT32_MAX};
    EXPECT_REFUSED(read_mesh(write(dir / "e.ply", binary(false, "uint", bad))), Status::FormatError,
                   "'face' element " + std::to_string(at) + " refers to vertex 4294967295, beyond 2^32 - 2");
  }
  // Cut inside the last face: the general path names the truncation.
  const std::string b = binary(false, "int", faces);
  std::string msg;
  EXPECT_EQ(status_of([&] { (void)read_mesh(write(dir / "f.ply", b.substr(0, b.size() - 2))); }, &msg), Status::FormatError);
  EXPECT_NE(msg.find("19999"), std::string::npos) << msg;
}

// Properties name_0 .. name_k one after another are one vector channel "name" (our writers'
// spelling of a vector), interleaved per vertex; properties not declared one after another,
// runs that do not start at 0, have one member, skip an index or whose "name" is taken stay
// apart.
TEST(PlyReader, NumberedPropertiesAreOneVectorChannel) {
  const auto dir = test::scratch_dir("vector_channels");
  const auto header = two_vertex_ply_header;
  const PointCloud c = read_point_cloud(
      write(dir / "v.ply", header({"w_0", "x", "w_1", "y", "z", "velocity_0", "velocity_1",
                                   "velocity_2", "id", "stress_0", "stress_1", "stress_2", "stress_3"}) +
                               "9 0 9 0 0 1 2 3 7 1 2 3 4\n9 1 9 0 0 4 5 6 8 5 6 7 8\n"));
  ASSERT_EQ(c.positions.size(), 2u);
  EXPECT_EQ(c.positions[1], (Vec3{1, 0, 0}));
  std::vector<std::string> names;
  for (const VertexAttribute& a : c.attributes) names.push_back(a.name);
  // w_0 and w_1 are not declared next to each other (x stands between them): apart.
  EXPECT_EQ(names, (std::vector<std::string>{"w_0", "w_1", "velocity", "id", "stress"}));
  EXPECT_EQ(c.attributes[2].components, 3);
  EXPECT_EQ(c.attributes[2].values, (std::vector<float>{1, 2, 3, 4, 5, 6}));
  EXPECT_EQ(c.attributes[3].components, 1);
  EXPECT_EQ(c.attributes[3].values, (std::vector<float>{7, 8}));
  EXPECT_EQ(c.attributes[4].components, 4);
  EXPECT_EQ(c.attributes[4].values, (std::vector<float>{1, 2, 3, 4, 5, 6, 7, 8}));
  // Not runs: one member, a start at 1, a gap, and a name that is a property's own.
  const PointCloud apart = read_point_cloud(
      write(dir / "apart.ply", header({"x", "y", "z", "a_0", "b_1", "b_2", "c_0", "c_2", "d", "d_0", "d_1", "_0", "_1"}) +
                                   "0 0 0 1 2 3 4 5 6 7 8 9 10\n1 0 0 1 2 3 4 5 6 7 8 9 10\n"));
  names.clear();
  for (const VertexAttribute& a : apart.attributes) {
    names.push_back(a.name);
    EXPECT_EQ(a.components, 1) << a.name;
  }
  EXPECT_EQ(names, (std::vector<std::string>{"a_0", "b_1", "b_2", "c_0", "c_2", "d", "d_0", "d_1", "_0", "_1"}));
  // A mesh's vector channel through binary and ASCII PLY, and a colour beside a "color_0" run.
  TriMesh m = icosphere_mesh(1);
  m.attributes.push_back({"velocity", 3, {}});
  m.attributes.push_back({"color", 3, {}});
  for (size_t i = 0; i < m.positions.size(); ++i) {
    m.attributes[0].values.insert(m.attributes[0].values.end(), {float(i), -float(i), 0.5f});
    m.attributes[1].values.insert(m.attributes[1].values.end(), {1.0f, 0.0f, 1.0f});
  }
  for (const MeshFormat format : {MeshFormat::Auto, MeshFormat::PlyAscii}) {
    const std::string name = format == MeshFormat::Auto ? "m.ply" : "a.ply";
    WriteMeshOptions options;
    options.format = format;
    write_mesh(m, (dir / name).string(), options);
    const TriMesh back = read_mesh((dir / name).string());
    ASSERT_EQ(back.attributes.size(), 2u) << name;
    EXPECT_EQ(back.attributes[0].name, "color") << name;
    EXPECT_EQ(back.attributes[1].name, "velocity") << name;
    EXPECT_EQ(back.attributes[1].components, 3) << name;
    EXPECT_EQ(back.attributes[1].values, m.attributes[0].values) << name;
  }
  const PointCloud colours = read_point_cloud(
      write(dir / "colours.ply", header({"x", "y", "z", "color_0", "color_1"}) + "0 0 0 1 2\n1 0 0 3 4\n"));
  ASSERT_EQ(colours.attributes.size(), 1u);  // no colour properties: "color" is free
  EXPECT_EQ(colours.attributes[0].name, "color");
  EXPECT_EQ(colours.attributes[0].components, 2);
}

// The other spellings of a vector the text reader knows (vx vy vz, name_x name_y name_z,
// name.x, name[x]) are one channel in a PLY too, and normal_x normal_y normal_z (PCL's field
// names, which the text reader reads too) are the normals when no nx ny nz are declared.
TEST(PlyReader, VectorSpellingsAndNormalFieldNames) {
  const auto dir = test::scratch_dir("ply_vector_spellings");
  const auto header = two_vertex_ply_header;
  const PointCloud pcl = read_point_cloud(
      write(dir / "pcl.ply", header({"x", "y", "z", "normal_x", "normal_y", "normal_z", "curvature"}) +
                                 "0 0 0 0 0 1 0.5\n1 0 0 0 1 0 0.25\n"));
  ASSERT_EQ(pcl.normals.size(), 2u);
  EXPECT_EQ(pcl.normals[1], (Vec3{0, 1, 0}));
  ASSERT_EQ(pcl.attributes.size(), 1u);
  EXPECT_EQ(pcl.attributes[0].name, "curvature");
  // nx ny nz win over normal_x ..; two of three stay attributes.
  const PointCloud both = read_point_cloud(
      write(dir / "both.ply", header({"x", "y", "z", "normal_x", "normal_y", "normal_z", "nx", "ny", "nz"}) +
                                  "0 0 0 1 0 0 0 0 1\n1 0 0 1 0 0 0 0 1\n"));
  ASSERT_EQ(both.normals.size(), 2u);
  EXPECT_EQ(both.normals[0], (Vec3{0, 0, 1}));
  EXPECT_EQ(both.attributes.size(), 1u);  // normal_x .. normal_z: one vector "normal"
  const PointCloud two = read_point_cloud(
      write(dir / "two.ply", header({"x", "y", "z", "normal_x", "normal_z"}) + "0 0 0 1 0\n1 0 0 1 0\n"));
  EXPECT_TRUE(two.normals.empty());
  EXPECT_EQ(two.attributes.size(), 2u);
  // vx vy vz is the velocity (as in a text file); a_x a_y a_z, b.x b.y b.z and c[x] c[y] c[z]
  // are vectors a, b and c; out of order or with a gap they stay apart.
  const PointCloud v = read_point_cloud(write(
      dir / "v.ply", header({"x", "y", "z", "vx", "vy", "vz", "a_x", "a_y", "a_z", "b.x", "b.y", "b.z", "c[x]",
                             "c[y]", "c[z]", "d_y", "d_x", "e_x", "e_z"}) +
                         "0 0 0 1 2 3 4 5 6 7 8 9 10 11 12 13 14 15 16\n"
                         "1 0 0 -1 -2 -3 -4 -5 -6 -7 -8 -9 -10 -11 -12 -13 -14 -15 -16\n"));
  std::vector<std::string> names;
  for (const VertexAttribute& a : v.attributes) names.push_back(a.name);
  EXPECT_EQ(names, (std::vector<std::string>{"velocity", "a", "b", "c", "d_y", "d_x", "e_x", "e_z"}));
  EXPECT_EQ(v.attributes[0].values, (std::vector<float>{1, 2, 3, -1, -2, -3}));
  EXPECT_EQ(v.attributes[3].components, 3);
  EXPECT_EQ(v.attributes[3].values, (std::vector<float>{10, 11, 12, -10, -11, -12}));
}

// OBJ: NaN and values beyond double named with their line (before: "a face refers to a
// vertex that does not exist"); 1e39 is a double like any other; a corner before its vertex
// is named.
// What a triangle mesh does not carry is named, not dropped silently: an OBJ's texture
// coordinates, materials and line elements (and colours on only some vertices), a PLY's face
// properties and other elements, an OFF's colours, VTK cell data. The mesh itself reads as
// before; read for its points, the faces' extras are not named (faces are not read then).
TEST(MeshReaders, WhatATriangleMeshDoesNotCarryIsNamed) {
  const auto dir = test::scratch_dir("mesh_not_read");
  const std::string obj = write(dir / "a.obj", "mtllib a.mtl\nv 0 0 0 1 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt 1 0\n"
                                               "usemtl skin\nf 1/1 2/2 3\nl 1 2\n");
  const TriMesh a = read_mesh(obj);
  EXPECT_EQ(a.triangles.size(), 1u);
  EXPECT_EQ(a.not_read, (std::vector<std::string>{"vertex colours (1 of the 3 vertices have one: a channel needs every vertex's)",
                                                  "texture coordinates (2 vt; 1 face corner names none)", "materials (1 usemtl)",
                                                  "line and point elements (1 l / p)"}));
  EXPECT_EQ(read_point_cloud(obj).not_read,
            std::vector<std::string>{"vertex colours (1 of the 3 vertices have one: a channel needs every vertex's)"});
  const std::string ply = write(dir / "a.ply", "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
                                               "property float z\nelement face 1\nproperty list uchar int vertex_indices\n"
                                               "property uchar red\nelement edge 1\nproperty int vertex1\nproperty int vertex2\n"
                                               "end_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2 255\n0 1\n");
  EXPECT_EQ(read_mesh(ply).not_read, (std::vector<std::string>{"face property 'red'", "element 'edge' (1)"}));
  EXPECT_TRUE(read_point_cloud(ply).not_read.empty());
  const std::string off = write(dir / "a.off", "OFF\n3 1 0\n0 0 0 255 0 0 # red\n1 0 0\n0 1 0 # a comment\n3 0 1 2 0.5 0.5 0.5\n");
  EXPECT_EQ(read_mesh(off).not_read, (std::vector<std::string>{"vertex colours or texture coordinates (the values after x y z)",
                                                               "face colours"}));
  const std::string plain_off = write(dir / "b.off", "OFF\n3 1 0\n0 0 0 # a comment\n1 0 0\n0 1 0\n3 0 1 2 # one\n");
  EXPECT_TRUE(read_mesh(plain_off).not_read.empty());
  const std::string vtk = write(dir / "a.vtk", "# vtk DataFile Version 3.0\nm\nASCII\nDATASET POLYDATA\nPOINTS 3 float\n"
                                               "0 0 0 1 0 0 0 1 0\nPOLYGONS 1 4\n3 0 1 2\nCELL_DATA 1\nSCALARS pressure float 1\n"
                                               "LOOKUP_TABLE default\n7\n");
  EXPECT_EQ(read_mesh(vtk).not_read, std::vector<std::string>{"CELL_DATA SCALARS 'pressure'"});
  EXPECT_TRUE(read_point_cloud(vtk).not_read.empty());
}

// Texture coordinates are values per triangle corner ("uv"), fanned with the polygons; a
// corner without one, or one naming a vt that does not exist, leaves them all unread and
// said (never an error: such files read before). Written back as vt lines, they read the same.
TEST(ObjReader, TextureCoordinatesAreCornerValues) {
  const auto dir = test::scratch_dir("obj_uv");
  const TriMesh quad = read_mesh(write(dir / "quad.obj", "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0 0\nvt 0.5 0\n"
                                                        "vt 0.5 0.25 7\nvt 0 0.25\nvn 0 0 1\nf 1/1/1 2/2/1 3/-2/1 4/4/1\n"));
  ASSERT_EQ(quad.triangles, (std::vector<Triangle>{{0, 1, 2}, {0, 2, 3}}));
  ASSERT_EQ(quad.corner_attributes.size(), 1u);
  EXPECT_EQ(quad.corner_attributes[0].name, "uv");
  EXPECT_EQ(quad.corner_attributes[0].components, 2);
  EXPECT_EQ(quad.corner_attributes[0].values, (std::vector<float>{0, 0, 0.5f, 0, 0.5f, 0.25f, 0, 0, 0.5f, 0.25f, 0, 0.25f}));
  EXPECT_TRUE(quad.not_read.empty());
  // A seam: vertex 2 (index 1) has two texture coordinates, one per face.
  const TriMesh seam = read_mesh(write(dir / "seam.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nvt 0 0\nvt 1 0\n"
                                                        "vt 0 1\nvt 0.9 0.1\nvt 1 1\nvt 0.2 0.8\nf 1/1 2/2 3/3\nf 2/4 4/5 3/6\n"));
  ASSERT_EQ(seam.corner_attributes.size(), 1u);
  EXPECT_EQ(seam.corner_attributes[0].values[2], 1.0f);
  EXPECT_EQ(seam.corner_attributes[0].values[6], 0.9f);
  const std::string written = (dir / "seam_out.obj").string();
  write_mesh(seam, written);
  const TriMesh back = read_mesh(written);
  EXPECT_EQ(back.triangles, seam.triangles);
  ASSERT_EQ(back.corner_attributes.size(), 1u);
  EXPECT_EQ(back.corner_attributes[0].values, seam.corner_attributes[0].values);
  const TriMesh out_of_range = read_mesh(write(dir / "far.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nf 1/1 2/5 3/1\n"));
  EXPECT_EQ(out_of_range.triangles.size(), 1u);
  EXPECT_TRUE(out_of_range.corner_attributes.empty());
  EXPECT_EQ(out_of_range.not_read, std::vector<std::string>{"texture coordinates (1 vt; a face names vt 5 of 1)"});
  EXPECT_TRUE(read_mesh(write(dir / "novt.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1/1 2/2 3/3\n")).corner_attributes.empty());
  EXPECT_REFUSED(read_mesh(write(dir / "badvt.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 x\nf 1/1 2/1 3/1\n")),
                 Status::FormatError, "line 4: texture v 'x' is not a number");
  EXPECT_REFUSED(read_mesh(write(dir / "hugevt.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 -1e39\nf 1/1 2/1 3/1\n")),
                 Status::FormatError, "line 4: texture coordinate '-1e39' is beyond the range of float");
  // Read for points, texture coordinates are neither read nor named.
  EXPECT_TRUE(read_point_cloud((dir / "quad.obj").string()).not_read.empty());
}

// MeshLab's texcoord face lists (u v per corner) are the same corner attribute "uv": fanned
// with the face, written back by both PLY encodings, named when a list does not fit.
TEST(PlyReader, TexcoordListsAreCornerValues) {
  const auto dir = test::scratch_dir("ply_uv");
  const std::string header = "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\n"
                             "property float z\nelement face 1\nproperty list uchar int vertex_indices\n"
                             "property list uchar float texcoord\nend_header\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n";
  const TriMesh quad = read_mesh(write(dir / "quad.ply", header + "4 0 1 2 3 8 0 0 0.5 0 0.5 0.25 0 0.25\n"));
  ASSERT_EQ(quad.triangles, (std::vector<Triangle>{{0, 1, 2}, {0, 2, 3}}));
  ASSERT_EQ(quad.corner_attributes.size(), 1u);
  EXPECT_EQ(quad.corner_attributes[0].values, (std::vector<float>{0, 0, 0.5f, 0, 0.5f, 0.25f, 0, 0, 0.5f, 0.25f, 0, 0.25f}));
  EXPECT_TRUE(quad.not_read.empty());
  for (const MeshFormat format : {MeshFormat::PlyBinary, MeshFormat::PlyAscii}) {
    const std::string out = (dir / "back.ply").string();
    WriteMeshOptions o;
    o.format = format;
    write_mesh(quad, out, o);
    const TriMesh back = read_mesh(out);
    EXPECT_EQ(back.triangles, quad.triangles);
    ASSERT_EQ(back.corner_attributes.size(), 1u);
    EXPECT_EQ(back.corner_attributes[0].values, quad.corner_attributes[0].values);
  }
  const TriMesh short_list = read_mesh(write(dir / "short.ply", header + "4 0 1 2 3 6 0 0 0.5 0 0.5 0.25\n"));
  EXPECT_EQ(short_list.triangles.size(), 2u);
  EXPECT_TRUE(short_list.corner_attributes.empty());
  EXPECT_EQ(short_list.not_read,
            std::vector<std::string>{"face property 'texcoord' (1 faces' lists do not hold a u and a v for each corner)"});
  EXPECT_TRUE(read_point_cloud(write(dir / "points.ply", header + "4 0 1 2 3 8 0 0 0.5 0 0.5 0.25 0 0.25\n")).not_read.empty());
}

TEST(ObjReader, ValuesAndCornersNamedWithTheirLine) {
  const auto dir = test::scratch_dir("obj");
  EXPECT_REFUSED(read_mesh(write(dir / "nan.obj", "v 0 0 0\nv 1 nan 0\nv 0 1 0\nf 1 2 3\n")), Status::FormatError,
                 "nan.obj': line 2: vertex y is NaN");
  EXPECT_REFUSED(read_mesh(write(dir / "inf.obj", "v 0 0 0\nv 1e400 0 0\nv 0 1 0\nf 1 2 3\n")), Status::FormatError,
                 "line 2: vertex x '1e400' is beyond the range of double");
  const TriMesh big = read_mesh(write(dir / "big.obj", "v 0 0 0\nv 1e39 0 0\nv 0 1e39 0\nf 1 2 3\n"));
  ASSERT_EQ(big.triangles.size(), 1u);
  EXPECT_EQ(big.positions[1].x, 1e39);
  EXPECT_REFUSED(read_mesh(write(dir / "fwd.obj", "v 0 0 0\nv 1 0 0\nf 1 2 3\nv 0 1 0\n")), Status::FormatError,
                 "line 3: face corner '3' names vertex 3, but only 2 are defined so far");
  EXPECT_REFUSED(read_mesh(write(dir / "two.obj", "v 0 0 0\nv 1 0 0\nf 1 2\n")), Status::FormatError,
                 "line 3: a face with 2 corners");
  // v x y z r g b: colours.
  const TriMesh col = read_mesh(write(dir / "col.obj", "v 0 0 0 1 0 0\nv 1 0 0 0 1 0\nv 0 1 0 0 0 1\nf 1 2 3\n"));
  ASSERT_EQ(col.attributes.size(), 1u);
  EXPECT_EQ(col.attributes[0].values[4], 1.0f);
  // A backslash ending a line continues the statement (a face wrapped over three lines, a
  // vertex over two, a comment in between), also on the file's last line.
  const TriMesh wrapped = read_mesh(write(dir / "wrapped.obj", "v 0 0 0\nv 1 \\\n 0 0\nv 1 1 0\nv 0 1 0\n"
                                                              "f 1 2 \\ # half\n 3 \\\r\n 4\nf 1 3 \\\n 4"));
  ASSERT_EQ(wrapped.positions.size(), 4u);
  EXPECT_EQ(wrapped.positions[1], (Vec3{1, 0, 0}));
  ASSERT_EQ(wrapped.triangles.size(), 3u);  // the quad fanned, then the last triangle
  EXPECT_EQ(wrapped.triangles[1], (Triangle{0, 2, 3}));
  EXPECT_EQ(wrapped.triangles[2], (Triangle{0, 2, 3}));
  EXPECT_REFUSED(read_mesh(write(dir / "wrapbad.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 \\\n 9\n")),
                 Status::FormatError, "line 5: face corner '9' names vertex 9");
  // Negative texture indices, -1 too (the last 'vt'; trimesh's negative_indices.obj).
  const TriMesh neg = read_mesh(write(dir / "neg.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 0 1\n"
                                                      "vn 0 0 1\nf -3/-3/-1 -2/-2/-1 -1/-1/-1\n"));
  ASSERT_EQ(neg.triangles.size(), 1u);
  EXPECT_EQ(neg.triangles[0], (Triangle{0, 1, 2}));
  // Normal indices in a file with no 'vn' (placeholders) are ignored; with some normals, an
  // index beyond them is still refused.
  const TriMesh placeholders = read_mesh(write(dir / "novn.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1//1 2//1 3//-1\n"));
  ASSERT_EQ(placeholders.triangles.size(), 1u);
  EXPECT_REFUSED(read_mesh(write(dir / "badvn.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 1\nf 1//1 2//1 3//2\n")),
                 Status::FormatError, "face corner '3//2' names normal 2, but only 1 are defined so far");
  // A UTF-8 byte order mark is skipped; UTF-16 is named (before: an empty mesh, no error).
  EXPECT_EQ(read_mesh(write(dir / "bom.obj", "\xEF\xBB\xBFv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n")).triangles.size(), 1u);
  std::string utf16 = "\xFF\xFE";
  for (char ch : std::string("v 0 0 0\n")) utf16 += std::string{ch, '\0'};
  EXPECT_REFUSED(read_mesh(write(dir / "utf16.obj", utf16)), Status::FormatError,
                 "the file is UTF-16 text (it starts with the byte order mark FF FE)");
  EXPECT_REFUSED(read_mesh(write(dir / "badvt.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1/x 2/1 3/1\n")),
                 Status::FormatError, "face corner '1/x' is not v, v/vt, v//vn or v/vt/vn");
}

// Legacy VTK as VTK's own sample data writes it: a cell list's first values on the line of its
// counts ("LINES 1 348 347 ..."), a blank line before ASCII; read as vtkDataReader reads them.
TEST(VtkLegacyReader, ValuesOnTheHeaderLineAndABlankLineBeforeAscii) {
  const auto dir = test::scratch_dir("vtk_legacy");
  const std::string points = "POINTS 4 float\n0 0 0 1 0 0 1 1 0 0 1 0\n";
  const TriMesh m = read_mesh(write(dir / "same_line.vtk", "# vtk DataFile Version 2.0\nsample\n\nASCII\n"
                                                          "DATASET POLYDATA\n" + points +
                                                          "POLYGONS 2 8 3 0 1 2\n3 0 2 3\nLINES 1 3 2\n0 1\n"));
  ASSERT_EQ(m.triangles.size(), 2u);
  EXPECT_EQ(m.triangles[0], (Triangle{0, 1, 2}));
  EXPECT_EQ(m.triangles[1], (Triangle{0, 2, 3}));
  EXPECT_REFUSED(read_mesh(write(dir / "short.vtk", "# vtk DataFile Version 2.0\nsample\nASCII\nDATASET POLYDATA\n" +
                                                        points + "POLYGONS 1 4 3 0 1\n")),
                 Status::FormatError, "POLYGONS");
  EXPECT_REFUSED(read_mesh(write(dir / "mode.vtk", "# vtk DataFile Version 2.0\nsample\n\nTEXT\n")),
                 Status::FormatError, "the line after the title is 'TEXT', not ASCII or BINARY");
  // A structured grid's points are particles (its cells are implied); a lattice given by its
  // axes alone is refused by name.
  const PointCloud grid = read_point_cloud(write(dir / "grid.vtk", "# vtk DataFile Version 2.0\ng\nASCII\n"
                                                                   "DATASET STRUCTURED_GRID\nDIMENSIONS 2 2 1\n" + points +
                                                                   "POINT_DATA 4\nSCALARS t float 1\nLOOKUP_TABLE default\n"
                                                                   "1 2 3 4\n"));
  ASSERT_EQ(grid.size(), 4u);
  EXPECT_EQ(grid.positions[2], (Vec3{1, 1, 0}));
  ASSERT_EQ(grid.attributes.size(), 1u);
  EXPECT_EQ(grid.attributes[0].values[3], 4.0f);
  EXPECT_REFUSED(read_point_cloud(write(dir / "image.vtk", "# vtk DataFile Version 2.0\ni\nASCII\n"
                                                            "DATASET STRUCTURED_POINTS\nDIMENSIONS 2 2 2\n")),
                 Status::FormatError, "DATASET STRUCTURED_POINTS lists no points");
}

// .xyz: a UTF-8 byte order mark is skipped (before: "not a number"); a line that never ends
// is refused after 64 KiB (before: read whole: /dev/zero grew to 10 GB); values beyond
// double are named.
TEST(XyzReader, ByteOrderMarkLongLinesAndOverflow) {
  const auto dir = test::scratch_dir("xyz");
  const PointCloud c = read_point_cloud(write(dir / "bom.xyz", "\xEF\xBB\xBF" "1 2 3\n4 5 6\n"));
  ASSERT_EQ(c.size(), 2u);
  EXPECT_EQ(c.positions[0], (Vec3{1, 2, 3}));
  EXPECT_REFUSED(read_point_cloud(write(dir / "long.xyz", std::string(200000, '0'))), Status::FormatError,
                 "long.xyz': line 1 is longer than 65536 bytes");
  EXPECT_REFUSED(read_point_cloud(write(dir / "inf.xyz", "0 0 0\n1e999 0 0\n")), Status::FormatError,
                 "inf.xyz' line 2: '1e999' is beyond the range of double");
  // /dev/zero behind a name: refused at once, in bounded memory.
  fs::create_symlink("/dev/zero", dir / "zero.xyz");
  EXPECT_REFUSED(read_point_cloud((dir / "zero.xyz").string()), Status::FormatError, "line 1 is longer than 65536 bytes");
}

// Text that would be misread as numbers is refused by name: UTF-16 (PowerShell's ">" and
// Notepad's "Unicode" write it) and decimal commas (spreadsheets in many locales write
// "0,0114;-0,0294"; split at the commas, each line became six values, read as a point and a
// "normal"). Commas that separate values, with or without spaces, still read.
TEST(XyzReader, Utf16AndDecimalCommasAreRefusedByName) {
  const auto dir = test::scratch_dir("xyz_text");
  std::string utf16 = "\xFF\xFE";
  for (char ch : std::string("1 2 3\n4 5 6\n")) utf16 += std::string{ch, '\0'};
  EXPECT_REFUSED(read_point_cloud(write(dir / "le.xyz", utf16)), Status::FormatError,
                 "le.xyz': the file is UTF-16 text (it starts with the byte order mark FF FE): save it as UTF-8");
  EXPECT_REFUSED(read_point_cloud(write(dir / "be.xyz", "\xFE\xFF" + utf16.substr(3))), Status::FormatError,
                 "byte order mark FE FF");
  EXPECT_REFUSED(read_point_cloud(write(dir / "nobom.xyz", utf16.substr(2))), Status::FormatError,
                 "nobom.xyz' line 1: NUL bytes: UTF-16 text");
  // Classic Mac OS line ends: one line of every value ("more than 64 values", or longer than
  // 64 KiB) before.
  std::string mac;
  for (int i = 0; i < 10000; ++i) mac += std::to_string(i) + " 0 0\r";
  for (const size_t size : {size_t(60), mac.size()})
    EXPECT_REFUSED(read_point_cloud(write(dir / "mac.xyz", mac.substr(0, size))), Status::FormatError,
                   "mac.xyz': its lines end with CR alone (classic Mac OS text)");
  EXPECT_EQ(read_point_cloud(write(dir / "crlf.xyz", "1 2 3\r\n4 5 6\r\n")).size(), 2u);
  for (const char* sep : {";", "\t", " ", "; "}) {
    SCOPED_TRACE(sep);
    EXPECT_REFUSED(read_point_cloud(write(dir / "comma.xyz", std::string("0,0114") + sep + "-0,0294" + sep + "0,9995\n")),
                   Status::FormatError, "comma.xyz' line 1: '0,0114' is a number with a decimal comma");
  }
  EXPECT_REFUSED(read_point_cloud(write(dir / "later.xyz", "1;2;3\n4;5;6,5\n")), Status::FormatError,
                 "later.xyz' line 2: '6,5' is a number with a decimal comma");
  // Comma-separated values (with spaces or not, an integer pair, a header) read as before.
  for (const char* text : {"1,2,3\n4,5,6\n", "1, 2, 3\n4, 5, 6\n", "1, 2,3\n4, 5,6\n", "1.0,2 ,3\n4.0,5 ,6\n",
                           "//X,Y,Z\n1,2,3\n4,5,6\n"}) {
    const PointCloud c = read_point_cloud(write(dir / "csv.xyz", text));
    ASSERT_EQ(c.size(), 2u) << text;
    EXPECT_EQ(c.positions[1], (Vec3{4, 5, 6})) << text;
    EXPECT_TRUE(c.normals.empty()) << text;
  }
}

// Text point files' columns: named by a header line (CloudCompare's "//X,Y,Z,R,G,B", PDAL's
// quoted names, any case), or told by their count and values (scanners' and CloudCompare's
// conventions): colours are never taken for normals, nothing is dropped.
TEST(XyzReader, ColumnsNamedByAHeaderOrToldByTheirValues) {
  const auto dir = test::scratch_dir("xyz_columns");
  auto read = [&](const std::string& name, const std::string& text) { return read_point_cloud(write(dir / name, text)); };
  auto expect_colours = [&](const PointCloud& c) {
    const VertexAttribute* col = attribute(c, "color");
    ASSERT_NE(col, nullptr);
    ASSERT_EQ(col->components, 3);
    EXPECT_EQ(col->values, (std::vector<float>{1, 0, 0, 0, 1, 0, 0, 0, 1}));
  };
  const std::string xyz[3] = {"0 0 0", "1 0 0", "0 1 0"};
  auto rows = [&](const std::string& a, const std::string& b, const std::string& c) {
    return xyz[0] + " " + a + "\n" + xyz[1] + " " + b + "\n" + xyz[2] + " " + c + "\n";
  };

  // A header: columns in any order and case, colours 0-255, a channel; normals need all three.
  PointCloud h = read("h.xyz", "//Intensity,Z,Y,X,R,G,B,nz\n5,0,0,0,255,0,0,1\n6,0,0,1,0,255,0,1\n7,0,1,0,0,0,255,1\n");
  EXPECT_EQ(h.positions[1], (Vec3{1, 0, 0}));
  EXPECT_EQ(h.positions[2], (Vec3{0, 1, 0}));
  EXPECT_TRUE(h.normals.empty());
  expect_colours(h);
  ASSERT_NE(attribute(h, "Intensity"), nullptr);
  EXPECT_EQ(attribute(h, "Intensity")->values, (std::vector<float>{5, 6, 7}));
  ASSERT_NE(attribute(h, "nz"), nullptr);  // a lone normal component stays a channel
  const PointCloud pdal = read("pdal.xyz", "\"X\",\"Y\",\"Z\",\"NormalX\",\"NormalY\",\"NormalZ\"\n" + rows("0,0,1", "0,0,1", "1,0,0"));
  ASSERT_EQ(pdal.normals.size(), 3u);
  EXPECT_EQ(pdal.normals[2], (Vec3{1, 0, 0}));
  EXPECT_REFUSED(read("noz.xyz", "x y w\n0 0 0\n"), Status::FormatError, "noz.xyz': its first line ('x y w') starts with a word, so it is read as a header line naming the columns, but it names no 'z' column (nor the positions as a vector");
  EXPECT_REFUSED(read("short.xyz", "x y z r g b\n0 0 0 1 1\n"), Status::FormatError,
                 "short.xyz' line 2: 5 values where the header names 6");

  // No header: 6 columns are normals unless plainly colours (whole numbers up to 255, or
  // values in [0, 1] that are not unit vectors); normals of any length stay normals.
  expect_colours(read("rgb.xyz", rows("255 0 0", "0 255 0", "0 0 255")));
  const PointCloud rgbf = read("rgbf.xyz", rows("0.5 0.5 0.5", "0.1 0.2 0.3", "1 1 1"));
  EXPECT_TRUE(rgbf.normals.empty());
  ASSERT_NE(attribute(rgbf, "color"), nullptr);
  EXPECT_EQ(attribute(rgbf, "color")->values[5], 0.3f);
  const PointCloud n6 = read("n.xyz", rows("0 0 1", "1 0 0", "0.6 0 0.8"));
  ASSERT_EQ(n6.normals.size(), 3u);
  EXPECT_TRUE(n6.attributes.empty());
  EXPECT_EQ(read("long_normals.xyz", rows("-3 2 1", "0.5 0 0", "0 0 0")).normals.size(), 3u);
  // 4: intensity; 7: x y z r g b intensity (.xyz) or x y z intensity r g b (.pts, with its
  // count lines); 9: colour and normals either way round.
  EXPECT_EQ(attribute(read("i.xyz", rows("10", "20", "30")), "intensity")->values, (std::vector<float>{10, 20, 30}));
  const PointCloud x7 = read("c7.xyz", rows("255 0 0 9", "0 255 0 8", "0 0 255 7"));
  expect_colours(x7);
  EXPECT_EQ(attribute(x7, "intensity")->values, (std::vector<float>{9, 8, 7}));
  const PointCloud p7 = read("scan.pts", "2\n" + xyz[0] + " -100 255 0 0\n" + xyz[1] + " 200 0 255 0\n1\n" + xyz[2] +
                                             " 300 0 0 255\n");
  ASSERT_EQ(p7.size(), 3u);
  expect_colours(p7);
  EXPECT_EQ(attribute(p7, "intensity")->values, (std::vector<float>{-100, 200, 300}));
  for (const auto& [name, a, b, c] : {std::tuple{"c9.xyz", "255 0 0 0 0 1", "0 255 0 0 0 1", "0 0 255 1 0 0"},
                                      std::tuple{"n9.xyz", "0 0 1 255 0 0", "0 0 1 0 255 0", "1 0 0 0 0 255"}}) {
    const PointCloud c9 = read(name, rows(a, b, c));
    ASSERT_EQ(c9.normals.size(), 3u) << name;
    EXPECT_EQ(c9.normals[2], (Vec3{1, 0, 0})) << name;
    expect_colours(c9);
  }
  // Any other count, and 7 or 9 columns that fit neither order: channels column_4, ...
  const PointCloud five = read("five.xyz", rows("1 2", "3 4", "5 6"));
  EXPECT_TRUE(five.normals.empty());
  ASSERT_EQ(five.attributes.size(), 2u);
  EXPECT_EQ(five.attributes[1].name, "column_5");
  EXPECT_EQ(five.attributes[1].values, (std::vector<float>{2, 4, 6}));
  EXPECT_EQ(read("seven.xyz", rows("1 2 3 4", "5 6 7 8", "9 10 -11 12")).attributes.size(), 4u);
  EXPECT_REFUSED(read("two.xyz", "0 0\n"), Status::FormatError, "two.xyz' line 1: 2 values, expected at least 3");
  EXPECT_REFUSED(read("ragged.xyz", "0 0 0\n1 0 0 1\n"), Status::FormatError, "line 2: 4 values where earlier lines have 3");
}

// CSV and .txt text files, and header lines naming vectors: ParaView's CSV export (quoted
// names, "Name:k" components, the positions last, a name with a space), pandas' to_csv (an
// unnamed index column), DualSPHysics' "Pos.x;Pos.y;Pos.z", our PLY naming "name_k". A vector
// of 3 is the positions, the normals, the colour or the velocity by its name; any other keeps
// its name and components; runs that are not 0, 1, 2, ... stay single channels.
// A column of words (a label, a material) is not read and is named, the rest of the file read
// (it refused the whole file); a word in a column of numbers, or in x, is still an error.
TEST(XyzReader, TextColumnsAreNamedNotRead) {
  const auto dir = test::scratch_dir("xyz_text");
  const PointCloud c = read_point_cloud(write(dir / "a.csv", "id,type,vx,vy,vz,x,y,z\n1,water,1,2,3,0,0,0\n"
                                                              "2,foam,4,5,6,1,0,0\n3,water,7,8,9,0,1,0\n"));
  ASSERT_EQ(c.size(), 3u);
  EXPECT_EQ(c.positions[1], (Vec3{1, 0, 0}));
  ASSERT_EQ(c.attributes.size(), 2u);
  EXPECT_EQ(c.attributes[0].name, "id");
  EXPECT_EQ(c.attributes[1].name, "velocity");
  EXPECT_EQ(c.attributes[1].values, (std::vector<float>{1, 2, 3, 4, 5, 6, 7, 8, 9}));
  EXPECT_EQ(c.not_read, std::vector<std::string>{"column 'type' (text)"});
  EXPECT_REFUSED(read_point_cloud(write(dir / "b.csv", "x,y,z,mass\n0,0,0,1\n1,0,0,heavy\n")), Status::FormatError,
                 "b.csv' line 3: not a number: 'heavy'");
  EXPECT_REFUSED(read_point_cloud(write(dir / "c.csv", "x,y,z\nnorth,0,0\n")), Status::FormatError,
                 "c.csv' line 2: the column 'x' holds 'north', not a coordinate");
  EXPECT_REFUSED(read_point_cloud(write(dir / "d.xyz", "0 0 0\n1 0 zero\n")), Status::FormatError,
                 "not a number: 'zero'");  // without a header every column is a number
}

TEST(XyzReader, CsvHeadersNameVectorsAsParaViewAndPandasWriteThem) {
  const auto dir = test::scratch_dir("xyz_csv");
  auto read = [&](const std::string& name, const std::string& text) { return read_point_cloud(write(dir / name, text)); };
  const std::vector<Vec3> expected = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};

  const PointCloud pv = read("paraview.csv",
                             "\"Density\",\"Velocity:0\",\"Velocity:1\",\"Velocity:2\",\"Point ID\",\"Points:0\",\"Points:1\","
                             "\"Points:2\"\r\n1000,1,2,3,0,0,0,0\r\n1001,4,5,6,1,1,0,0\r\n1002,7,8,9,2,0,1,0\r\n");
  EXPECT_EQ(pv.positions, expected);
  ASSERT_EQ(pv.attributes.size(), 3u);
  EXPECT_EQ(pv.attributes[0].name, "Density");
  EXPECT_EQ(pv.attributes[1].name, "velocity");
  EXPECT_EQ(pv.attributes[1].components, 3);
  EXPECT_EQ(pv.attributes[1].values, (std::vector<float>{1, 2, 3, 4, 5, 6, 7, 8, 9}));
  ASSERT_NE(attribute(pv, "Point ID"), nullptr);
  EXPECT_EQ(attribute(pv, "Point ID")->values, (std::vector<float>{0, 1, 2}));

  // pandas: ",x,y,z,vx,vy,vz" with the index first; newer ParaView: "Points_0".
  const PointCloud pd = read("pandas.csv", ",x,y,z,vx,vy,vz\n0,0,0,0,1,1,1\n1,1,0,0,2,2,2\n2,0,1,0,3,3,3\n");
  EXPECT_EQ(pd.positions, expected);
  ASSERT_NE(attribute(pd, "column_1"), nullptr);
  EXPECT_EQ(attribute(pd, "column_1")->values, (std::vector<float>{0, 1, 2}));
  ASSERT_NE(attribute(pd, "velocity"), nullptr);
  EXPECT_EQ(attribute(pd, "velocity")->values, (std::vector<float>{1, 1, 1, 2, 2, 2, 3, 3, 3}));
  const PointCloud underscore = read("pv510.txt", "Points_0\tPoints_1\tPoints_2\tNormals_0\tNormals_1\tNormals_2\tforce_0\tforce_1\n"
                                                  "0\t0\t0\t0\t0\t1\t5\t6\n1\t0\t0\t0\t0\t1\t5\t6\n0\t1\t0\t1\t0\t0\t5\t6\n");
  EXPECT_EQ(underscore.positions, expected);
  ASSERT_EQ(underscore.normals.size(), 3u);
  EXPECT_EQ(underscore.normals[2], (Vec3{1, 0, 0}));
  ASSERT_NE(attribute(underscore, "force"), nullptr);
  EXPECT_EQ(attribute(underscore, "force")->components, 2);

  // DualSPHysics: semicolons, "Pos.x" and "Vel.x", units after the names; a colour vector
  // scaled as r g b columns.
  const PointCloud ds = read("dsph.csv", "Pos.x [m];Pos.y [m];Pos.z [m];Idp;Vel.x [m/s];Vel.y (m/s);Vel.z;Color_x;Color_y;Color_z;\n"
                                         "0;0;0;7;0;0;-1;255;0;0\n1;0;0;8;0;0;-2;0;255;0\n0;1;0;9;0;0;-3;0;0;255\n");
  EXPECT_EQ(ds.positions, expected);
  EXPECT_EQ(attribute(ds, "Idp")->values, (std::vector<float>{7, 8, 9}));
  EXPECT_EQ(attribute(ds, "velocity")->values, (std::vector<float>{0, 0, -1, 0, 0, -2, 0, 0, -3}));
  EXPECT_EQ(attribute(ds, "color")->values, (std::vector<float>{1, 0, 0, 0, 1, 0, 0, 0, 1}));

  // Houdini's table export: "P[x]", "v[0]"; the bracketed component is no unit.
  const PointCloud hou = read("houdini.csv", "P[x],P[y],P[z],v[0],v[1],v[2],Cd[r],Cd[g],Cd[b],w[r]\n"
                                             "0,0,0,1,2,3,1,0,0,5\n1,0,0,1,2,3,0,1,0,5\n0,1,0,1,2,3,0,0,1,5\n");
  EXPECT_EQ(hou.positions, expected);
  ASSERT_NE(attribute(hou, "velocity"), nullptr);
  EXPECT_EQ(attribute(hou, "velocity")->values, (std::vector<float>{1, 2, 3, 1, 2, 3, 1, 2, 3}));
  ASSERT_NE(attribute(hou, "color"), nullptr);
  EXPECT_EQ(attribute(hou, "color")->values, (std::vector<float>{1, 0, 0, 0, 1, 0, 0, 0, 1}));
  EXPECT_NE(attribute(hou, "w[r]"), nullptr);  // one component alone stays a channel
  // x y z columns win over a vector named as positions; components out of order, or one
  // alone, stay single channels; a trailing delimiter adds no column.
  const PointCloud both = read("both.csv", "x,y,z,P_0,P_1,P_2,a:1,a:0,b_0,\n0,0,0,9,9,9,1,2,3,\n1,0,0,9,9,9,1,2,3,\n0,1,0,9,9,9,1,2,3,\n");
  EXPECT_EQ(both.positions, expected);
  ASSERT_NE(attribute(both, "P"), nullptr);
  EXPECT_EQ(attribute(both, "P")->components, 3);
  for (const char* single : {"a:1", "a:0", "b_0"}) EXPECT_NE(attribute(both, single), nullptr) << single;
  // splashsurf's binary .xyz: x y z as little-endian float32 (this machine's order), told
  // from text by its bytes; not a whole number of particles: refused by name. Only .xyz.
  std::string bin;
  for (const Vec3& q : expected)
    for (double x : {q.x, q.y, q.z}) {
      const float f = float(x) + 0.5f;
      bin.append(reinterpret_cast<const char*>(&f), 4);
    }
  const PointCloud b = read("splashsurf.xyz", bin);
  ASSERT_EQ(b.size(), 3u);
  EXPECT_EQ(b.positions[2], (Vec3{0.5, 1.5, 0.5}));
  EXPECT_TRUE(b.attributes.empty() && b.normals.empty());
  EXPECT_REFUSED(read("cut.xyz", bin.substr(0, 31)), Status::FormatError,
                 "cut.xyz': binary (not text), 31 bytes: read as splashsurf's binary .xyz");
  EXPECT_REFUSED(read("binary.csv", bin), Status::FormatError, "binary.csv' line 1: ");
  // Tab-aligned columns: a run of tabs is one separator, in the header as in the data.
  EXPECT_EQ(read("aligned.txt", "x\t\ty\t\tz\n0\t\t0\t\t0\n1\t\t0\t\t0\n0\t\t1\t\t0\n").positions, expected);
  // Headerless .txt and .csv read as .xyz does.
  EXPECT_EQ(read("plain.txt", "0 0 0\n1 0 0\n0 1 0\n").positions, expected);
  EXPECT_EQ(read("plain.csv", "0,0,0\n1,0,0\n0,1,0\n").positions, expected);
  // No positions: the error says what was looked for.
  EXPECT_REFUSED(read("nopos.csv", "\"Velocity:0\",\"Velocity:1\",\"Velocity:2\"\n1,2,3\n"), Status::FormatError,
                 "names no 'x' column (nor the positions as a vector, Points:0 Points:1 Points:2)");
  EXPECT_REFUSED(read("short.csv", "\"Point ID\",x,y,z\n1,2,3\n"), Status::FormatError,
                 "short.csv' line 2: 3 values where the header names 4");
}

// Whatever the format, a 3-component channel named v, vel or velocity (any case) is the
// channel "velocity" (Blender's motion blur, --attributes velocity), unless one is so named.
TEST(FileReaders, TheVelocityIsNamedAsBlenderReadsItInEveryFormat) {
  const auto dir = test::scratch_dir("velocity_names");
  TriMesh c;  // the writers of .vtk and .vtu write meshes; a triangle's corners are the points
  c.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  c.triangles = {{0, 1, 2}};
  const std::vector<float> v = {1, 2, 3, 4, 5, 6, 7, 8, 9};
  for (const char* ext : {".vtk", ".vtu", ".ply"})
    for (const char* name : {"Vel", "V", "VELOCITY"}) {
      c.attributes = {{"density", 1, {1, 2, 3}}, {name, 3, v}};
      const std::string path = (dir / (std::string(name) + ext)).string();
      write_mesh(c, path);
      const PointCloud back = read_point_cloud(path);
      ASSERT_EQ(back.attributes.size(), 2u) << path;
      EXPECT_EQ(back.attributes[1].name, "velocity") << path;
      EXPECT_EQ(back.attributes[1].values, v) << path;
    }
  // Two candidates: the first; one already called velocity: the others keep their names; a
  // "v" of 2 components is no velocity.
  c.attributes = {{"vel", 3, v}, {"V", 3, v}, {"v2", 2, {0, 0, 0, 0, 0, 0}}};
  write_mesh(c, (dir / "two.vtk").string());
  PointCloud back = read_point_cloud((dir / "two.vtk").string());
  EXPECT_EQ(back.attributes[0].name, "velocity");
  EXPECT_EQ(back.attributes[1].name, "V");
  c.attributes = {{"V", 3, v}, {"velocity", 1, {1, 2, 3}}, {"v", 2, {0, 0, 0, 0, 0, 0}}};
  write_mesh(c, (dir / "named.vtu").string());
  back = read_point_cloud((dir / "named.vtu").string());
  EXPECT_EQ(back.attributes[0].name, "V");
  EXPECT_EQ(back.attributes[2].name, "v");
}

// Each file is read exactly once, front to back: a FIFO (readable once) reads like a file.
// Before, a header pass read the file and then OpenMesh read it again (and found nothing).
TEST(FileReaders, EachFileIsReadOnceFrontToBack) {
  const auto dir = test::scratch_dir("fifo");
  const TriMesh ico = icosphere_mesh(2);
  write_mesh(ico, (dir / "ico.ply").string());
  write_mesh(ico, (dir / "ico.obj").string());
  for (const char* ext : {".ply", ".obj"}) {
    SCOPED_TRACE(ext);
    std::ifstream in(dir / (std::string("ico") + ext), std::ios::binary);
    const std::string bytes((std::istreambuf_iterator<char>(in)), {});
    TriMesh m;
    std::string msg;
    EXPECT_EQ(read_through_fifo(dir / (std::string("pipe") + ext), bytes, [&](const std::string& f) { m = read_mesh(f); }, msg),
              Status::Ok) << msg;
    EXPECT_EQ(m.triangles, ico.triangles);
  }
}

// STL: corners with equal coordinates become one vertex (topology needs shared vertices),
// ASCII (with or without solid names, several solids) and binary alike; coordinates exact.
TEST(StlReader, AsciiAndBinaryShareVertices) {
  const auto dir = test::scratch_dir("stl");
  auto facet = [](const char* a, const char* b, const char* c) {
    return std::string("facet normal 0 0 1\n outer loop\n  vertex ") + a + "\n  vertex " + b + "\n  vertex " + c +
           "\n endloop\nendfacet\n";
  };
  const std::string text = "solid\n" + facet("0 0 0", "1 0 0", "0 1 0") + facet("1 0 0", "1 1 0", "0 1 0") +
                           "endsolid\nsolid second\n" + facet("0 0 0", "0 1 0", "0 0 0.10000000000000001") +
                           "endsolid second\n";
  const TriMesh a = read_mesh(write(dir / "a.stl", text));
  EXPECT_EQ(a.positions.size(), 5u);
  EXPECT_EQ(a.triangles, (std::vector<Triangle>{{0, 1, 2}, {1, 3, 2}, {0, 2, 4}}));
  EXPECT_EQ(a.positions[4].z, 0.1);
  EXPECT_EQ(topology_report(a).components, 1u);
  std::string b(80, ' ');
  append(b, uint32_t(2));
  const float tris[2][12] = {{0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 0}, {0, 0, 1, 1, 0, 0, 1, 1, 0, 0, 1, 0}};
  for (const auto& t : tris) {
    for (float v : t) append(b, v);
    append(b, uint16_t(0));
  }
  const TriMesh m = read_mesh(write(dir / "b.stl", b));
  EXPECT_EQ(m.positions.size(), 4u);
  EXPECT_EQ(m.triangles, (std::vector<Triangle>{{0, 1, 2}, {1, 3, 2}}));
  EXPECT_REFUSED(read_mesh(write(dir / "more.stl", b + "xx")), Status::FormatError, "binary STL with more data");
}

namespace {

/// Houdini's binary JSON, little-endian, for the bgeo cases below.
struct BinaryJson {
  std::string s = "\x7fNSJb";
  BinaryJson& raw(std::initializer_list<int> bytes) {
    for (int b : bytes) s += char(b);
    return *this;
  }
  BinaryJson& str(const std::string& t) {
    s += char(0x27);
    s += char(t.size());
    s += t;
    return *this;
  }
  BinaryJson& i32(int32_t v) {
    s += char(0x13);
    append(s, v);
    return *this;
  }
  /// The points' P as "tuples" of uniform arrays of `type` (0x19 real32, 0x18 real16, 0x11 int8...).
  BinaryJson& geometry(const std::string& tuples, int points) {
    raw({'['}).str("pointcount").i32(points).str("attributes").raw({'['}).str("pointattributes").raw({'[', '['});
    raw({'['}).str("name").str("P").str("type").str("numeric").raw({']'});
    raw({'['}).str("values").raw({'['}).str("size").i32(3).str("tuples").raw({'['});
    s += tuples;
    return raw({']', ']', ']', ']', ']', ']', ']'});
  }
};

}  // namespace

// Houdini 12+'s binary-JSON bgeo (bgeo_json.cpp): every numeric type a uniform array may hold
// read exactly; a map where the schema has key/value lists; what it refuses, by name.
TEST(BgeoJsonReader, TypesLimitsAndRefusals) {
  const auto dir = test::scratch_dir("bgeo_json");
  // Three points: real32, real16 (1.5 = 0x3e00, -2 = 0xc000, 0.25 = 0x3400), int8.
  std::string t;
  t += std::string("\x40\x19\x03", 3);
  for (float f : {1.0f, 2.0f, 3.0f}) append(t, f);
  t += std::string("\x40\x18\x03", 3);
  for (uint16_t h : {uint16_t(0x3e00), uint16_t(0xc000), uint16_t(0x3400)}) append(t, h);
  t += std::string("\x40\x11\x03\x05\xfb\x00", 6);
  const PointCloud c = read_point_cloud(write(dir / "types.bgeo", BinaryJson().geometry(t, 3).s));
  ASSERT_EQ(c.positions.size(), 3u);
  EXPECT_EQ(c.positions[0], (Vec3{1, 2, 3}));
  EXPECT_EQ(c.positions[1], (Vec3{1.5, -2, 0.25}));
  EXPECT_EQ(c.positions[2], (Vec3{5, -5, 0}));

  // The root as a map ({...}) rather than a key/value list.
  std::string m = "\x7fNSJb{";
  m += std::string("\x27\x0apointcount", 12) + "\x13";
  append(m, int32_t(1));
  m += std::string("\x27\x0a" "attributes", 12) + "[" + std::string("\x27\x0fpointattributes", 17) + "[[";
  m += BinaryJson().raw({'['}).str("name").str("P").str("type").str("numeric").raw({']', '['}).str("values").s.substr(5);
  m += BinaryJson().raw({'['}).str("size").i32(3).str("arrays").raw({'['}).s.substr(5);
  for (float f : {7.0f, 8.0f, 9.0f}) {
    m += std::string("\x40\x19\x01", 3);
    append(m, f);
  }
  m += "]]]]]]}";
  const PointCloud one = read_point_cloud(write(dir / "map.bgeo", m));
  ASSERT_EQ(one.positions.size(), 1u);
  EXPECT_EQ(one.positions[0], (Vec3{7, 8, 9}));

  // Nesting past the limit, a page size past it, constant pages expanding past 64 values a
  // byte, a tuple of the wrong size: refused, naming what.
  EXPECT_REFUSED(read_point_cloud(write(dir / "deep.bgeo", "\x7fNSJb" + std::string(200, '['))), Status::FormatError,
                 "nested more than 64 deep");
  std::string paged = BinaryJson().raw({'['}).str("pointcount").i32(1 << 30).str("attributes").raw({'['}).str("pointattributes")
                          .raw({'[', '[', '['}).str("name").str("P").str("type").str("numeric").raw({']', '['}).str("values")
                          .raw({'['}).str("size").i32(3).str("pagesize").i32(1024).str("constantpageflags").raw({'['}).s;
  paged += std::string("\x40\x10\xf4", 3);
  append(paged, uint32_t(1 << 20));
  paged += std::string((1 << 20) / 8, '\xff');
  paged += BinaryJson().raw({']'}).str("rawpagedata").raw({0x40, 0x19, 3, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, ']', ']', ']', ']', ']', ']'}).s.substr(5);
  EXPECT_REFUSED(read_point_cloud(write(dir / "expand.bgeo", paged)), Status::FormatError, "more than 64 per byte");
  std::string wrong;
  wrong += std::string("\x40\x19\x02", 3);
  append(wrong, 1.0f);
  append(wrong, 2.0f);
  EXPECT_REFUSED(read_point_cloud(write(dir / "tuple.bgeo", BinaryJson().geometry(wrong, 1).s)), Status::FormatError,
                 "tuple 0 does not hold 3 values");
  EXPECT_REFUSED(read_point_cloud(write(dir / "short.bgeo", BinaryJson().geometry(t, 4).s)), Status::FormatError,
                 "\"tuples\" holds 3 tuples for 4 points");
}

// Houdini's .bgeo.sc (SideFX's SCF around Blosc chunks, compressed.cpp): the same points as
// the plain file, for each of Blosc's compressors, chunk sizes that split the content into
// many chunks or one, with and without a metadata section; the .geo.sc of the text form too.
// A damaged container is refused naming what is wrong, before anything is decompressed.
TEST(BgeoReader, BloscCompressedScContainers) {
  const auto dir = test::scratch_dir("bgeo_sc");
  std::string t;
  for (int i = 0; i < 300; ++i) {
    t += std::string("\x40\x19\x03", 3);
    for (float f : {float(i) * 0.25f, float(i % 17) - 8.0f, 1.0f / float(i + 1)}) append(t, f);
  }
  const std::string content = BinaryJson().geometry(t, 300).s;
  const PointCloud plain = read_point_cloud(write(dir / "plain.bgeo", content));
  ASSERT_EQ(plain.positions.size(), 300u);
  for (const char* codec : {"blosclz", "lz4", "zlib", "zstd"})
    for (size_t block : {size_t(64), size_t(1000), size_t(65536)})
      for (const std::string& metadata : {std::string(), std::string("{\"software\": \"test\"}")}) {
        SCOPED_TRACE(std::string(codec) + ", chunks of " + std::to_string(block) + " bytes");
        const PointCloud c = read_point_cloud(write(dir / "c.bgeo.sc", test::scf_wrap(content, block, codec, metadata)));
        EXPECT_EQ(c.positions, plain.positions);
      }
  const std::string text = "[\"pointcount\", 2, \"attributes\", [\"pointattributes\", [[[\"name\", \"P\", \"type\", "
                           "\"numeric\"], [\"values\", [\"size\", 3, \"tuples\", [[1, 2, 3], [4, 5, 6.5]]]]]]]]";
  const PointCloud g = read_point_cloud(write(dir / "t.geo.sc", test::scf_wrap(text, 16, "zstd")));
  EXPECT_EQ(g.positions, (std::vector<Vec3>{{1, 2, 3}, {4, 5, 6.5}}));

  const std::string good = test::scf_wrap(content, 1000);
  const auto patched = [&](size_t at, const std::string& bytes) {
    std::string s = good;
    s.replace(at, bytes.size(), bytes);
    return s;
  };
  std::string huge(8, '\xff');
  EXPECT_REFUSED(read_point_cloud(write(dir / "cut.bgeo.sc", good.substr(0, good.size() / 2))), Status::FormatError,
                 "truncated (it does not end with the SCF footer");
  EXPECT_REFUSED(read_point_cloud(write(dir / "meta.bgeo.sc", patched(4, huge))), Status::FormatError,
                 "its metadata length (18446744073709551615) runs past its end");
  EXPECT_REFUSED(read_point_cloud(write(dir / "index.bgeo.sc", patched(good.size() - 12, huge))), Status::FormatError,
                 "its seek index length (18446744073709551615) does not fit");
  // The first chunk's compressed size (bytes 12..15 of its header) past the data.
  EXPECT_REFUSED(read_point_cloud(write(dir / "chunk.bgeo.sc", patched(12 + 12, std::string("\xff\xff\x00\x00", 4)))),
                 Status::FormatError, "the Blosc chunk at byte 12 runs past the seek index");
  // Its uncompressed size (bytes 4..7) beyond anything Blosc makes of its few hundred bytes.
  EXPECT_REFUSED(read_point_cloud(write(dir / "ratio.bgeo.sc", patched(12 + 4, std::string("\x00\x00\x00\x7f", 4)))),
                 Status::FormatError, "more than Blosc's compressors give");
  // A byte between the last chunk and the index.
  const size_t index = good.size() - 12 - size_t(static_cast<unsigned char>(good[good.size() - 5]));  // < 256 here
  std::string padded = good;
  padded.insert(index, 1, '\0');
  EXPECT_REFUSED(read_point_cloud(write(dir / "pad.bgeo.sc", padded)), Status::FormatError, "runs past the seek index");
  std::string empty = "scf1";
  test::append_be64(empty, 0);
  test::append_be64(empty, 0);
  test::append_be64(empty, 0);
  test::append_be64(empty, 16);
  EXPECT_REFUSED(read_point_cloud(write(dir / "empty.bgeo.sc", empty + "1fcs")), Status::FormatError,
                 "it holds no compressed data");
  EXPECT_REFUSED(read_point_cloud(write(dir / "other.bgeo.sc", test::scf_wrap("PLY is not bgeo", 64))),
                 Status::FormatError, "once decompressed");
}

// VTK XML arrays compressed by each of VTK's compressors (zlib, LZ4, LZMA), in several blocks
// (the last one short): every value exact. Blocks whose header claims more than their codec
// can give from their bytes are refused before anything is allocated; damaged blocks are
// refused naming the codec. (Files of VTK's own writers: tests/python/test_vtk_files.py.)
TEST(VtkXmlReader, CompressedBlocksOfEveryCodec) {
  using test::VtuCodec;
  const auto dir = test::scratch_dir("vtu_codecs");
  std::vector<float> xyz;
  for (int i = 0; i < 3 * 50; ++i) xyz.push_back(float(i % 7) * 0.5f - float(i) * 1e-3f);
  for (VtuCodec codec : {VtuCodec::Zlib, VtuCodec::Lz4, VtuCodec::Xz}) {
    SCOPED_TRACE(test::compressor_name(codec));
    for (size_t block : {size_t(64), size_t(100), size_t(4096)}) {
      const PointCloud c = read_point_cloud(write(dir / "c.vtu", test::compressed_vtu(codec, xyz, block)));
      ASSERT_EQ(c.positions.size(), 50u);
      for (size_t i = 0; i < 50; ++i)
        EXPECT_EQ(c.positions[i], (Vec3{xyz[3 * i], xyz[3 * i + 1], xyz[3 * i + 2]})) << i;
    }
    // One block of 600 000 bytes from 2 compressed bytes: more than any codec gives.
    std::vector<float> many(3 * 50000, 1.0f);
    std::string header;
    auto word = [&](uint32_t v) { header.append(reinterpret_cast<const char*>(&v), 4); };
    word(1), word(600000), word(0), word(2);
    EXPECT_REFUSED(read_point_cloud(write(dir / "claim.vtu", test::compressed_vtu(codec, many, 600000, header + "xx"))),
                   Status::FormatError, "2 compressed bytes cannot hold the 600000 its header claims");
    // The right header over damaged bytes.
    std::string array = test::compressed_array(codec, std::string(reinterpret_cast<const char*>(xyz.data()), 600), 600);
    array[16] = char(~array[16]);  // the block's first byte: zlib's header, LZ4's first token, xz's magic
    const std::string codec_name = codec == VtuCodec::Zlib ? "zlib" : codec == VtuCodec::Lz4 ? "LZ4" : "xz";
    EXPECT_REFUSED(read_point_cloud(write(dir / "bad.vtu", test::compressed_vtu(codec, xyz, 600, array))),
                   Status::FormatError, "block 0: the " + codec_name + " data is corrupt");
  }
}

namespace {
/// A Krakatoa .prt: channels (name, type code, arity) over `count` records of `record` bytes.
std::string prt_file(int64_t count, const std::vector<std::tuple<std::string, int32_t, int32_t>>& channels,
                     const std::string& records, const char* magic = "\xC0PRT\r\n\x1A\n") {
  std::string s(magic, 8);
  append(s, int32_t(56));
  s += std::string("Extensible Particle Format") + std::string(6, '\0');
  append(s, int32_t(1));
  append(s, count);
  append(s, int32_t(4));
  append(s, int32_t(channels.size()));
  append(s, int32_t(44));
  int32_t offset = 0;
  for (const auto& [name, type, arity] : channels) {
    s += name + std::string(32 - name.size(), '\0');
    append(s, type);
    append(s, arity);
    append(s, offset);
    offset += arity * (type == 3 ? 2 : type == 5 ? 8 : 4);
  }
  uLongf size = compressBound(uLong(records.size()));
  std::string z(size, '\0');
  compress(reinterpret_cast<Bytef*>(z.data()), &size, reinterpret_cast<const Bytef*>(records.data()), uLong(records.size()));
  return s + z.substr(0, size);
}
}  // namespace

// Krakatoa .prt: Position, Normal and other channels of any type exactly (float16 too); a
// malformed header, a missing Position, a count the data cannot hold and corrupt data are
// refused naming the file and the problem.
TEST(PrtReader, ChannelsExactAndBadFilesNamed) {
  const auto dir = test::scratch_dir("prt");
  std::string records;
  for (int i = 0; i < 2; ++i) {
    for (float v : {float(i), 2.0f, 3.0f}) append(records, v);                    // Position float32
    for (uint16_t h : {uint16_t(0x3e00), uint16_t(0xc000), uint16_t(0x3400)}) append(records, h);  // Velocity float16
    append(records, double(1000.5 + i));                                          // Density float64
    for (float v : {0.0f, 0.0f, 1.0f}) append(records, v);                        // Normal float32
  }
  const std::vector<std::tuple<std::string, int32_t, int32_t>> channels = {
      {"Position", 4, 3}, {"Velocity", 3, 3}, {"Density", 5, 1}, {"Normal", 4, 3}};
  const PointCloud c = read_point_cloud(write(dir / "ok.prt", prt_file(2, channels, records)));
  ASSERT_EQ(c.size(), 2u);
  EXPECT_EQ(c.positions[1], (Vec3{1, 2, 3}));
  ASSERT_EQ(c.normals.size(), 2u);
  EXPECT_EQ(c.normals[1], (Vec3{0, 0, 1}));
  ASSERT_EQ(c.attributes.size(), 2u);
  EXPECT_EQ(c.attributes[0].name, "velocity");
  EXPECT_EQ(c.attributes[0].values, (std::vector<float>{1.5f, -2.0f, 0.25f, 1.5f, -2.0f, 0.25f}));
  EXPECT_EQ(c.attributes[1].name, "density");
  EXPECT_EQ(c.attributes[1].values, (std::vector<float>{1000.5f, 1001.5f}));

  EXPECT_REFUSED(read_point_cloud(write(dir / "magic.prt", prt_file(2, channels, records, "\xC0PRX\r\n\x1A\n"))),
                 Status::FormatError, "magic.prt': not a Krakatoa PRT file");
  EXPECT_REFUSED(read_point_cloud(write(dir / "nopos.prt", prt_file(2, {{"Density", 5, 1}}, std::string(16, '\0')))),
                 Status::FormatError, "nopos.prt': no Position channel");
  EXPECT_REFUSED(read_point_cloud(write(dir / "type.prt", prt_file(2, {{"Position", 11, 3}}, records))),
                 Status::FormatError, "channel 0 'Position': data type 11 is not 0..10");
  EXPECT_REFUSED(read_point_cloud(write(dir / "many.prt", prt_file(int64_t(1) << 40, channels, records))),
                 Status::FormatError, "particles of 38 bytes cannot come from the");
  EXPECT_REFUSED(read_point_cloud(write(dir / "more.prt", prt_file(3, channels, records))), Status::FormatError,
                 "the particle data: ");
  std::string bad = prt_file(2, channels, records);
  bad.resize(bad.size() - 6);
  EXPECT_REFUSED(read_point_cloud(write(dir / "cut.prt", bad)), Status::FormatError, "cut.prt': the particle data: truncated");
  EXPECT_REFUSED(read_point_cloud(write(dir / "short.prt", prt_file(2, channels, records).substr(0, 70))),
                 Status::FormatError, "short.prt': truncated: the file ends");
}

// A ParaView collection lists frames in any order: they come back by time, joined to its
// folder (Windows' backslashes read as '/'); a .series the same. Entries that would reach
// outside its folder, share a time, or lack a file or a time are refused by name.
TEST(FrameCollection, FramesByTimeInsideTheCollectionsFolder) {
  const fs::path dir = test::scratch_dir("collection");
  EXPECT_TRUE(is_frame_collection("a/b.PVD") && is_frame_collection("f.vtu.series") && !is_frame_collection("f.vtu"));
  const std::string pvd = write(dir / "run.pvd",
                                "<?xml version=\"1.0\"?>\n<VTKFile type=\"Collection\" version=\"0.1\">\n"
                                "<Collection>\n<DataSet timestep=\"0.5\" part=\"0\" file=\"b.vtu\"/>\n"
                                "<!-- a comment -->\n<DataSet timestep=\" 1e-3 \" file=\"sub\\a.vtu\"/>\n"
                                "</Collection>\n</VTKFile>\n");
  const std::string series = write(
      dir / "run.vtu.series",
      R"({"file-series-version": "1.0", "files": [{"name": "b.vtu", "time": 0.5}, {"name": "sub/a.vtu", "time": 0.001}]})");
  for (const std::string& path : {pvd, series}) {
    const std::vector<CollectionFrame> f = read_frame_collection(path);
    ASSERT_EQ(f.size(), 2u) << path;
    EXPECT_EQ(f[0].time, 0.001);
    EXPECT_EQ(f[0].path, (dir / "sub/a.vtu").string());
    EXPECT_EQ(f[1].time, 0.5);
    EXPECT_EQ(f[1].path, (dir / "b.vtu").string());
    EXPECT_EQ(f[1].listed, "b.vtu");
  }
  auto one = [&](const std::string& time, const std::string& file) {
    return write(dir / "one.pvd", "<VTKFile type=\"Collection\"><Collection><DataSet timestep=\"" + time +
                                      "\" file=\"" + file + "\"/></Collection></VTKFile>");
  };
  EXPECT_REFUSED(read_frame_collection(one("0", "../a.vtu")), Status::FormatError, "not a path inside the collection");
  // An absolute path is refused even when it names a file beside the collection.
  EXPECT_REFUSED(read_frame_collection(one("0", (dir / "a.vtu").string())), Status::FormatError, "not a path inside");
  EXPECT_REFUSED(read_frame_collection(one("0", "a/..\\..\\b.vtu")), Status::FormatError, "not a path inside");
  EXPECT_REFUSED(read_frame_collection(one("inf", "a.vtu")), Status::FormatError, "the time of 'a.vtu' is not finite");
  EXPECT_REFUSED(read_frame_collection(one("t", "a.vtu")), Status::FormatError, "the timestep 't' of 'a.vtu' is not a number");
  EXPECT_REFUSED(read_frame_collection(write(dir / "e.pvd", "<VTKFile type=\"Collection\"><Collection/></VTKFile>")),
                 Status::FormatError, "lists no frame");
  EXPECT_REFUSED(read_frame_collection(write(dir / "g.pvd", "<VTKFile type=\"PolyData\"></VTKFile>")),
                 Status::FormatError, "is not a Collection");
  EXPECT_REFUSED(read_frame_collection(write(dir / "t.series", R"({"files": [{"name": "a", "time": 1}, {"name": "b", "time": 1}]})")),
                 Status::FormatError, "'a' and 'b' share the time 1");
  EXPECT_REFUSED(read_frame_collection(write(dir / "n.series", R"({"files": [{"name": "a", "time": "1"}]})")),
                 Status::FormatError, "files[0] ('a') has no numeric \"time\"");
  EXPECT_REFUSED(read_frame_collection((dir / "none.pvd").string()), Status::IoError, "none.pvd");
}
