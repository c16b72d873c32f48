// Internal: the mesh and point writers (PLY binary and ASCII, OBJ, XYZ), onto an OutputFile.
#pragma once

#include "particlemesh/core/config.h"

#include "particlemesh/io/mesh_io.h"
#include "particlemesh/io/output_file.h"

namespace PM_NAMESPACE::detail {

/// Whether positions go to the file as float64 rather than float32: when float32 would
/// round some coordinate by more than a millionth of the mesh's size (a mesh farther from
/// the origin than about 16 times its size: georeferenced scans; or coordinates so small
/// that float32 holds them as subnormals, below 1.2e-38), or cannot hold it at all (beyond
/// 3.4e38).
bool needs_double_positions(const std::vector<Vec3>& positions);

void write_ply(const TriMesh& mesh, OutputFile& out, bool binary, bool normals);
void write_obj(const TriMesh& mesh, OutputFile& out, bool normals);
void write_xyz(const PointCloud& cloud, OutputFile& out);

}  // namespace particlemesh::detail
