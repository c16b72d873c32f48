// The type-independent body of ParticleTriangulation and its precompiled instantiations.
#include <pcl/impl/instantiate.hpp>
#include <pcl/point_types.h>

#include <particlemesh_pcl/particle_triangulation.h>
#include <particlemesh_pcl/impl/particle_triangulation.hpp>

#include <particlemesh/mesh/point_cloud.h>

#include "surface.h"

namespace particlemesh_pcl::detail
{
  SurfaceOutput
  reconstructParticles (particlemesh::PointCloud particles, const PreprocessOptions &preprocessing,
                        const SurfaceSettings &surface)
  {
    particlemesh::validate_point_cloud (particles);
    SurfaceOutput out;
    std::vector<std::uint32_t> kept;
    out.preprocessing = preprocess (particles, preprocessing, &kept);
    particlemesh::SurfaceOptions options;
    // Downsampled to a target spacing: that is r0 (the median nearest-neighbour distance of
    // a voxel sampling is well below the voxel edge, and an L from it leaves gaps).
    options.spacing = surface.spacing > 0 || preprocessing.downsampling == Downsampling::None
                          ? surface.spacing
                          : preprocessing.leaf_size;
    options.max_edge_factor = surface.max_edge_factor;
    options.threads = surface.threads;
    options.max_neighbors = surface.max_neighbors;
    options.normal_angle = surface.normal_angle;
    options.fill_holes = surface.fill_holes;
    options.min_component_triangles = surface.min_component_triangles;
    options.local_spacing = surface.local_spacing;
    options.has_viewpoint = surface.use_viewpoint;
    options.viewpoint = {preprocessing.viewpoint[0], preprocessing.viewpoint[1], preprocessing.viewpoint[2]};
    SurfaceMesh s = buildSurface (particles, options, surface.raw);
    out.vertex_source.resize (s.vertex_source.size ());
    for (std::size_t v = 0; v < s.vertex_source.size (); ++v)
      out.vertex_source[v] = kept[s.vertex_source[v]];
    out.mesh = std::move (s.mesh);
    out.spacing = s.spacing;
    out.spacing_estimated = s.spacing_estimated;
    out.max_edge = s.max_edge;
    out.surface = s.surface;
    return out;
  }
}

#define PM_PCL_POINT_TYPES \
  (pcl::PointXYZ)(pcl::PointNormal)(pcl::PointXYZRGB)(pcl::PointXYZRGBNormal)(pcl::PointXYZI)
PCL_INSTANTIATE (ParticleTriangulation, PM_PCL_POINT_TYPES)
