// Reading and writing meshes and point clouds.
//
// Meshes go through OpenMesh's readers and writers (PLY binary/ASCII, OBJ; OFF and STL read),
// fed from our flat arrays through OpenMesh's importer/exporter interfaces, so non-manifold
// meshes (such as the seed's raw triangle set) are written and read faithfully.
#pragma once

#include <string>

#include "particlemesh/core/export.h"
#include "particlemesh/mesh/point_cloud.h"
#include "particlemesh/mesh/tri_mesh.h"

namespace particlemesh {

enum class MeshFormat {
  Auto,       ///< from the file extension: .ply -> PlyBinary, .obj -> Obj
  PlyBinary,  ///< binary little-endian PLY, float32 positions/normals, int32 indices
  PlyAscii,
  Obj,
};

struct WriteMeshOptions {
  MeshFormat format = MeshFormat::Auto;
  bool write_normals = true;  ///< write per-vertex normals when the mesh has them
};

/// Write a mesh. The file is written under a temporary name in the same folder and renamed
/// into place only when complete, so a failed write never leaves a truncated file behind.
/// @throws Error(IoError | InvalidArgument) naming the file.
PM_EXPORT void write_mesh(const TriMesh& mesh, const std::string& path,
                          const WriteMeshOptions& options = {});

/// Read a mesh (.ply, .obj, .off, .stl). Polygons with more than three corners are fanned.
/// @throws Error(IoError | FormatError) naming the file and the problem.
PM_EXPORT TriMesh read_mesh(const std::string& path);

/// Read particles: .ply (vertices and, if present, nx ny nz and red green blue -> the "color"
/// attribute, 3 floats in [0, 1]; faces ignored) or .xyz
/// (one point per line: "x y z" or "x y z nx ny nz", '#' starts a comment).
/// The cloud is validated (see validate_point_cloud).
/// @throws Error(IoError | FormatError | InvalidInput) naming the file and line or index.
PM_EXPORT PointCloud read_point_cloud(const std::string& path);

/// Write particles as .ply (binary) or .xyz, atomically (see write_mesh).
PM_EXPORT void write_point_cloud(const PointCloud& cloud, const std::string& path);

}  // namespace particlemesh
