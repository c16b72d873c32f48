#include "io/formats.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <string>
#include <string_view>

#include "particlemesh/core/error.h"

namespace PM_NAMESPACE::detail {

const std::vector<FileFormat>& file_formats() {
  // The one table of readable formats. A new one: its reader (io/<format>_reader.cpp,
  // returning FileContents), declared in formats.h, and a line here.
  static const std::vector<FileFormat> formats{
      // extension, name, reader, points, mesh
      {".ply", "PLY", &read_ply, true, true},
      {".xyz", "XYZ text", &read_xyz, true, false},
      {".pts", "PTS text (Leica, CloudCompare)", &read_xyz, true, false},
      {".csv", "CSV text (ParaView's CSV export, spreadsheets, pandas)", &read_xyz, true, false},
      {".txt", "text points (as .xyz)", &read_xyz, true, false},
      {".obj", "Wavefront OBJ", &read_obj, true, true},
      {".off", "OFF", &read_off, true, true},
      {".stl", "STL", &read_stl, true, true},
      {".vtk", "VTK legacy", &read_vtk_legacy, true, true},
      {".vtu", "VTK XML UnstructuredGrid", &read_vtk_xml, true, true},
      {".vtp", "VTK XML PolyData", &read_vtk_xml, true, true},
      {".pvtu", "VTK XML parallel UnstructuredGrid", &read_vtk_xml, true, true},
      {".pvtp", "VTK XML parallel PolyData", &read_vtk_xml, true, true},
      {".prt", "Krakatoa PRT", &read_prt, true, false},
      {".las", "ASPRS LAS lidar", &read_las, true, false},
      {".laz", "LAZ (compressed LAS: refused with how to decompress it)", &read_las, true, false},
      {".bgeo", "Houdini bgeo", &read_bgeo, true, false},
      {".bgeo.gz", "Houdini bgeo", &read_bgeo, true, false},
      {".bhclassic", "Houdini classic bgeo", &read_bgeo, true, false},
      {".geo", "Houdini geo (ASCII JSON)", &read_bgeo, true, false},
      {".geo.gz", "Houdini geo (ASCII JSON)", &read_bgeo, true, false},
      {".bgeo.sc", "Houdini bgeo, Blosc-compressed", &read_bgeo, true, false},
      {".geo.sc", "Houdini geo (ASCII JSON), Blosc-compressed", &read_bgeo, true, false},
  };
  return formats;
}

std::string lower_extension(const std::string& path) {
  const std::filesystem::path p(path);
  std::string ext = p.extension().string();
  for (char& c : ext) c = char(std::tolower(static_cast<unsigned char>(c)));
  if (ext == ".gz" || ext == ".sc") {
    std::string inner = p.stem().extension().string();
    for (char& c : inner) c = char(std::tolower(static_cast<unsigned char>(c)));
    if (inner == ".bgeo" || inner == ".geo") return inner + ext;
  }
  return ext;
}

bool path_inside_folder(const std::string& listed, std::string& portable) {
  namespace fs = std::filesystem;
  portable = listed;
  std::replace(portable.begin(), portable.end(), '\\', '/');  // written on Windows
  const fs::path relative(portable);
  bool outside = portable.empty() || relative.is_absolute() || relative.has_root_name();
  for (const fs::path& part : relative) outside = outside || part == "..";
  return !outside;
}

void note_not_read(FileContents& c, std::string what) {
  if (std::find(c.not_read.begin(), c.not_read.end(), what) != c.not_read.end()) return;
  if (c.not_read.size() < kMaxNotRead)
    c.not_read.push_back(std::move(what));
  else
    ++c.not_read_more;
}

std::vector<std::string> not_read_lines(FileContents& c) {
  std::vector<std::string> lines = std::move(c.not_read);
  if (c.not_read_more > 0) lines.push_back("and " + std::to_string(c.not_read_more) + " more");
  return lines;
}

std::string unique_attribute_name(const FileContents& c, const std::string& name) {
  auto taken = [&](const std::string& n) {
    for (const VertexAttribute& a : c.attributes)
      if (a.name == n) return true;
    return false;
  };
  if (!taken(name)) return name;
  for (int k = 2;; ++k)
    if (!taken(name + "_" + std::to_string(k))) return name + "_" + std::to_string(k);
}

int vector_component(std::string_view name, std::string& base) {
  const bool bracket = name.size() > 3 && name.back() == ']';
  if (bracket) name.remove_suffix(1);
  const size_t cut = bracket ? name.rfind('[') : name.find_last_of(":_.");
  if (bracket && cut == std::string_view::npos) return -1;
  if (cut != std::string_view::npos && cut > 0 && cut + 1 < name.size()) {
    const std::string_view tail = name.substr(cut + 1);
    int index = -1;
    if (tail.size() == 1) {
      const char c = char(std::tolower(static_cast<unsigned char>(tail[0])));
      if (c >= 'x' && c <= 'z') index = c - 'x';
      if (bracket && (c == 'r' || c == 'g' || c == 'b')) index = c == 'r' ? 0 : c == 'g' ? 1 : 2;  // Cd[r]
    }
    if (index < 0 && name[cut] != '.' && tail.size() <= 2 &&
        std::all_of(tail.begin(), tail.end(), [](char c) { return c >= '0' && c <= '9'; }))
      index = tail.size() == 2 && tail[0] == '0' ? -1 : std::stoi(std::string(tail));
    if (index >= 0) {
      base = std::string(name.substr(0, cut));
      return index;
    }
  }
  if (name.size() == 2 && (name[0] == 'v' || name[0] == 'V')) {
    const char c = char(std::tolower(static_cast<unsigned char>(name[1])));
    if (c >= 'x' && c <= 'z') {
      base = "v";
      return c - 'x';
    }
  }
  return -1;
}

void name_the_velocity(FileContents& c) {
  for (const VertexAttribute& a : c.attributes)
    if (a.name == "velocity") return;
  for (VertexAttribute& a : c.attributes) {
    std::string n = a.name;
    for (char& ch : n) ch = char(std::tolower(static_cast<unsigned char>(ch)));
    if (a.components == 3 && (n == "v" || n == "vel" || n == "velocity")) {
      a.name = "velocity";
      return;
    }
  }
}

const FileFormat* format_for(const std::string& path) {
  const std::string ext = lower_extension(path);
  for (const FileFormat& f : file_formats())
    if (ext == f.extension) return &f;
  return nullptr;
}

std::string known_extensions(bool points) {
  std::string s;
  for (const FileFormat& f : file_formats())
    if (points ? f.points : f.mesh) s += (s.empty() ? "" : ", ") + std::string(f.extension);
  return s;
}

void check_contents(const std::string& path, const FileContents& c, ReadPurpose purpose) {
  auto fail = [&](Status s, const std::string& problem) { throw Error(s, "'" + path + "': " + problem); };
  const size_t n = c.positions.size();
  if (!c.normals.empty() && c.normals.size() != n)
    fail(Status::Internal, "the reader returned " + std::to_string(c.normals.size()) + " normals for " +
                               std::to_string(n) + " points");
  for (const VertexAttribute& a : c.attributes)
    if (a.components < 1 || a.values.size() != n * size_t(a.components))
      fail(Status::Internal, "the reader returned attribute '" + a.name + "' with " + std::to_string(a.values.size()) +
                                 " values for " + std::to_string(n) + " points");
  if (purpose == ReadPurpose::Points) return;  // validate_point_cloud names bad values as for any cloud
  static const char* const kAxis[3] = {"x", "y", "z"};
  for (size_t i = 0; i < n; ++i)
    for (int a = 0; a < 3; ++a)
      if (!std::isfinite(c.positions[i][a]))
        fail(Status::FormatError, "vertex " + std::to_string(i) + ": " + kAxis[a] + " is " +
                                      (std::isnan(c.positions[i][a]) ? "NaN" : "infinite"));
  for (size_t t = 0; t < c.triangles.size(); ++t)
    for (uint32_t v : c.triangles[t])
      if (v >= n)
        fail(Status::FormatError, "a face refers to vertex " + std::to_string(v) + ", but the file has " +
                                      std::to_string(n) + " vertices (indices from 0)");
  if (c.faces > 0 && c.triangles.empty())
    fail(Status::FormatError, "the file declares " + std::to_string(c.faces) + " faces, but none could be read");
}

}  // namespace particlemesh::detail
