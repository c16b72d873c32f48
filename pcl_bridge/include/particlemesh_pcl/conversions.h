/*
 * particlemesh PCL bridge: pcl::PointCloud<PointT> / pcl::PCLPointCloud2 in, particlemesh
 * clouds and meshes across, pcl::PolygonMesh / pcl::Vertices out.
 *
 * Invalid points (a NaN or Inf coordinate: what organized depth-sensor clouds hold where the
 * sensor saw nothing) are dropped and counted; every conversion that drops points fills an
 * index map so that results refer back to the input cloud's points.
 */
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include <pcl/PCLPointCloud2.h>
#include <pcl/PolygonMesh.h>
#include <pcl/Vertices.h>
#include <pcl/point_cloud.h>
#include <pcl/types.h>

#include <particlemesh/mesh/point_cloud.h>
#include <particlemesh/mesh/tri_mesh.h>

namespace particlemesh_pcl
{
  /** \brief Name of the per-vertex colour attribute: 3 floats per point, r g b in [0, 1]. */
  inline constexpr const char* kColorAttribute = "color";
  /** \brief Name of the per-vertex intensity attribute: 1 float per point, as stored. */
  inline constexpr const char* kIntensityAttribute = "intensity";

  /** \brief What a conversion into particles found in the input. */
  struct ConversionReport
  {
    std::size_t input_points = 0;    ///< points considered (the whole cloud or the given indices)
    std::size_t valid_points = 0;    ///< points kept: all three coordinates finite
    std::size_t invalid_points = 0;  ///< points dropped: a NaN or Inf coordinate
    /** \brief Kept points whose normal was NaN, Inf or zero. If there is any, the whole
      * normal channel is dropped (the surface stage then estimates normals itself), so the
      * particles never hold a mix of real and made-up normals. */
    std::size_t invalid_normals = 0;
    std::uint32_t width = 0;         ///< of the input cloud
    std::uint32_t height = 0;        ///< of the input cloud (> 1: organized)
    bool organized = false;          ///< height > 1
    bool has_normals = false;        ///< the particles carry normals
    bool has_color = false;          ///< the particles carry the "color" attribute
    bool has_intensity = false;      ///< the particles carry the "intensity" attribute
  };

  /** \brief Convert a PCL point cloud to particles: positions, normals where the point type
    * has them (normal_x/y/z), colour (rgb/rgba -> "color", 3 floats in [0, 1]) and intensity
    * ("intensity") as per-vertex attributes.
    * \tparam PointT any PCL point type with x, y, z (precompiled for pcl::PointXYZ,
    * PointNormal, PointXYZRGB, PointXYZRGBNormal and PointXYZI; define PCL_NO_PRECOMPILE for
    * others).
    * \param[in] cloud the input cloud (organized or not)
    * \param[out] particles the valid points, in input order
    * \param[out] index_map index_map[i] = index in \a cloud of particle i
    * \return what was kept and dropped
    */
  template <typename PointT> ConversionReport
  toParticles (const pcl::PointCloud<PointT> &cloud,
               particlemesh::PointCloud &particles,
               pcl::Indices &index_map);

  /** \brief As above, for the points listed in \a indices only (in that order).
    * \note An index outside the cloud throws particlemesh::Error(InvalidArgument).
    */
  template <typename PointT> ConversionReport
  toParticles (const pcl::PointCloud<PointT> &cloud,
               const pcl::Indices &indices,
               particlemesh::PointCloud &particles,
               pcl::Indices &index_map);

  /** \brief Convert a binary blob cloud (what pcl::PCDReader and the PolygonMesh hold) to
    * particles. Fields are found by name whatever their numeric type: x y z (required),
    * normal_x normal_y normal_z, rgb or rgba (packed 0x00RRGGBB), intensity; every other field
    * (a label, PCL's curvature, a descriptor of COUNT values) is an attribute of its name with
    * COUNT components ("_", PCL's padding, is skipped; a field named "color" or "intensity"
    * beside those channels becomes "color_field" / "intensity_field").
    * \throws particlemesh::Error(FormatError) if x, y or z is missing or the blob's sizes
    * are inconsistent.
    */
  ConversionReport
  toParticles (const pcl::PCLPointCloud2 &cloud,
               particlemesh::PointCloud &particles,
               pcl::Indices &index_map);

  /** \brief Triangles of \a mesh as pcl::Vertices, vertex v written as index_map[v] (the
    * point of the original cloud it came from). An empty \a index_map means identity.
    */
  void
  toPolygons (const particlemesh::TriMesh &mesh,
              const pcl::Indices &index_map,
              std::vector<pcl::Vertices> &polygons);

  /** \brief A self-contained pcl::PolygonMesh of \a mesh: its cloud has fields x y z
    * (float32), normal_x normal_y normal_z when the mesh has normals, rgb (PCL's packed
    * float) when it has the "color" attribute, intensity when it has "intensity" (PCL's PLY
    * writer knows no other field); polygons are the triangles. pcl::io::savePLYFile and PCL's
    * viewers read it.
    */
  void
  toPolygonMesh (const particlemesh::TriMesh &mesh, pcl::PolygonMesh &output);

  /** \brief A particlemesh mesh from a pcl::PolygonMesh: positions, normals and colour
    * (as in toParticles, but keeping every point so polygon indices stay valid; invalid
    * points keep their NaN coordinates), polygons with more than three corners fanned.
    * \throws particlemesh::Error(FormatError) on a missing coordinate field or a polygon
    * index outside the cloud.
    */
  void
  fromPolygonMesh (const pcl::PolygonMesh &input, particlemesh::TriMesh &mesh);
}

#ifdef PCL_NO_PRECOMPILE
#include <particlemesh_pcl/impl/conversions.hpp>
#endif
