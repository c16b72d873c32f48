// Files whose header promises more data than the file holds: a FormatError naming
// the file and what is missing, before anything is allocated from the promised counts.
// OpenMesh's readers trust their headers: unchecked, an ASCII PLY promising 2e9 vertices read
// as a 4-vertex mesh (one made up), an OFF file promising 1e9 vertices looped and allocated
// for minutes, and a binary PLY face's list count was an allocation size.
#include <gtest/gtest.h>

#include <cstring>
#include <filesystem>
#include <fstream>

#include "hostile_support.h"
#include "particlemesh/io/mesh_io.h"
#include "particlemesh/sample/shapes.h"
#include "support/test_support.h"

using namespace particlemesh;
using namespace particlemesh::test;
namespace fs = std::filesystem;

namespace {

std::string write(const fs::path& p, const std::string& bytes) {
  std::ofstream(p, std::ios::binary).write(bytes.data(), std::streamsize(bytes.size()));
  return p.string();
}

template <class T>
void append(std::string& s, T v) {
  s.append(reinterpret_cast<const char*>(&v), sizeof v);
}

const char* kVertexHeader = "element vertex %s\nproperty float x\nproperty float y\nproperty float z\n";

std::string ply(const std::string& format, const std::string& vertices, const std::string& faces = "",
                const std::string& list = "uchar int") {
  char buf[256];
  std::snprintf(buf, sizeof buf, kVertexHeader, vertices.c_str());
  std::string h = "ply\nformat " + format + " 1.0\n" + buf;
  if (!faces.empty()) h += "element face " + faces + "\nproperty list " + list + " vertex_indices\n";
  return h + "end_header\n";
}

// Both readers (mesh and particles) must refuse, quickly, with the message.
void expect_refused(const std::string& path, const std::string& text, bool cloud = true) {
  const auto t0 = Clock::now();
  PM_EXPECT_ERROR(read_mesh(path), Status::FormatError, text);
  if (cloud) PM_EXPECT_ERROR(read_point_cloud(path), Status::FormatError, text);
  EXPECT_LT(seconds(Clock::now() - t0), 5.0) << "a hang, not a check";
  std::string msg;
  status_of([&] { read_mesh(path); }, &msg);
  EXPECT_NE(msg.find(fs::path(path).filename().string()), std::string::npos) << msg;
}

}  // namespace

TEST(FileLimits, AsciiPlyPromisingMoreVerticesOrFaces) {
  const auto dir = scratch_dir("ply");
  expect_refused(write(dir / "v.ply", ply("ascii", "2000000000") + "0 0 0\n1 0 0\n0 1 0\n"),
                 "promises 2000000000 'vertex' elements, the file ends in element 3");
  expect_refused(write(dir / "f.ply", ply("ascii", "5", "3") + "0 0 0\n1 0 0\n0 1 0\n1 1 0\n0 0 1\n3 0 1 2\n"),
                 "promises 3 'face' elements, the file ends in element 1");
  // A face whose list count is more than the file holds.
  expect_refused(write(dir / "l.ply", ply("ascii", "3", "1") + "0 0 0\n1 0 0\n0 1 0\n4000000000 0 1 2\n"),
                 "promises 1 'face' element, the file ends in element 0");
  expect_refused(write(dir / "neg.ply", ply("ascii", "3", "1") + "0 0 0\n1 0 0\n0 1 0\n-3 0 1 2\n"),
                 "list count '-3' is not a non-negative integer");
  // Exactly what it promises: fine (and a trailing extra line is ignored, as before).
  const TriMesh m = read_mesh(write(dir / "ok.ply", ply("ascii", "3", "1") + "0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n\n"));
  EXPECT_EQ(m.positions.size(), 3u);
  EXPECT_EQ(m.triangles.size(), 1u);
}

