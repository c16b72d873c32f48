// Meshes for ParaView and the simulation tools: VTK legacy .vtk and VTK XML .vtu / .vtp.
//
// .vtk: "# vtk DataFile Version 3.0", BINARY (big-endian, as the format requires), POLYDATA
// with POINTS (float, or double when float32 would not hold them: needs_double_positions),
// POLYGONS (the classic counts-and-ids layout every VTK since 3.0 reads), and POINT_DATA with
// NORMALS "Normals" and one FIELD array per attribute (float, its components; names with
// spaces or other special characters written as VTK writes them, %XX).
// .vtu / .vtp: UnstructuredGrid (triangle cells, type 5) or PolyData (Polys), one piece, data
// appended raw, little-endian, UInt64 headers, uncompressed: PointData Normals="Normals" and
// one array per attribute, Points (Float32 or Float64 as above), connectivity and offsets
// Int64.
// Written by hand for the reason the readers are (vtk_legacy_reader.cpp): the core library
// does not depend on VTK; the tests read every file written here back with VTK's own readers.
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

#include "io/writers.h"
#include "particlemesh/core/error.h"

namespace PM_NAMESPACE::detail {

namespace {

/// Bytes for an OutputFile, in 64 KiB writes.
class Bytes {
 public:
  explicit Bytes(OutputFile& out) : out_(out) { buf_.reserve(kSize + 64); }
  ~Bytes() = default;
  void put(std::string_view s) {
    buf_.append(s);
    if (buf_.size() >= kSize) flush();
  }
  template <class T>
  void big_endian(T v) {
    unsigned char b[sizeof(T)];
    std::memcpy(b, &v, sizeof(T));
    for (size_t i = 0; i < sizeof(T); ++i) buf_.push_back(char(b[sizeof(T) - 1 - i]));  // hosts are little-endian
    if (buf_.size() >= kSize) flush();
  }
  template <class T>
  void little_endian(T v) {
    buf_.append(reinterpret_cast<const char*>(&v), sizeof(T));
    if (buf_.size() >= kSize) flush();
  }
  void flush() {
    out_.write(buf_.data(), buf_.size());
    buf_.clear();
  }

