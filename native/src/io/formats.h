// Internal: the file formats particlemesh reads, and what a reader returns.
//
// One table (file_formats(), in formats.cpp) maps each extension to its reader; read_mesh and
// read_point_cloud (mesh_io.cpp) look the extension up there and nowhere else. A new format
// is one reader function and one line in that table.
//
// Every reader reads its file once, front to back (FileReader), keeps coordinates exactly
// (doubles, and integer and float32 values converted exactly), and throws Error(IoError |
// FormatError) with a message that starts with the file's name in quotes and says where
// (element, line) and what is wrong. What it returns is checked once more by
// check_contents (formats.cpp): finite coordinates, indices in range, attribute sizes.
#pragma once

#include "particlemesh/core/config.h"

#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "particlemesh/mesh/point_cloud.h"
#include "particlemesh/mesh/tri_mesh.h"

namespace PM_NAMESPACE::detail {

/// What a reader found in a file.
struct FileContents {
  std::vector<Vec3> positions;
  /// Empty, or one per position. A (0, 0, 0) normal is a point without a normal (the surface
  /// stage estimates those); readers keep it as it is.
  std::vector<Vec3> normals;
  /// Polygons fanned into triangles (corners in the file's order); empty for point formats.
  std::vector<Triangle> triangles;
  /// Per-position channels: "color" (3 floats in [0, 1]) from a file's red/green/blue, and
  /// whatever named per-point values a format carries (values[point * components + c]).
  std::vector<VertexAttribute> attributes;
  /// Per triangle corner (TriMesh::corner_attributes): "uv" from OBJ's vt.
  std::vector<VertexAttribute> corner_attributes;
  /// The number of faces the file declares (before fanning): a mesh file that declares faces
  /// but yields no triangle is an error, never an empty mesh.
  uint64_t faces = 0;
  /// Per-point data the file holds that the reader does not carry (PointCloud::not_read), one
  /// line each in the order met, added with note_not_read: at most kMaxNotRead lines, the
  /// others only counted in not_read_more (a file may declare tens of thousands).
  std::vector<std::string> not_read;
  uint64_t not_read_more = 0;
};

constexpr size_t kMaxNotRead = 32;

/// Adds `what` ("point attribute 'name' (strings)") to c.not_read, once.
void note_not_read(FileContents& c, std::string what);

/// c.not_read, with a last line for the ones only counted ("and 5 more").
std::vector<std::string> not_read_lines(FileContents& c);

/// Why a file is read: for a mesh (faces wanted) or for its points (faces skipped, though
/// still walked, so that a truncated file is refused either way).
enum class ReadPurpose { Mesh, Points };

using ReadFunction = FileContents (*)(const std::string& path, ReadPurpose purpose);

struct FileFormat {
  const char* extension;  ///< lower case, with the dot: ".ply"
  const char* name;       ///< for messages and --help: "PLY"
  ReadFunction read;
  bool points;  ///< read_point_cloud reads it (particles)
  bool mesh;    ///< read_mesh reads it
};

/// Every format particlemesh reads (the one place a reader is registered).
const std::vector<FileFormat>& file_formats();

/// The format for `path`'s extension (any case), or nullptr.
const FileFormat* format_for(const std::string& path);

/// ".ply, .xyz" - the extensions read for points (points = true) or meshes.
std::string known_extensions(bool points);

/// Lower-case extension of `path`, with the dot ("" if none). The compound ".bgeo.gz",
/// ".bgeo.sc", ".geo.gz" and ".geo.sc" count as one extension.
std::string lower_extension(const std::string& path);

/// `name`, or name_2, name_3 ... when `c` already has an attribute of that name (attribute
/// names are how the C ABI and the writers address them, so they are unique).
std::string unique_attribute_name(const FileContents& c, const std::string& name);

/// Whatever the format, the particles' velocity is the channel "velocity" (the name Blender's
/// motion blur reads and --attributes velocity takes): the first 3-component channel named
/// v, vel or velocity in any case (Houdini's "v", DualSPHysics' "Vel", ParaView's "Velocity",
/// a text file's vx vy vz) is renamed so, unless a channel is already called "velocity".
void name_the_velocity(FileContents& c);

/// Which component of a vector a column or property name is: "name:k" or "name_k" (k from
/// 0; ParaView's CSV export, our PLY naming), "name_x" or "name.x" (y, z: 1, 2; any case),
/// "name[x]", "name[k]" or "name[r]" (Houdini's table export: "P[x]", "Cd[r]"), or one of "vx",
/// "vy", "vz" (the velocity, base "v"). Sets `base` and returns the index, or -1. The text
/// and PLY readers make a run of names 0, 1, .. of one base, declared in a row, one vector.
int vector_component(std::string_view name, std::string& base);

/// The shared checks on what a reader returned: positions finite (a NaN or infinite
/// coordinate names the vertex; for meshes FormatError, for points InvalidInput as
/// validate_point_cloud words it), normals and attributes sized to the positions, triangle
/// indices below the vertex count, and a file that declares faces yielding triangles.
void check_contents(const std::string& path, const FileContents& c, ReadPurpose purpose);

/// Whether a file named in another (a .pvtu's piece, a collection's frame) stays in the naming
/// file's folder or below it: relative, no '..'. `portable` receives it with Windows'
/// backslashes read as '/'.
bool path_inside_folder(const std::string& listed, std::string& portable);

/// A .pvd's (timestep, file) entries, in the listed order (vtk_xml_reader.cpp).
/// @throws Error(FormatError) when it is not a VTK collection or an entry lacks either.
std::vector<std::pair<std::string, std::string>> read_pvd_entries(const std::string& path);

// The readers (one file each).
FileContents read_ply(const std::string& path, ReadPurpose purpose);
FileContents read_obj(const std::string& path, ReadPurpose purpose);
FileContents read_off(const std::string& path, ReadPurpose purpose);
FileContents read_stl(const std::string& path, ReadPurpose purpose);
FileContents read_xyz(const std::string& path, ReadPurpose purpose);
FileContents read_prt(const std::string& path, ReadPurpose purpose);
FileContents read_las(const std::string& path, ReadPurpose purpose);
FileContents read_vtk_legacy(const std::string& path, ReadPurpose purpose);
FileContents read_vtk_xml(const std::string& path, ReadPurpose purpose);
/// Houdini's geometry in every form bgeo_reader.cpp lists (gzip- and Blosc-compressed too).
FileContents read_bgeo(const std::string& path, ReadPurpose purpose);

}  // namespace particlemesh::detail
