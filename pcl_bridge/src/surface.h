// Internal: the one place where the bridge builds a surface from particles. Everything in
// the bridge (the PCL class, the CLI's PCD path through it) goes through buildSurface, so
// moving to another particlemesh surface stage is a change here only.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include <particlemesh/mesh/point_cloud.h>
#include <particlemesh/mesh/tri_mesh.h>
#include <particlemesh/surface/reconstruct.h>

namespace particlemesh_pcl::detail
{
  struct SurfaceMesh
  {
    particlemesh::TriMesh mesh;
    /// vertex_source[v] = index in the particles handed in of mesh vertex v
    std::vector<std::uint32_t> vertex_source;
    double spacing = 0;
    bool spacing_estimated = false;
    double max_edge = 0;
    particlemesh::SurfaceStats surface;  ///< zero when raw
  };

  /// The finished surface (particlemesh::reconstruct_surface), or the smallest-sphere test's
  /// exact triangle set when `raw`. @throws particlemesh::Error as the surface stage does.
  SurfaceMesh buildSurface (const particlemesh::PointCloud &particles,
                            const particlemesh::SurfaceOptions &options, bool raw);
}