TEST(FileLimits, BinaryPlyPromisingMoreOrHugeListCounts) {
  const auto dir = scratch_dir("bply");
  std::string v = ply("binary_little_endian", "2000000000");
  for (int i = 0; i < 9; ++i) append(v, float(i));
  expect_refused(write(dir / "v.ply", v), "promises 2000000000 'vertex' elements (at least 24000000000 bytes)");
  // A face list whose count (an int here) is 4e9: more than the rest of the file.
  std::string l = ply("binary_little_endian", "3", "1", "uint int");
  for (int i = 0; i < 9; ++i) append(l, float(i % 2));
  append(l, uint32_t(4000000000u));
  for (int i = 0; i < 3; ++i) append(l, int32_t(i));
  expect_refused(write(dir / "l.ply", l), "has a list of 4000000000 items, more than the rest of the file holds");
  std::string neg = ply("binary_little_endian", "3", "1", "int int");
  for (int i = 0; i < 9; ++i) append(neg, float(i % 2));
  append(neg, int32_t(-1));
  expect_refused(write(dir / "neg.ply", neg), "negative list count");
  std::string f = ply("binary_big_endian", "3", "2");
  for (int i = 0; i < 9; ++i) append(f, uint32_t(0));
  f += char(3);
  for (int i = 0; i < 3; ++i) append(f, uint32_t(__builtin_bswap32(uint32_t(i))));
  expect_refused(write(dir / "f.ply", f), "promises 2 'face' elements, the file ends in element 1");
  // Our own writer's files pass the check unchanged.
  const TriMesh ico = icosphere_mesh(2);
  write_mesh(ico, (dir / "ico.ply").string());
  EXPECT_EQ(read_mesh((dir / "ico.ply").string()).triangles, ico.triangles);
}

TEST(FileLimits, PlyHeaderItself) {
  const auto dir = scratch_dir("hdr");
  expect_refused(write(dir / "noend.ply", "ply\nformat ascii 1.0\nelement vertex 3\n"), "no end_header");
  expect_refused(write(dir / "count.ply", "ply\nformat ascii 1.0\nelement vertex lots\nend_header\n"),
                 "element NAME COUNT");
  expect_refused(write(dir / "type.ply", "ply\nformat ascii 1.0\nelement vertex 1\nproperty quad x\nend_header\n1\n"),
                 "unknown type");
  expect_refused(write(dir / "fmt.ply", "ply\nformat zip 1.0\nelement vertex 1\nend_header\n"), "not ascii or binary");
  // OpenMesh's reader looped forever on an unparsable version (found by fuzzing).
  expect_refused(write(dir / "ver.ply", "ply\nformat ascii ..0\nelement vertex 1\nproperty float x\nend_header\n1\n"),
                 "format TYPE VERSION");
  // Header lines are read line by line: a line that is not a PLY keyword is refused by name
  // (OpenMesh read the header word by word, took end_header for a property name and looped
  // forever; found by fuzzing). An obj_info line mentioning end_header is only information.
  const std::string xyz = "element vertex 1\nproperty float x\nproperty float y\nproperty float z\n";
  expect_refused(write(dir / "mid.ply", "ply\nformat ascii 1.0\n" + xyz + "x property float\nend_header\n0 0 0\n"),
                 "bad PLY header line 'x property float' (unknown keyword 'x')");
  EXPECT_EQ(read_point_cloud(write(dir / "mid2.ply", "ply\nformat ascii 1.0\n" + xyz +
                                                         "obj_info end_header\nend_header\n0 0 7\n"))
                .positions[0].z,
            7.0);
  // OpenMesh takes the three words after "ply" as the format line, whatever they are; an
  // unreadable version there left its stream failed and it looped forever (found by fuzzing).
  expect_refused(write(dir / "first.ply", "ply\ncomment before\nformat ascii 1.0\n" + xyz + "end_header\n0 0 0\n"),
                 "the line after 'ply' must be: format TYPE VERSION");
  expect_refused(write(dir / "first2.ply", "ply\nfo:rmat ascii \x01t\nformat ascii 1.0\n" + xyz + "end_header\n0 0 0\n"),
                 "the line after 'ply' must be");
  expect_refused(write(dir / "two.ply", "ply\nformat ascii 1.0\n" + xyz + "format binary_little_endian 1.0\nend_header\n0 0 0\n"),
                 "a second format line");
  // Unknown keywords and comments that merely mention a keyword are read as before.
  const PointCloud ok = read_point_cloud(
      write(dir / "info.ply", "ply\nformat ascii 1.0\nobj_info scanner 3\ncomment a property of end_header\n" + xyz +
                                  "obj_info x comment property\nend_header\n0 1 2\n"));
  ASSERT_EQ(ok.size(), 1u);
  EXPECT_EQ(ok.positions[0].z, 2.0);
}