 private:
  static constexpr size_t kSize = size_t(1) << 16;
  OutputFile& out_;
  std::string buf_;
};

/// A legacy array name: VTK's %XX for what would break a whitespace-separated header.
std::string legacy_name(const std::string& name) {
  std::string s;
  char hex[4];
  for (char c : name.empty() ? std::string("attribute") : name) {
    const auto u = static_cast<unsigned char>(c);
    if (u <= ' ' || u > '~' || c == '%') {
      std::snprintf(hex, sizeof hex, "%%%02X", u);
      s += hex;
    } else {
      s.push_back(c);
    }
  }
  return s;
}

std::string xml_escaped(const std::string& text) {
  std::string s;
  for (char c : text) {
    switch (c) {
      case '&': s += "&amp;"; break;
      case '<': s += "&lt;"; break;
      case '>': s += "&gt;"; break;
      case '"': s += "&quot;"; break;
      default: s.push_back(c);
    }
  }
  return s;
}

std::vector<const VertexAttribute*> carried(const TriMesh& mesh) {
  std::vector<const VertexAttribute*> out;
  for (const VertexAttribute& a : mesh.attributes)
    if (a.components >= 1 && a.values.size() == mesh.positions.size() * size_t(a.components)) out.push_back(&a);
  return out;
}

/// One line, without what would end it or the XML comment early.
std::string one_line(const std::string& text, bool xml) {
  std::string s;
  for (char c : text) s.push_back(c == '\n' || c == '\r' ? ' ' : c);
  if (xml)
    for (size_t p; (p = s.find("--")) != std::string::npos;) s.replace(p, 2, "- ");
  return s;
}

}  // namespace

void write_vtk(const TriMesh& mesh, OutputFile& out, bool normals, const std::string& comment) {
  const auto& P = mesh.positions;
  const bool doubles = needs_double_positions(P);
  const size_t n = P.size(), t = mesh.triangles.size();
  if (t > size_t(INT32_MAX) / 4) throw Error(Status::LimitExceeded, "'" + out.path() + "': too many triangles for a legacy .vtk file (use .vtu)");
  Bytes b(out);
  std::string title = one_line(comment.empty() ? std::string("particlemesh mesh") : comment, false);
  if (title.size() > 255) title.resize(255);  // the format's limit
  b.put("# vtk DataFile Version 3.0\n" + title + "\nBINARY\nDATASET POLYDATA\nPOINTS " + std::to_string(n) +
        (doubles ? " double\n" : " float\n"));
  for (const Vec3& p : P)
    for (int a = 0; a < 3; ++a) {
      if (doubles) b.big_endian(p[a]);
      else b.big_endian(float(p[a]));
    }
  b.put("\nPOLYGONS " + std::to_string(t) + " " + std::to_string(4 * t) + "\n");
  for (const Triangle& tri : mesh.triangles) {
    b.big_endian(int32_t(3));
    for (uint32_t v : tri) b.big_endian(int32_t(v));
  }
  b.put("\n");
  const auto attrs = carried(mesh);
  if (n > 0 && (normals || !attrs.empty())) {
    b.put("POINT_DATA " + std::to_string(n) + "\n");
    if (normals) {
      b.put("NORMALS Normals float\n");
      for (const Vec3& v : mesh.normals)
        for (int a = 0; a < 3; ++a) b.big_endian(float(v[a]));
      b.put("\n");
    }
    if (!attrs.empty()) {
      b.put("FIELD FieldData " + std::to_string(attrs.size()) + "\n");
      for (const VertexAttribute* a : attrs) {
        b.put(legacy_name(a->name) + " " + std::to_string(a->components) + " " + std::to_string(n) + " float\n");
        for (float v : a->values) b.big_endian(v);
        b.put("\n");
      }
    }
  }
  b.flush();
}

void write_vtk_xml(const TriMesh& mesh, OutputFile& out, bool normals, bool polydata, const std::string& comment) {
  const auto& P = mesh.positions;
  const bool doubles = needs_double_positions(P);
  const uint64_t n = P.size(), t = mesh.triangles.size();
  const auto attrs = carried(mesh);
  // Appended blocks in order: normals, attributes, points, connectivity, offsets, (types).
  uint64_t offset = 0;
  auto block = [&](uint64_t bytes) {
    const uint64_t at = offset;
    offset += 8 + bytes;
    return std::to_string(at);
  };
  const char* kind = polydata ? "PolyData" : "UnstructuredGrid";
  std::string x = "<?xml version=\"1.0\"?>\n";
  if (!comment.empty()) x += "<!-- " + one_line(comment, true) + " -->\n";
  x += std::string("<VTKFile type=\"") + kind + "\" version=\"1.0\" byte_order=\"LittleEndian\" header_type=\"UInt64\">\n";
  x += std::string("  <") + kind + ">\n    <Piece NumberOfPoints=\"" + std::to_string(n) + "\" " +
       (polydata ? "NumberOfVerts=\"0\" NumberOfLines=\"0\" NumberOfStrips=\"0\" NumberOfPolys=\"" : "NumberOfCells=\"") +
       std::to_string(t) + "\">\n";
  x += std::string("      <PointData") + (normals ? " Normals=\"Normals\"" : "") + ">\n";
  if (normals)
    x += "        <DataArray type=\"Float32\" Name=\"Normals\" NumberOfComponents=\"3\" format=\"appended\" offset=\"" +
         block(12 * n) + "\"/>\n";
  for (const VertexAttribute* a : attrs)
    x += "        <DataArray type=\"Float32\" Name=\"" + xml_escaped(a->name) + "\" NumberOfComponents=\"" +
         std::to_string(a->components) + "\" format=\"appended\" offset=\"" + block(4 * a->values.size()) + "\"/>\n";
  x += "      </PointData>\n      <Points>\n";
  x += std::string("        <DataArray type=\"") + (doubles ? "Float64" : "Float32") +
       "\" Name=\"Points\" NumberOfComponents=\"3\" format=\"appended\" offset=\"" + block((doubles ? 24 : 12) * n) +
       "\"/>\n      </Points>\n";
  x += polydata ? "      <Polys>\n" : "      <Cells>\n";
  x += "        <DataArray type=\"Int64\" Name=\"connectivity\" format=\"appended\" offset=\"" + block(24 * t) + "\"/>\n";
  x += "        <DataArray type=\"Int64\" Name=\"offsets\" format=\"appended\" offset=\"" + block(8 * t) + "\"/>\n";
  if (!polydata) x += "        <DataArray type=\"UInt8\" Name=\"types\" format=\"appended\" offset=\"" + block(t) + "\"/>\n";
  x += polydata ? "      </Polys>\n" : "      </Cells>\n";
  x += std::string("    </Piece>\n  </") + kind + ">\n  <AppendedData encoding=\"raw\">\n   _";
  Bytes b(out);
  b.put(x);
  if (normals) {
    b.little_endian(uint64_t(12 * n));
    for (const Vec3& v : mesh.normals)
      for (int a = 0; a < 3; ++a) b.little_endian(float(v[a]));
  }
  for (const VertexAttribute* a : attrs) {
    b.little_endian(uint64_t(4 * a->values.size()));
    for (float v : a->values) b.little_endian(v);
  }
  b.little_endian(uint64_t((doubles ? 24 : 12) * n));
  for (const Vec3& p : P)
    for (int a = 0; a < 3; ++a) {
      if (doubles) b.little_endian(p[a]);
      else b.little_endian(float(p[a]));
    }
  b.little_endian(uint64_t(24 * t));
  for (const Triangle& tri : mesh.triangles)
    for (uint32_t v : tri) b.little_endian(int64_t(v));
  b.little_endian(uint64_t(8 * t));
  for (uint64_t i = 1; i <= t; ++i) b.little_endian(int64_t(3 * i));
  if (!polydata) {
    b.little_endian(uint64_t(t));
    for (uint64_t i = 0; i < t; ++i) b.little_endian(uint8_t(5));  // VTK_TRIANGLE
  }
  b.put("\n  </AppendedData>\n</VTKFile>\n");
  b.flush();
}

}  // namespace particlemesh::detail
