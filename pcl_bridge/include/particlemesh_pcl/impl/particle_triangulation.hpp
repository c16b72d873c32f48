/*
 * Template bodies of particlemesh_pcl/particle_triangulation.h. The type-dependent part is
 * only the conversion of the input; preprocessing and the surface run in the library
 * (detail::reconstructParticles), compiled once for every point type.
 */
#pragma once

#include <chrono>
#include <exception>
#include <new>

#include <pcl/console/print.h>

#include <particlemesh/core/error.h>
#include <particlemesh_pcl/impl/conversions.hpp>
#include <particlemesh_pcl/particle_triangulation.h>

namespace particlemesh_pcl
{
  template <typename PointInT> bool
  ParticleTriangulation<PointInT>::computePolygons (std::vector<pcl::Vertices> &polygons)
  {
    const auto start = std::chrono::steady_clock::now ();
    polygons.clear ();
    report_ = ReconstructionReport ();
    try
    {
      // The polygons index the input cloud, whose points stay where they are.
      if (preprocess_.mls_radius != 0)
        throw particlemesh::Error (particlemesh::Status::InvalidArgument,
                                   "smoothing (PreprocessOptions::mls_radius) would move the points the polygons "
                                   "index: run pcl::MovingLeastSquares on the cloud before setInputCloud");
      particlemesh::PointCloud particles;
      pcl::Indices index_map;
      report_.input = toParticles (*input_, *indices_, particles, index_map);

      PreprocessOptions options = preprocess_;
      for (int c = 0; c < 3; ++c)
        options.viewpoint[c] = use_sensor_origin_ ? input_->sensor_origin_[c] : viewpoint_[c];

      detail::SurfaceOutput out = detail::reconstructParticles (std::move (particles), options, surface_);

      // mesh vertex -> preprocessed particle -> valid input point -> input cloud index
      pcl::Indices to_input (out.vertex_source.size ());
      for (std::size_t v = 0; v < to_input.size (); ++v)
        to_input[v] = index_map[out.vertex_source[v]];
      toPolygons (out.mesh, to_input, polygons);

      report_.preprocessing = out.preprocessing;
      report_.vertices = out.preprocessing.output_points;
      report_.triangles = polygons.size ();
      report_.spacing = out.spacing;
      report_.spacing_estimated = out.spacing_estimated;
      report_.max_edge = out.max_edge;
      report_.surface = out.surface;
      report_.ok = true;
    }
    catch (const particlemesh::Error &e)
    {
      report_.error = e.what ();
    }
    catch (const std::bad_alloc &)
    {
      report_.error = "out of memory";
    }
    catch (const std::exception &e)
    {
      report_.error = std::string ("internal error: ") + e.what ();
    }
    report_.seconds = std::chrono::duration<double> (std::chrono::steady_clock::now () - start).count ();
    if (!report_.ok)
    {
      PCL_ERROR ("[pcl::%s::performReconstruction] Reconstruction failed: %s (spacing %g, max edge factor %g)\n",
                 getClassName ().c_str (), report_.error.c_str (), surface_.spacing, surface_.max_edge_factor);
      polygons.clear ();
    }
    return report_.ok;
  }

  template <typename PointInT> void
  ParticleTriangulation<PointInT>::performReconstruction (pcl::PolygonMesh &output)
  {
    if (!computePolygons (output.polygons))
    {
      // as pcl::GreedyProjectionTriangulation does on failure: an empty mesh
      output.cloud.width = output.cloud.height = 0;
      output.cloud.data.clear ();
    }
  }

  template <typename PointInT> void
  ParticleTriangulation<PointInT>::performReconstruction (std::vector<pcl::Vertices> &polygons)
  {
    computePolygons (polygons);
  }
}

#define PCL_INSTANTIATE_ParticleTriangulation(T) \
  template class PCL_EXPORTS particlemesh_pcl::ParticleTriangulation<T>;
