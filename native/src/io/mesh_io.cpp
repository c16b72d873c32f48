#include "particlemesh/io/mesh_io.h"

#include <algorithm>
#include <string>

#include "io/formats.h"
#include "io/writers.h"
#include "particlemesh/core/error.h"
#include "particlemesh/io/frame_collection.h"

namespace PM_NAMESPACE {

namespace {

detail::FileContents read_file(const std::string& path, detail::ReadPurpose purpose) {
  const bool points = purpose == detail::ReadPurpose::Points;
  const detail::FileFormat* f = detail::format_for(path);
  if (!f || !(points ? f->points : f->mesh)) {
    const std::string ext = detail::lower_extension(path);
    if (is_frame_collection(path))
      throw Error(Status::FormatError, "'" + path + "': a collection of frames (" + ext +
                                           "), not one file of particles: read_frame_collection lists its files (the "
                                           "command line meshes every frame of it as a sequence)");
    throw Error(Status::FormatError, "'" + path + "': " +
                                         (ext.empty() ? std::string("no file extension to tell the format by")
                                                      : "unsupported file type '" + ext + "'") +
                                         " (" + (points ? "particles" : "meshes") + ": " +
                                         detail::known_extensions(points) + ")");
  }
  detail::FileContents c = f->read(path, purpose);
  detail::check_contents(path, c, purpose);
  detail::name_the_velocity(c);
  return c;
}

/// Moves what a mesh and a point cloud both hold (positions, normals, attributes) out of `c`.
template <class Vertices>
Vertices take_vertices(detail::FileContents& c) {
  Vertices v;
  v.positions = std::move(c.positions);
  v.normals = std::move(c.normals);
  v.attributes = std::move(c.attributes);
  return v;
}

}  // namespace

std::string readable_extensions(bool points) { return detail::known_extensions(points); }

bool reads_format(const std::string& path, bool points) {
  const detail::FileFormat* f = detail::format_for(path);
  return f != nullptr && (points ? f->points : f->mesh);
}

TriMesh read_mesh(const std::string& path) {
  detail::FileContents c = read_file(path, detail::ReadPurpose::Mesh);
  TriMesh mesh = take_vertices<TriMesh>(c);
  mesh.triangles = std::move(c.triangles);
  mesh.corner_attributes = std::move(c.corner_attributes);
  mesh.not_read = detail::not_read_lines(c);
  // Normals that are not finite are no normals (they are only carried, never trusted).
  for (const Vec3& n : mesh.normals)
    if (!is_finite(n)) {
      mesh.normals.clear();
      break;
    }
  return mesh;
}

PointCloud read_point_cloud(const std::string& path) {
  detail::FileContents c = read_file(path, detail::ReadPurpose::Points);
  PointCloud cloud = take_vertices<PointCloud>(c);
  cloud.not_read = detail::not_read_lines(c);
  if (cloud.positions.empty()) throw Error(Status::InvalidInput, "'" + path + "' holds no points");
  try {
    validate_point_cloud(cloud);
  } catch (const Error& e) {
    throw Error(e.status(), "'" + path + "': " + e.what());
  }
  return cloud;
}

MeshFormat mesh_output_format(const std::string& path, MeshFormat format) {
  const std::string ext = detail::lower_extension(path);
  const MeshFormat by_extension = ext == ".ply"   ? MeshFormat::PlyBinary
                                  : ext == ".obj" ? MeshFormat::Obj
                                  : ext == ".vtk" ? MeshFormat::Vtk
                                  : ext == ".vtu" ? MeshFormat::Vtu
                                  : ext == ".vtp" ? MeshFormat::Vtp
                                                  : MeshFormat::Auto;
  if (by_extension == MeshFormat::Auto) {
    if (!is_stream_output(path))
      throw Error(Status::InvalidArgument, "'" + path + "': cannot tell the mesh format from " +
                                               (ext.empty() ? std::string("a name without extension") : "'" + ext + "'") +
                                               " (use .ply, .obj, .vtk, .vtu or .vtp)");
    return format == MeshFormat::Auto ? MeshFormat::PlyBinary : format;  // a device or FIFO: PLY unless asked
  }
  if (format == MeshFormat::Auto) return by_extension;
  const bool ply = format == MeshFormat::PlyBinary || format == MeshFormat::PlyAscii;
  if (ply ? by_extension != MeshFormat::PlyBinary : format != by_extension)
    throw Error(Status::InvalidArgument, "'" + path + "': the extension does not match the requested format" +
                                             std::string(format == MeshFormat::PlyAscii ? " (ASCII is for .ply)" : ""));
  return format;
}

void write_mesh(const TriMesh& mesh, OutputFile& out, const WriteMeshOptions& options) {
  const MeshFormat format = mesh_output_format(out.path(), options.format);
  // The largest index first (a loop without branches), the message's index only if it is bad.
  uint32_t largest = 0;
  const uint32_t* index = mesh.triangles.empty() ? nullptr : mesh.triangles.data()->data();
  for (size_t i = 0; i < 3 * mesh.triangles.size(); ++i) largest = std::max(largest, index[i]);
  if (largest >= mesh.positions.size())
    for (const Triangle& t : mesh.triangles)
      for (uint32_t v : t)
        if (v >= mesh.positions.size())
          throw Error(Status::InvalidArgument, "mesh has a triangle index " + std::to_string(v) + " beyond its " +
                                                   std::to_string(mesh.positions.size()) + " vertices");
  const bool normals = options.write_normals && !mesh.normals.empty() && mesh.normals.size() == mesh.positions.size();
  switch (format) {
    case MeshFormat::Obj: detail::write_obj(mesh, out, normals, options.comment); break;
    case MeshFormat::Vtk: detail::write_vtk(mesh, out, normals, options.comment); break;
    case MeshFormat::Vtu: detail::write_vtk_xml(mesh, out, normals, false, options.comment); break;
    case MeshFormat::Vtp: detail::write_vtk_xml(mesh, out, normals, true, options.comment); break;
    default: detail::write_ply(mesh, out, format != MeshFormat::PlyAscii, normals, options.comment);
  }
}

void write_mesh(const TriMesh& mesh, const std::string& path, const WriteMeshOptions& options) {
  mesh_output_format(path, options.format);  // before creating anything
  OutputFile out(path);
  write_mesh(mesh, out, options);
  out.commit();
}

void check_point_cloud_output(const std::string& path) {
  const std::string ext = detail::lower_extension(path);
  if (ext != ".ply" && ext != ".xyz" && !is_stream_output(path))
    throw Error(Status::InvalidArgument, "'" + path + "': particles are written as .ply or .xyz");
  check_output_path(path);
}

void write_point_cloud(const PointCloud& cloud, const std::string& path) {
  const std::string ext = detail::lower_extension(path);
  if (ext != ".xyz" && ext != ".ply" && !is_stream_output(path))
    throw Error(Status::InvalidArgument, "'" + path + "': particles are written as .ply or .xyz");
  OutputFile out(path);
  write_point_cloud(cloud, out);
  out.commit();
}

void write_point_cloud(const PointCloud& cloud, OutputFile& out) {
  const std::string ext = detail::lower_extension(out.path());
  const bool xyz = ext == ".xyz" || (ext != ".ply" && out.streams());
  if (!xyz && ext != ".ply")
    throw Error(Status::InvalidArgument, "'" + out.path() + "': particles are written as .ply or .xyz");
  if (xyz) {
    detail::write_xyz(cloud, out);
  } else {
    TriMesh m;
    m.positions = cloud.positions;
    m.normals = cloud.normals;
    detail::write_ply(m, out, true, cloud.has_normals());
  }
}

}  // namespace particlemesh
