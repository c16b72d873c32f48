#include "particlemesh/io/mesh_io.h"

#include <OpenMesh/Core/IO/IOManager.hh>
#include <OpenMesh/Core/IO/IOInstances.hh>
#include <OpenMesh/Core/System/omstream.hh>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <sstream>
#include <system_error>

#include "io/atomic_file.h"
#include "io/header_check.h"
#include "io/openmesh_adapters.h"
#include "io/xyz_format.h"
#include "particlemesh/core/error.h"

namespace particlemesh {

namespace {

namespace fs = std::filesystem;

std::string lower_extension(const std::string& path) {
  std::string ext = fs::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return char(std::tolower(c)); });
  return ext;
}

// OpenMesh's IO manager is a process-wide singleton that reports problems on its global
// error stream. Serialise access and capture the message so it ends up in our Error.
std::mutex& openmesh_io_mutex() {
  static std::mutex m;
  return m;
}

// OpenMesh reports problems on its process-wide error stream. We connect that stream to a
// buffer once (connecting and disconnecting per call leaks inside OpenMesh) and read the
// buffer back into our Error messages; OpenMesh's chatter on its log streams is silenced.
// Callers hold openmesh_io_mutex().
std::ostringstream& openmesh_error_buffer() {
  static std::ostringstream* buffer = [] {
    auto* b = new std::ostringstream;  // lives as long as OpenMesh's own stream objects
    omerr().disconnect(std::cerr);
    omerr().connect(*b);
    omlog().disable();
    omout().disable();
    return b;
  }();
  return *buffer;
}

class CaptureOpenMeshErrors {
 public:
  CaptureOpenMeshErrors() : buffer_(openmesh_error_buffer()) {
    omerr().flush();
    buffer_.str("");
  }
  std::string message() {
    omerr().flush();
    std::string s = buffer_.str();
    while (!s.empty() && std::isspace(static_cast<unsigned char>(s.back()))) s.pop_back();
    std::replace(s.begin(), s.end(), '\n', ' ');
    return s;
  }

 private:
  std::ostringstream& buffer_;
};

void require_readable(const std::string& path) {
  std::error_code ec;
  if (!fs::exists(path, ec)) throw Error(Status::IoError, "'" + path + "': no such file");
  if (fs::is_directory(path, ec)) throw Error(Status::IoError, "'" + path + "' is a folder, not a file");
  std::ifstream probe(path, std::ios::binary);
  if (!probe) throw Error(Status::IoError, "'" + path + "': cannot open for reading");
  if (fs::file_size(path, ec) == 0) throw Error(Status::FormatError, "'" + path + "' is empty");
}

detail::FlatImporter read_with_openmesh(const std::string& path, bool want_normals) {
  detail::FlatImporter importer;
  OpenMesh::IO::Options opt;
  if (want_normals) opt += OpenMesh::IO::Options::VertexNormal;
  opt += OpenMesh::IO::Options::VertexColor;  // kept by read_point_cloud as "color"
  std::lock_guard<std::mutex> lock(openmesh_io_mutex());
  CaptureOpenMeshErrors capture;
  bool ok = false;
  try {
    ok = OpenMesh::IO::IOManager().read(path, importer, opt);
  } catch (const std::exception& e) {
    throw Error(Status::FormatError, "'" + path + "': " + e.what());
  }
  if (!ok) {
    std::string why = capture.message();
    if (why.empty()) why = "not a readable mesh file";
    throw Error(Status::FormatError, "'" + path + "': " + why);
  }
  if (importer.bad_face)
    throw Error(Status::FormatError, "'" + path + "': a face refers to a vertex that does not exist");
  if (!opt.check(OpenMesh::IO::Options::VertexNormal)) importer.normals.clear();
  if (!importer.normals.empty()) importer.normals.resize(importer.positions.size());
  if (!opt.check(OpenMesh::IO::Options::VertexColor)) importer.colors.clear();
  if (!importer.colors.empty()) importer.colors.resize(3 * importer.positions.size());
  return importer;
}

void check_extension_known(const std::string& path, std::initializer_list<const char*> known) {
  const std::string ext = lower_extension(path);
  for (const char* k : known)
    if (ext == k) return;
  std::string list;
  for (const char* k : known) list += std::string(list.empty() ? "" : ", ") + k;
  throw Error(Status::FormatError,
              "'" + path + "': unsupported file type '" + ext + "' (supported: " + list + ")");
}

}  // namespace

