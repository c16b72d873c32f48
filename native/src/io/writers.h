// Internal: the mesh and point writers (PLY binary and ASCII, OBJ, XYZ), onto an OutputFile.
#pragma once

#include "particlemesh/core/config.h"

#include "particlemesh/io/mesh_io.h"
#include "particlemesh/io/output_file.h"

#include <string>

#include "particlemesh/core/config.h"

namespace PM_NAMESPACE::detail {

/// Whether positions go to the file as float64 rather than float32: when float32 would
/// round some coordinate by more than a millionth of the mesh's size (a mesh farther from
/// the origin than about 16 times its size: georeferenced scans; or coordinates so small
/// that float32 holds them as subnormals, below 1.2e-38), or cannot hold it at all (beyond
/// 3.4e38).
bool needs_double_positions(const std::vector<Vec3>& positions);

/// `comment` (one line, may be empty): a PLY "comment" header line, an OBJ "#" line.
void write_ply(const TriMesh& mesh, OutputFile& out, bool binary, bool normals, const std::string& comment = {});
void write_obj(const TriMesh& mesh, OutputFile& out, bool normals, const std::string& comment = {});
/// VTK legacy, BINARY (big-endian) POLYDATA: POINTS, POLYGONS, POINT_DATA with NORMALS and
/// one FIELD array per attribute; `comment` is the title line (vtk_writers.cpp).
void write_vtk(const TriMesh& mesh, OutputFile& out, bool normals, const std::string& comment = {});
/// VTK XML UnstructuredGrid (.vtu) or PolyData (.vtp), raw appended little-endian data;
/// `comment` an XML comment after the declaration.
void write_vtk_xml(const TriMesh& mesh, OutputFile& out, bool normals, bool polydata, const std::string& comment = {});
void write_xyz(const PointCloud& cloud, OutputFile& out);

}  // namespace particlemesh::detail
