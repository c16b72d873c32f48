#include "particlemesh/io/mesh_io.h"

#include <OpenMesh/Core/IO/IOManager.hh>
#include <OpenMesh/Core/IO/IOInstances.hh>
#include <OpenMesh/Core/System/omstream.hh>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <mutex>
#include <sstream>
#include <system_error>

#include "core/parallel.h"
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

/// Puts the coordinates (and normals) the header check read exactly in place of OpenMesh's
/// float32 ones (see detail::ExactVertices).
void use_exact_vertices(detail::FlatImporter& imp, detail::ExactVertices& exact) {
  if (!exact.positions.empty() && exact.positions.size() == imp.positions.size()) imp.positions = std::move(exact.positions);
  if (!exact.normals.empty() && exact.normals.size() == imp.normals.size()) imp.normals = std::move(exact.normals);
}

/// OpenMesh's PLY reader writes a line to std::cerr for every integer-typed coordinate it
/// cannot convert (three per vertex), whose values the header check has read exactly (see
/// detail::ExactVertices). While it reads such a file, std::cerr goes nowhere.
class SilenceCerr {
 public:
  explicit SilenceCerr(bool on) : saved_(on ? std::cerr.rdbuf(nullptr) : nullptr), on_(on) {}
  ~SilenceCerr() {
    if (!on_) return;
    std::cerr.rdbuf(saved_);
    std::cerr.clear();
  }
  SilenceCerr(const SilenceCerr&) = delete;
  SilenceCerr& operator=(const SilenceCerr&) = delete;

 private:
  std::streambuf* saved_;
  bool on_;
};