void write_mesh(const TriMesh& mesh, const std::string& path, const WriteMeshOptions& options) {
  MeshFormat format = options.format;
  const std::string ext = lower_extension(path);
  if (format == MeshFormat::Auto) {
    if (ext == ".ply") format = MeshFormat::PlyBinary;
    else if (ext == ".obj") format = MeshFormat::Obj;
    else throw Error(Status::InvalidArgument, "'" + path + "': cannot tell the mesh format from '" + ext + "' (use .ply or .obj)");
  }
  if ((format == MeshFormat::Obj) != (ext == ".obj") || (format != MeshFormat::Obj && ext != ".ply"))
    throw Error(Status::InvalidArgument, "'" + path + "': the extension does not match the requested format");
  for (const Triangle& t : mesh.triangles)
    for (uint32_t v : t)
      if (v >= mesh.positions.size())
        throw Error(Status::InvalidArgument, "mesh has a triangle index " + std::to_string(v) +
                                                 " beyond its " + std::to_string(mesh.positions.size()) + " vertices");
  const bool normals = options.write_normals && !mesh.normals.empty() && mesh.normals.size() == mesh.positions.size();

  detail::AtomicFile file(path);
  detail::FlatExporter exporter(mesh.positions, mesh.normals, mesh.triangles, normals);
  OpenMesh::IO::Options opt;
  if (format == MeshFormat::PlyBinary) opt += OpenMesh::IO::Options::Binary;
  if (normals) opt += OpenMesh::IO::Options::VertexNormal;
  {
    // OpenMesh's writers do not check their stream: a failed write (disk full, file size
    // limit) would leave a truncated file that looks complete. So we own the stream and
    // check it once OpenMesh is done.
    std::ofstream out(file.temp_path(), std::ios::binary | std::ios::trunc);
    if (!out) throw Error(Status::IoError, "cannot write '" + path + "': " + std::strerror(errno));
    std::lock_guard<std::mutex> lock(openmesh_io_mutex());
    CaptureOpenMeshErrors capture;
    bool ok = false;
    errno = 0;
    try {
      ok = OpenMesh::IO::IOManager().write(out, format == MeshFormat::Obj ? "obj" : "ply", exporter, opt, 6);
    } catch (const std::exception& e) {
      throw Error(Status::IoError, "cannot write '" + path + "': " + e.what());
    }
    if (!ok) {
      std::string why = capture.message();
      throw Error(Status::IoError, "cannot write '" + path + "'" + (why.empty() ? "" : ": " + why));
    }
    out.flush();
    const int write_errno = errno;
    out.close();
    if (out.fail())
      throw Error(Status::IoError, "cannot write '" + path + "': " +
                                       (write_errno ? std::strerror(write_errno) : "write failed"));
  }
  file.commit();
}

TriMesh read_mesh(const std::string& path) {
  check_extension_known(path, {".ply", ".obj", ".off", ".stl"});
  require_readable(path);
  detail::check_mesh_file_header(path, lower_extension(path));
  detail::FlatImporter imp = read_with_openmesh(path, true);
  TriMesh mesh;
  mesh.positions = std::move(imp.positions);
  mesh.normals = std::move(imp.normals);
  mesh.triangles = std::move(imp.triangles);
  for (size_t i = 0; i < mesh.positions.size(); ++i)
    if (!is_finite(mesh.positions[i]))
      throw Error(Status::FormatError, "'" + path + "': vertex " + std::to_string(i) + " has a non-finite coordinate");
  for (const Vec3& n : mesh.normals)
    if (!is_finite(n)) { mesh.normals.clear(); break; }  // unusable normals are dropped, not fatal
  return mesh;
}

PointCloud read_point_cloud(const std::string& path) {
  check_extension_known(path, {".ply", ".xyz"});
  require_readable(path);
  PointCloud cloud;
  if (lower_extension(path) == ".xyz") {
    cloud = detail::read_xyz(path);
  } else {
    detail::check_mesh_file_header(path, ".ply");
    detail::FlatImporter imp = read_with_openmesh(path, true);
    cloud.positions = std::move(imp.positions);
    cloud.normals = std::move(imp.normals);
    if (!imp.colors.empty()) cloud.attributes.push_back({"color", 3, std::move(imp.colors)});
  }
  if (cloud.positions.empty()) throw Error(Status::InvalidInput, "'" + path + "' holds no points");
  try {
    validate_point_cloud(cloud);
  } catch (const Error& e) {
    throw Error(e.status(), "'" + path + "': " + e.what());
  }
  return cloud;
}

void write_point_cloud(const PointCloud& cloud, const std::string& path) {
  const std::string ext = lower_extension(path);
  if (ext == ".xyz") {
    detail::write_xyz(cloud, path);
    return;
  }
  if (ext != ".ply") throw Error(Status::InvalidArgument, "'" + path + "': point clouds are written as .ply or .xyz");
  TriMesh m;
  m.positions = cloud.positions;
  m.normals = cloud.normals;
  write_mesh(m, path, {MeshFormat::PlyBinary, true});
}

}  // namespace particlemesh
