// Reading and writing meshes and point clouds.
//
// Every file is read once, front to back, by one reader per format, keeping coordinates
// exactly (double, integer and float32 values alike); every file is written through an
// OutputFile (particlemesh/io/output_file.h): complete or untouched, devices and FIFOs
// written straight through. Formats: PLY (ASCII and binary, read and written), OBJ (read and
// written), OFF and STL (read), XYZ text (points, read and written), VTK legacy .vtk and VTK
// XML .vtu / .vtp (read and written), Houdini's classic .bgeo (particles, read).
#pragma once

#include "particlemesh/core/config.h"

#include <string>

#include "particlemesh/core/export.h"
#include "particlemesh/io/output_file.h"
#include "particlemesh/mesh/point_cloud.h"
#include "particlemesh/mesh/tri_mesh.h"

namespace PM_NAMESPACE {

enum class MeshFormat {
  Auto,       ///< from the file extension: .ply -> PlyBinary, .obj -> Obj (a device or FIFO without one: PlyBinary)
  PlyBinary,  ///< binary little-endian PLY, float32 positions/normals, int32 indices
  PlyAscii,
  Obj,
  Vtk,  ///< VTK legacy, BINARY POLYDATA (.vtk)
  Vtu,  ///< VTK XML UnstructuredGrid, raw appended data (.vtu)
  Vtp,  ///< VTK XML PolyData, raw appended data (.vtp)
};

struct WriteMeshOptions {
  MeshFormat format = MeshFormat::Auto;
  bool write_normals = true;  ///< write per-vertex normals when the mesh has them
  /// One line of text carried in the file's header (PLY "comment", OBJ "#", the VTK legacy
  /// title, a VTK XML comment); empty: none.
  std::string comment;
};

/// The format a mesh written to `path` gets (Auto resolved from the extension: .ply, .obj,
/// .vtk, .vtu, .vtp; a device, FIFO or /dev/stdout without one of them gets PLY). Call it
/// before any work to refuse a bad output name early. @throws Error(InvalidArgument) for
/// another extension on a file, or one that does not match `format`.
PM_EXPORT MeshFormat mesh_output_format(const std::string& path, MeshFormat format = MeshFormat::Auto);

/// Write a mesh through a temporary file renamed into place when complete (see OutputFile):
/// a failed write never leaves a truncated file. Positions are float32 unless float32 would
/// lose them (far from the origin for their size, beyond 3.4e38, or below 1.2e-38): then
/// float64. A "color" attribute (3 floats in [0, 1]) is written as red green blue (PLY uchar;
/// OBJ "v x y z r g b"); other attributes as float properties of PLY, named "name" (one
/// component) or "name_0" .. "name_k" (characters other than letters, digits and '_' become
/// '_'), and as point-data arrays of their names in .vtk / .vtu / .vtp (OBJ: not written).
/// @throws Error(IoError | InvalidArgument) naming the file.
PM_EXPORT void write_mesh(const TriMesh& mesh, const std::string& path, const WriteMeshOptions& options = {});

/// Write a mesh's bytes into `out` (the caller commits it, with the run's other outputs).
PM_EXPORT void write_mesh(const TriMesh& mesh, OutputFile& out, const WriteMeshOptions& options = {});

/// Read a mesh (.ply, .obj, .off, .stl, .vtk, .vtu, .vtp). Polygons with more than three
/// corners are fanned.
/// A PLY file's colours come back as the "color" attribute, its other vertex properties as
/// attributes of their names, except that properties name_0, name_1, .., name_k declared one
/// after another are the one (k + 1)-component attribute "name" (as write_mesh writes a
/// vector), unless "name" is itself a property's name.
/// @throws Error(IoError | FormatError) naming the file and the problem (and the element or
///         line): a header that promises more or less than the data, a face corner beyond
///         the vertices, a NaN or infinite coordinate, a face with fewer than three corners.
PM_EXPORT TriMesh read_mesh(const std::string& path);

/// Read particles: .ply (the vertex element: x y z, optional nx ny nz, red green blue -> the
/// "color" attribute in [0, 1], other properties as attributes, name_0 .. name_k declared
/// one after another as the vector "name", as read_mesh; faces ignored), .xyz (one
/// point per line: "x y z" or "x y z nx ny nz", '#' starts a comment), .obj point clouds
/// (as MeshLab, Blender and CloudCompare export them: the v lines, "v x y z r g b" -> the
/// "color" attribute; vn lines as the normals, in order, when the file has no faces and one
/// vn per v; faces ignored), simulators' files:
/// VTK legacy .vtk (ASCII or BINARY; POLYDATA or UNSTRUCTURED_GRID; POINT_DATA arrays as
/// attributes, NORMALS as the normals), VTK XML .vtu / .vtp and parallel .pvtu / .pvtp
/// (pieces from the file's folder or below; ascii, base64, raw appended;
/// uncompressed or compressed by zlib, LZ4 or LZMA; PointData arrays as attributes),
/// lidar .las (intensity, classification, colour), Krakatoa's .prt (every channel) and Houdini's .bgeo (binary JSON or classic, plain or gzip) and ASCII .geo (point
/// attributes, "N" as the normals). Attributes are float channels: integer arrays (ids) are
/// exact up to 2^24. A (0, 0, 0) normal is kept as it is: the surface stage reads it as a
/// point without a normal.
/// The cloud is validated (see validate_point_cloud).
/// @throws Error(IoError | FormatError | InvalidInput) naming the file and line or index.
PM_EXPORT PointCloud read_point_cloud(const std::string& path);

/// The extensions read_point_cloud (points) or read_mesh reads, for messages: ".ply, .xyz".
PM_EXPORT std::string readable_extensions(bool points);

/// Whether read_mesh (points = false) or read_point_cloud (points = true) reads `path`'s
/// format, by its extension (any case); the file itself is not opened.
PM_EXPORT bool reads_format(const std::string& path, bool points);

/// Check, before any work, that particles can be written to `path` (.ply or .xyz, or a
/// device / FIFO). @throws Error(InvalidArgument).
PM_EXPORT void check_point_cloud_output(const std::string& path);

/// Write particles as .ply (binary) or .xyz (17 digits: doubles round-trip), atomically; a
/// device or FIFO without either extension gets .xyz text.
PM_EXPORT void write_point_cloud(const PointCloud& cloud, const std::string& path);

/// Write particles' bytes into `out` (the caller commits it).
PM_EXPORT void write_point_cloud(const PointCloud& cloud, OutputFile& out);

}  // namespace particlemesh
