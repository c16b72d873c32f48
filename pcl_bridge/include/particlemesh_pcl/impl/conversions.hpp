/*
 * Template bodies of particlemesh_pcl/conversions.h. Included by the library's
 * instantiation unit, or by users who define PCL_NO_PRECOMPILE for their own point types.
 */
#pragma once

#include <cmath>
#include <string>

#include <pcl/point_types.h>

#include <particlemesh/core/error.h>
#include <particlemesh_pcl/conversions.h>

namespace particlemesh_pcl
{
  namespace detail
  {
    inline bool
    finite3 (float a, float b, float c)
    {
      return std::isfinite (a) && std::isfinite (b) && std::isfinite (c);
    }
  }

  template <typename PointT> ConversionReport
  toParticles (const pcl::PointCloud<PointT> &cloud,
               const pcl::Indices &indices,
               particlemesh::PointCloud &particles,
               pcl::Indices &index_map)
  {
    constexpr bool kNormals = pcl::traits::has_normal_v<PointT>;
    constexpr bool kColor = pcl::traits::has_color_v<PointT>;
    constexpr bool kIntensity = pcl::traits::has_intensity_v<PointT>;

    ConversionReport report;
    report.input_points = indices.size ();
    report.width = cloud.width;
    report.height = cloud.height;
    report.organized = cloud.height > 1;

    particlemesh::PointCloud out;
    pcl::Indices map;
    out.positions.reserve (indices.size ());
    map.reserve (indices.size ());
    particlemesh::VertexAttribute color{kColorAttribute, 3, {}};
    particlemesh::VertexAttribute intensity{kIntensityAttribute, 1, {}};

    for (std::size_t k = 0; k < indices.size (); ++k)
    {
      const pcl::index_t i = indices[k];
      if (i < 0 || static_cast<std::size_t> (i) >= cloud.size ())
        throw particlemesh::Error (particlemesh::Status::InvalidArgument,
                                   "indices[" + std::to_string (k) + "] = " + std::to_string (i) +
                                   " is outside the cloud (" + std::to_string (cloud.size ()) + " points)");
      const PointT &p = cloud[i];
      if (!detail::finite3 (p.x, p.y, p.z))
      {
        ++report.invalid_points;
        continue;
      }
      map.push_back (i);
      out.positions.push_back ({p.x, p.y, p.z});
      if constexpr (kNormals)
      {
        const bool ok = detail::finite3 (p.normal_x, p.normal_y, p.normal_z) &&
                        (p.normal_x != 0.f || p.normal_y != 0.f || p.normal_z != 0.f);
        if (!ok) ++report.invalid_normals;
        out.normals.push_back ({p.normal_x, p.normal_y, p.normal_z});
      }
      if constexpr (kColor)
      {
        color.values.push_back (p.r / 255.f);
        color.values.push_back (p.g / 255.f);
        color.values.push_back (p.b / 255.f);
      }
      if constexpr (kIntensity)
        intensity.values.push_back (p.intensity);
    }
    if (report.invalid_normals > 0)
      out.normals.clear ();
    if constexpr (kColor)
      out.attributes.push_back (std::move (color));
    if constexpr (kIntensity)
      out.attributes.push_back (std::move (intensity));

    report.valid_points = out.positions.size ();
    report.has_normals = !out.normals.empty ();
    report.has_color = kColor;
    report.has_intensity = kIntensity;
    particles = std::move (out);
    index_map = std::move (map);
    return report;
  }

  template <typename PointT> ConversionReport
  toParticles (const pcl::PointCloud<PointT> &cloud,
               particlemesh::PointCloud &particles,
               pcl::Indices &index_map)
  {
    pcl::Indices all (cloud.size ());
    for (std::size_t i = 0; i < all.size (); ++i)
      all[i] = static_cast<pcl::index_t> (i);
    return toParticles (cloud, all, particles, index_map);
  }
}

#define PCL_INSTANTIATE_toParticles(T)                                                      \
  template PCL_EXPORTS particlemesh_pcl::ConversionReport particlemesh_pcl::toParticles<T> ( \
      const pcl::PointCloud<T> &, particlemesh::PointCloud &, pcl::Indices &);               \
  template PCL_EXPORTS particlemesh_pcl::ConversionReport particlemesh_pcl::toParticles<T> ( \
      const pcl::PointCloud<T> &, const pcl::Indices &, particlemesh::PointCloud &, pcl::Indices &);