// OpenMesh's ASCII PLY reader neither checks a read nor reads a token twice: a value it cannot
// read whole ("4.89859e0-17", ".0-565685") left the stream failed or shifted, and the face
// list counts after it stale: 1 GB allocated from a 3 kB file (found by fuzzing).
TEST(FileLimits, AsciiPlyValuesThatAreNotNumbers) {
  const auto dir = scratch_dir("plytokens");
  const std::string head = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
                           "property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n";
  const std::string verts[] = {"0 0 0\n", "1 0 0\n", "0 1 0\n"};
  auto file = [&](const std::string& v1, const std::string& face) { return head + verts[0] + v1 + verts[2] + face; };
  expect_refused(write(dir / "e.ply", file("1 4.89859e0-17 0\n", "3 0 1 2\n")), "'vertex' element 1: '4.89859e0-17' is not a number");
  expect_refused(write(dir / "d.ply", file("1 .0-565685 0\n", "3 0 1 2\n")), "'.0-565685' is not a number");
  // NaN is a number the file holds: named with its vertex, for meshes and particles.
  PM_EXPECT_ERROR(read_mesh(write(dir / "n.ply", file("1 nan 0\n", "3 0 1 2\n"))), Status::FormatError, "vertex 1: y is NaN");
  PM_EXPECT_ERROR(read_point_cloud((dir / "n.ply").string()), Status::InvalidInput, "n.ply': positions[1].y is NaN");
  expect_refused(write(dir / "i.ply", file(verts[1], "3 0 1.5 2\n")), "'face' element 0: '1.5' is not an integer", false);
  // OpenMesh trimmed the magic line: " ply" without end_header looped for minutes (fuzzing).
  expect_refused(write(dir / "space.ply", " ply \nformat ascii 1.0\nelement vertex 1\nproperty float x\nend_h\n"),
                 "bad PLY header line 'end_h' (unknown keyword 'end_h')");
  expect_refused(write(dir / "space2.ply", " ply \nformat ascii 1.0\nelement vertex 1\nproperty float x\n"),
                 "no end_header");
  // What writers produce is read: exponents, signs, leading dots, CRLF.
  const TriMesh m = read_mesh(write(dir / "ok.ply", file("1e0 -0.0 +.5e-3\r\n", "3 0 1 2\r\n")));
  ASSERT_EQ(m.triangles.size(), 1u);
  EXPECT_FLOAT_EQ(float(m.positions[1].z), 0.0005f);
}

