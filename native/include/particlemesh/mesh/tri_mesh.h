// The flat indexed triangle mesh that every stage produces and consumes.
#pragma once

#include "particlemesh/core/config.h"

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "particlemesh/core/vec3.h"
#include "particlemesh/mesh/point_cloud.h"

namespace PM_NAMESPACE {

/// Three vertex indices. The winding (counter-clockwise seen from outside) gives the facing.
using Triangle = std::array<uint32_t, 3>;

/// #V positions, optional #V normals, #F triangles, optional per-vertex attributes.
/// Vertices need not all be used (a triangulation keeps every input particle as a vertex,
/// so output index i is input particle i).
struct TriMesh {
  std::vector<Vec3> positions;
  std::vector<Vec3> normals;  ///< empty or one per vertex
  std::vector<Triangle> triangles;
  std::vector<VertexAttribute> attributes;
  /// Optional values per triangle corner (face-varying: a vertex on a texture seam has one
  /// per side): as VertexAttribute, with values[(3 * t + c) * components + k] for corner c of
  /// triangle t. "uv" (2 components) holds texture coordinates: OBJ's vt and PLY's texcoord
  /// face lists (MeshLab's), read and written.
  /// smooth_mesh carries every one, linearly over each input triangle.
  std::vector<VertexAttribute> corner_attributes;
  /// What read_mesh found in the file but does not carry, one line each naming it (as
  /// PointCloud::not_read): "texture coordinates (120 vt)", "face property 'red'", "element
  /// 'edge' (12)", "CELL_DATA SCALARS 'pressure'". Empty for a mesh not read from a file.
  std::vector<std::string> not_read;

  size_t vertex_count() const { return positions.size(); }
  size_t triangle_count() const { return triangles.size(); }
};

}  // namespace particlemesh