detail::FlatImporter read_with_openmesh(const std::string& path, bool want_normals, bool quiet_cerr = false) {
  detail::FlatImporter importer;
  OpenMesh::IO::Options opt;
  if (want_normals) opt += OpenMesh::IO::Options::VertexNormal;
  opt += OpenMesh::IO::Options::VertexColor;  // kept by read_point_cloud as "color"
  std::lock_guard<std::mutex> lock(openmesh_io_mutex());
  CaptureOpenMeshErrors capture;
  bool ok = false;
  try {
    SilenceCerr quiet(quiet_cerr);
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

/// Whether positions go to the file as float64: when float32 would round some coordinate by
/// more than a millionth of the mesh's size, i.e. the mesh lies farther from the origin than
/// about 16 times its size (georeferenced scans). Otherwise float32, as every tool reads.
bool needs_double_positions(const std::vector<Vec3>& positions) {
  if (positions.empty()) return false;
  Vec3 lo = positions[0], hi = positions[0];
  double largest = 0;
  for (const Vec3& p : positions) {
    lo = {std::min(lo.x, p.x), std::min(lo.y, p.y), std::min(lo.z, p.z)};
    hi = {std::max(hi.x, p.x), std::max(hi.y, p.y), std::max(hi.z, p.z)};
    largest = std::max({largest, std::abs(p.x), std::abs(p.y), std::abs(p.z)});
  }
  const double size = norm(hi - lo);
  return largest * 0x1p-24 > 1e-6 * size;  // float32 rounds by up to 2^-24 of the value
}

/// Writes a mesh with float64 positions (see needs_double_positions): OpenMesh's writers
/// write positions as float32 only. The layout is theirs otherwise (PLY: one vertex element,
/// float32 normals, faces as uchar-counted int lists; OBJ: v, vn, f a//a).
void write_double_positions(std::ostream& out, const TriMesh& mesh, MeshFormat format, bool normals) {
  const auto& P = mesh.positions;
  const auto& N = mesh.normals;
  char line[160];
  auto put = [&](int length) { out.write(line, std::streamsize(length)); };
  if (format == MeshFormat::Obj) {
    out << "# " << P.size() << " vertices, " << mesh.triangles.size() << " faces\n";
    for (const Vec3& p : P) put(std::snprintf(line, sizeof line, "v %.17g %.17g %.17g\n", p.x, p.y, p.z));
    if (normals)
      for (const Vec3& n : N) put(std::snprintf(line, sizeof line, "vn %.9g %.9g %.9g\n", n.x, n.y, n.z));
    for (const Triangle& t : mesh.triangles)
      put(normals ? std::snprintf(line, sizeof line, "f %u//%u %u//%u %u//%u\n", t[0] + 1, t[0] + 1, t[1] + 1,
                                  t[1] + 1, t[2] + 1, t[2] + 1)
                  : std::snprintf(line, sizeof line, "f %u %u %u\n", t[0] + 1, t[1] + 1, t[2] + 1));
    return;
  }
  const bool binary = format == MeshFormat::PlyBinary;
  out << "ply\nformat " << (binary ? "binary_little_endian" : "ascii") << " 1.0\nelement vertex " << P.size()
      << "\nproperty double x\nproperty double y\nproperty double z\n";
  if (normals) out << "property float nx\nproperty float ny\nproperty float nz\n";
  out << "element face " << mesh.triangles.size() << "\nproperty list uchar int vertex_indices\nend_header\n";
  for (size_t i = 0; i < P.size(); ++i) {
    if (binary) {  // a little-endian host (x86-64, aarch64), as the header says
      const double p[3] = {P[i].x, P[i].y, P[i].z};
      out.write(reinterpret_cast<const char*>(p), sizeof p);
      if (normals) {
        const float n[3] = {float(N[i].x), float(N[i].y), float(N[i].z)};
        out.write(reinterpret_cast<const char*>(n), sizeof n);
      }
    } else {
      put(std::snprintf(line, sizeof line, "%.17g %.17g %.17g", P[i].x, P[i].y, P[i].z));
      if (normals) put(std::snprintf(line, sizeof line, " %.9g %.9g %.9g", N[i].x, N[i].y, N[i].z));
      out << '\n';
    }
  }
  for (const Triangle& t : mesh.triangles) {
    if (binary) {
      char face[13];
      face[0] = 3;
      std::memcpy(face + 1, t.data(), 12);
      out.write(face, sizeof face);
    } else {
      put(std::snprintf(line, sizeof line, "3 %u %u %u\n", t[0], t[1], t[2]));
    }
  }
}

/// Binary PLY with float32 positions, the layout and bytes OpenMesh's PLY writer gives
/// (float32 normals, faces as uchar-counted int lists), built in memory on all cores and
/// written at once: OpenMesh's writer puts each value through the stream on its own, about
/// ten times slower on the million-triangle meshes that smoothing makes.
void write_float_binary_ply(std::ostream& out, const TriMesh& mesh, bool normals) {
  const auto& P = mesh.positions;
  const auto& N = mesh.normals;
  const auto& T = mesh.triangles;
  std::string header = "ply\nformat binary_little_endian 1.0\nelement vertex " + std::to_string(P.size()) +
                       "\nproperty float x\nproperty float y\nproperty float z\n";
  if (normals) header += "property float nx\nproperty float ny\nproperty float nz\n";
  header += "element face " + std::to_string(T.size()) + "\nproperty list uchar int vertex_indices\nend_header\n";
  const size_t vertex_bytes = normals ? 24 : 12, face_bytes = 13;
  std::vector<char> body(P.size() * vertex_bytes + T.size() * face_bytes);
  char* const faces = body.data() + P.size() * vertex_bytes;
  detail::parallel_blocks(P.size(), 16384, [&](size_t b, size_t e) {
    for (size_t i = b; i < e; ++i) {  // a little-endian host (x86-64, aarch64), as the header says
      float v[6] = {float(P[i].x), float(P[i].y), float(P[i].z), 0, 0, 0};
      if (normals) {
        v[3] = float(N[i].x);
        v[4] = float(N[i].y);
        v[5] = float(N[i].z);
      }
      std::memcpy(body.data() + i * vertex_bytes, v, vertex_bytes);
    }
  });
  detail::parallel_blocks(T.size(), 16384, [&](size_t b, size_t e) {
    for (size_t f = b; f < e; ++f) {
      char* d = faces + f * face_bytes;
      d[0] = 3;
      std::memcpy(d + 1, T[f].data(), 12);
    }
  });
  out.write(header.data(), std::streamsize(header.size()));
  out.write(body.data(), std::streamsize(body.size()));
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

  const bool doubles = needs_double_positions(mesh.positions);
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
      if (doubles) {
        write_double_positions(out, mesh, format, normals);
        ok = true;
      } else if (format == MeshFormat::PlyBinary) {
        write_float_binary_ply(out, mesh, normals);
        ok = true;
      } else {
        // Text (OBJ, ASCII PLY) with the 9 digits that give a float32 back (OpenMesh's
        // default of 6 moved a coordinate by up to 16 ulps).
        ok = OpenMesh::IO::IOManager().write(out, format == MeshFormat::Obj ? "obj" : "ply", exporter, opt, 9);
      }
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
  detail::ExactVertices exact;
  detail::check_mesh_file_header(path, lower_extension(path), &exact);
  detail::FlatImporter imp = read_with_openmesh(path, true, exact.integer_types);
  use_exact_vertices(imp, exact);
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
    detail::ExactVertices exact;
    detail::check_mesh_file_header(path, ".ply", &exact);
    detail::FlatImporter imp = read_with_openmesh(path, true, exact.integer_types);
    use_exact_vertices(imp, exact);
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