TEST(FileLimits, OffPromisingMore) {
  const auto dir = scratch_dir("off");
  expect_refused(write(dir / "v.off", "OFF\n1000000000 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n"),
                 "promises 1000000000 vertices and 1 faces", false);
  expect_refused(write(dir / "f.off", "OFF\n3 1000000000 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n"),
                 "promises 3 vertices and 1000000000 faces", false);
  expect_refused(write(dir / "x.off", "OFF\n3 x 0\n"), "'x' is not a vertex/face/edge count", false);
  // Comments are read anywhere (OpenMesh's reader could not read one before the counts).
  expect_refused(write(dir / "c.off", "OFF\n# a comment\n3 1 0\n"), "promises 3 vertices and 1 faces, the file ends in vertex 0", false);
  EXPECT_EQ(read_mesh(write(dir / "cok.off", "OFF # the keyword\n# a comment\n3 1 0\n0 0 0 # a vertex\n1 0 0\n0 1 0\n3 0 1 2\n"))
                .triangles.size(),
            1u);
  // ModelNet's files glue the vertex count to the keyword (and trimesh's test file indents it).
  const TriMesh glued = read_mesh(write(dir / "glued.off", "\t  OFF3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n"));
  EXPECT_EQ(glued.positions.size(), 3u);
  EXPECT_EQ(glued.triangles.size(), 1u);
  expect_refused(write(dir / "glued_bad.off", "OFF3x 1 0\n"), "bad OFF header: '3x' is not a vertex/face/edge count", false);
  // Found by fuzzing: the whole file on the keyword's line (OpenMesh then read its counts from
  // a failed stream: uninitialized, an allocation of GBs).
  expect_refused(write(dir / "line.off", "COFF \xff\xff 05 0OF 5"), "bad OFF header: '?\?' is not a vertex/face/edge count", false);
  // A face's corner count is walked too: 4e9 corners in a 40-byte file was 4e9 handles pushed.
  const std::string tri = "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n";
  expect_refused(write(dir / "k.off", tri + "4000000000 0 1 2\n"), "the file ends in face 0 (4000000000 corners)", false);
  expect_refused(write(dir / "k2.off", "OFF\n3 2 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n9 0 1\n"),
                 "ends in face 1 (9 corners)", false);
  // A token the reader cannot read fails its stream: every later read is stale.
  expect_refused(write(dir / "nan.off", "OFF\n3 1 0\n0 0 0\n1 zero 0\n0 1 0\n3 0 1 2\n"), "vertex 1: 'zero' is not a number", false);
  expect_refused(write(dir / "idx.off", tri + "3 0 a 2\n"), "face 0: corner 'a' is not an index", false);
  // Binary OFF is refused by name (OpenMesh read it with the host's byte order, where
  // Geomview's format is big-endian: a reader of it would be a reader of our own guess).
  std::string bin = "OFF BINARY\n";
  for (uint32_t c : {3u, 1u, 0u}) append(bin, c);
  for (int i = 0; i < 9; ++i) append(bin, float(i % 2));
  append(bin, uint32_t(4000000000u));
  expect_refused(write(dir / "b.off", bin), "binary OFF is not read", false);
  // More data than the counts: a count is wrong.
  expect_refused(write(dir / "more.off", tri + "3 0 1 2\n3 0 2 1\n"), "more data after the 3 vertices and 1 faces", false);

  const TriMesh ok = read_mesh(write(dir / "ok.off", "OFF\n4 2 0\n0 0 0\n1 0 0\n0 1 0\n1 1 0\n3 0 1 2\n3 1 3 2\n"));
  EXPECT_EQ(ok.triangles.size(), 2u);
  // Colours on vertex and face lines (COFF), normals (NOFF), values across lines: read.
  const TriMesh coff = read_mesh(write(dir / "ok.coff.off",
                                       "COFF\n3 1 0\n0 0 0 255 0 0\n1 0 0 0 255 0\n0 1 0 0 0 255 255\n3 0 1 2 10 20 30\n"));
  EXPECT_EQ(coff.triangles.size(), 1u);
  const TriMesh noff = read_mesh(write(dir / "ok.noff.off", "NOFF\n3 1\n0\n0 0 0 0 0 1\n1 0 0 0 0 1\n0 1 0 0 0 1\n3 0 1 2\n"));
  EXPECT_EQ(noff.triangles.size(), 1u);
}

TEST(FileLimits, BinaryStlPromisingMore) {
  const auto dir = scratch_dir("stl");
  std::string s(80, ' ');
  append(s, uint32_t(100000000));
  s += std::string(50, '\0');
  expect_refused(write(dir / "t.stl", s), "truncated binary STL: the header promises 100000000 triangles", false);
  std::string ok(80, ' ');
  append(ok, uint32_t(1));
  for (float f : {0.f, 0.f, 1.f, 0.f, 0.f, 0.f, 1.f, 0.f, 0.f, 0.f, 1.f, 0.f}) append(ok, f);
  append(ok, uint16_t(0));
  EXPECT_EQ(read_mesh(write(dir / "ok.stl", ok)).triangles.size(), 1u);
}
