/*
 * particlemesh in PCL's surface-class family: a drop-in for pcl::GreedyProjectionTriangulation.
 */
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include <pcl/pcl_macros.h>
#include <pcl/surface/reconstruction.h>

#include <particlemesh/mesh/point_cloud.h>
#include <particlemesh/mesh/tri_mesh.h>
#include <particlemesh/surface/reconstruct.h>
#include <particlemesh_pcl/conversions.h>
#include <particlemesh_pcl/preprocessing.h>

namespace particlemesh_pcl
{
  /** \brief What the last reconstruct() call did (getReport()). */
  struct ReconstructionReport
  {
    bool ok = false;                 ///< false: the output is empty and \a error says why
    std::string error;
    ConversionReport input;          ///< points considered, invalid (NaN) points dropped, ...
    PreprocessReport preprocessing;  ///< outliers removed, downsampled away, normals estimated
    std::size_t vertices = 0;        ///< points the surface was built on
    std::size_t triangles = 0;
    double spacing = 0;              ///< particle spacing r0 used (world units)
    bool spacing_estimated = false;  ///< r0 was the median nearest-neighbour distance
    double max_edge = 0;             ///< longest allowed edge L = max edge factor * r0
    particlemesh::SurfaceStats surface;  ///< holes filled / left open, unused points, ... (zero when raw)
    double seconds = 0;              ///< wall time of the whole call
  };

  /** \brief Settings of the surface step, shared by the class and the CLI. */
  struct SurfaceSettings
  {
    double spacing = 0;              ///< r0 in world units, 0 = estimate
    double max_edge_factor = 2.0;    ///< L = factor * r0 (Tonnesen's default: 2)
    int threads = 0;                 ///< 0 = all cores; never changes the output
    std::size_t max_neighbors = 256; ///< see particlemesh::TriangulateOptions::max_neighbors
    double normal_angle = 120.0;     ///< co-normality limit, degrees (SurfaceOptions::normal_angle)
    std::size_t fill_holes = 100;    ///< largest boundary loop filled, edges (SurfaceOptions::fill_holes)
    std::size_t min_component_triangles = 0; ///< pieces of fewer triangles removed (SurfaceOptions::min_component_triangles)
    bool raw = false;                ///< the smallest-sphere test's exact triangle set instead of the surface
    bool local_spacing = true;       ///< each point's own edge limit (SurfaceOptions::local_spacing)
    bool use_viewpoint = true;       ///< keep depth jumps seen from the viewpoint open (SurfaceOptions::viewpoint)
  };

  namespace detail
  {
    /** \brief Result of the type-independent part of ParticleTriangulation. */
    struct SurfaceOutput
    {
      particlemesh::TriMesh mesh;
      /** \brief vertex_source[v] = index into the particles handed in of mesh vertex v. */
      std::vector<std::uint32_t> vertex_source;
      PreprocessReport preprocessing;
      particlemesh::SurfaceStats surface;
      double spacing = 0;
      bool spacing_estimated = false;
      double max_edge = 0;
    };

    /** \brief Preprocess (as switched on), then build the surface on \a particles.
      * Compiled once, in the library, for every point type.
      * \throws particlemesh::Error */
    SurfaceOutput
    reconstructParticles (particlemesh::PointCloud particles,
                          const PreprocessOptions &preprocessing,
                          const SurfaceSettings &surface);
  }

  /** \brief ParticleTriangulation builds a surface on the input points from the
    * smallest-sphere test of Tonnesen's thesis (chapter 5, section 5.2.3): triangle (i, j, k)
    * is a candidate when its edges are at most L = max edge factor x spacing and no other point
    * lies inside the smallest sphere enclosing it; particlemesh::reconstruct_surface then keeps
    * a consistently oriented 2-manifold of them (normals, co-normality, manifold extraction,
    * small-hole filling, closed parts facing outward). Every output vertex is an input point,
    * so it is a pcl::MeshConstruction like pcl::GreedyProjectionTriangulation, and replaces it
    * without other changes:
    * \code
    * particlemesh_pcl::ParticleTriangulation<pcl::PointNormal> pt;   // was: GreedyProjectionTriangulation
    * pt.setInputCloud (cloud_with_normals);
    * pt.setSearchMethod (tree2);        // accepted, not needed: particlemesh uses its own grid
    * pt.reconstruct (triangles);        // pcl::PolygonMesh: cloud = the input, polygons index it
    * \endcode
    *
    * Invalid points (NaN/Inf coordinates, e.g. an organized depth frame's holes) are
    * skipped and counted; the polygons index the original cloud (organized or not).
    * Optional preprocessing for real scans (off by default, one switch each; see
    * particlemesh_pcl/preprocessing.h): statistical outlier removal, uniform-sampling or
    * voxel-grid downsampling to a target spacing, normal estimation toward a viewpoint.
    *
    * \note Normals: the point type's normals (or those of setEstimateNormals) decide which way
    * the surface faces; its tangent planes come from its own plane fits. Normals flipped
    * toward a viewpoint are consistent for a single view (a depth frame), not around a closed
    * object seen from outside (they face inward on its far side): such normals are found
    * inconsistent by their flip along the silhouette, whatever the cloud's size, and then only
    * vote which way each piece of a spanning tree's orientation faces.
    *
    * Failure follows PCL: a PCL_ERROR message "[pcl::ParticleTriangulation::...] ..." and an
    * empty output; getReport () says what happened.
    *
    * \tparam PointInT a point type with x, y, z; normals, rgb and intensity are used when
    * present. Precompiled for pcl::PointXYZ, PointNormal, PointXYZRGB, PointXYZRGBNormal,
    * PointXYZI; define PCL_NO_PRECOMPILE for others.
    * \ingroup surface
    */
  template <typename PointInT>
  class ParticleTriangulation : public pcl::MeshConstruction<PointInT>
  {
    public:
      using Ptr = pcl::shared_ptr<ParticleTriangulation<PointInT> >;
      using ConstPtr = pcl::shared_ptr<const ParticleTriangulation<PointInT> >;

      using pcl::MeshConstruction<PointInT>::input_;
      using pcl::MeshConstruction<PointInT>::indices_;
      using pcl::MeshConstruction<PointInT>::tree_;
      using pcl::MeshConstruction<PointInT>::check_tree_;

      using PointCloudIn = pcl::PointCloud<PointInT>;
      using PointCloudInPtr = typename PointCloudIn::Ptr;
      using PointCloudInConstPtr = typename PointCloudIn::ConstPtr;

      /** \brief Empty constructor. No kd-tree is built: particlemesh searches neighbours
        * with its own uniform grid (a tree given to setSearchMethod is accepted and unused). */
      ParticleTriangulation ()
      {
        check_tree_ = false;
      }

      ~ParticleTriangulation () override = default;

      /** \brief Set the particle spacing r0 in world units; 0 (default) estimates it as the
        * median nearest-neighbour distance of the points, or, when downsampling is on, takes
        * the downsampling leaf size.
        * \note r0 x the max edge factor limits the maximum edge length! */
      inline void
      setSpacing (double spacing) { surface_.spacing = spacing; }

      /** \brief Get the particle spacing (0 = estimated). */
      inline double
      getSpacing () const { return (surface_.spacing); }

      /** \brief Set the longest allowed edge as a multiple of the spacing (default 2,
        * Tonnesen's value). Larger bridges wider gaps and costs more. */
      inline void
      setMaxEdgeFactor (double factor) { surface_.max_edge_factor = factor; }

      /** \brief Get the longest allowed edge as a multiple of the spacing. */
      inline double
      getMaxEdgeFactor () const { return (surface_.max_edge_factor); }

      /** \brief Set the number of threads (0, default: all cores). The output is the same
        * for any value. */
      inline void
      setNumberOfThreads (unsigned int threads) { surface_.threads = static_cast<int> (threads); preprocess_.threads = static_cast<int> (threads); }

      /** \brief Get the number of threads (0 = all cores). */
      inline unsigned int
      getNumberOfThreads () const { return (static_cast<unsigned int> (surface_.threads)); }

      /** \brief Fail if a point has more than this many neighbours within the longest edge
        * (default 256): a sign the points are far denser than the spacing. */
      inline void
      setMaximumNearestNeighbors (std::size_t nnn) { surface_.max_neighbors = nnn; }

      /** \brief Get the neighbour limit. */
      inline std::size_t
      getMaximumNearestNeighbors () const { return (surface_.max_neighbors); }

      /** \brief Set the co-normality limit in degrees (default 120): a triangle whose corner
        * normals disagree by more is not surface (keeps sheets that face each other apart). */
      inline void
      setNormalAngle (double degrees) { surface_.normal_angle = degrees; }

      /** \brief Get the co-normality limit in degrees. */
      inline double
      getNormalAngle () const { return (surface_.normal_angle); }

      /** \brief Set the largest boundary loop, in edges, that may be filled (default 100;
        * 0 fills none). Only holes narrower than 1.5 x the longest edge are filled: the real
        * openings of a scan stay open whatever this is. */
      inline void
      setMaximumHoleSize (std::size_t edges) { surface_.fill_holes = edges; }

      /** \brief Get the largest boundary loop that may be filled. */
      inline std::size_t
      getMaximumHoleSize () const { return (surface_.fill_holes); }

      /** \brief Remove every piece of the surface with fewer than this many triangles (the
        * stray triangles a scan leaves among its rows; default 0 keeps every piece). Their
        * points are then in no triangle. */
      inline void
      setMinimumComponentTriangles (std::size_t triangles) { surface_.min_component_triangles = triangles; }

      /** \brief Get the smallest piece, in triangles, that is kept (0: every piece). */
      inline std::size_t
      getMinimumComponentTriangles () const { return (surface_.min_component_triangles); }

      /** \brief Give each point its own longest edge from the spacing of the points around it
        * (default true): unevenly sampled scans (a depth camera's samples spread with the
        * distance) mesh whole. Within 15 % of r0 a point's spacing is r0, at most it is 3 r0,
        * and r0 (setSpacing, or estimated) scales them. false: one longest edge, r0 x the max
        * edge factor, for every point. */
      inline void
      setLocalSpacing (bool enable) { surface_.local_spacing = enable; }

      /** \brief Does each point get its own longest edge? */
      inline bool
      getLocalSpacing () const { return (surface_.local_spacing); }

      /** \brief Keep the depth jumps seen from the viewpoint (the input's sensor_origin_, or
        * setNormalViewPoint) open (default true): no triangle gets an edge within 12.5 degrees
        * of the view ray through it. Taken only where the points look scanned from there (most
        * of their planes face it well below grazing angles): a default origin an object was
        * never scanned from is ignored (getReport ().surface.viewpoint_used). */
      inline void
      setUseViewPoint (bool enable) { surface_.use_viewpoint = enable; }

      /** \brief Are depth jumps seen from the viewpoint kept open? */
      inline bool
      getUseViewPoint () const { return (surface_.use_viewpoint); }

      /** \brief Return the exact triangle set of Tonnesen's smallest-sphere test (default
        * false): every triangle that passes it, unoriented and not a manifold (overlapping pairs on
        * quads). For study and comparison; the default is the finished surface. */
      inline void
      setRawTriangulation (bool raw) { surface_.raw = raw; }

      /** \brief Is the raw triangle set returned? */
      inline bool
      getRawTriangulation () const { return (surface_.raw); }

      /** \brief Statistical outlier removal before meshing (default off).
        * \param[in] enable switch
        * \param[in] mean_k neighbours for the mean distance (PCL tutorial: 50)
        * \param[in] stddev_mul drop points whose mean distance exceeds mean + stddev_mul * stddev */
      inline void
      setRemoveOutliers (bool enable, int mean_k = 50, double stddev_mul = 1.0)
      {
        preprocess_.remove_outliers = enable;
        preprocess_.outlier_mean_k = mean_k;
        preprocess_.outlier_stddev_mul = stddev_mul;
      }

      /** \brief Is outlier removal on? */
      inline bool
      getRemoveOutliers () const { return (preprocess_.remove_outliers); }

      /** \brief Downsample to a target spacing before meshing (default Downsampling::None).
        * \param[in] method UniformSampling or VoxelGrid (None switches it off)
        * \param[in] leaf_size voxel edge in world units (> 0). Unless setSpacing gives one,
        * it is also the spacing r0 of the triangulation: a voxel sampling's median
        * nearest-neighbour distance is well below the voxel edge, and an edge limit from it
        * would leave gaps. */
      inline void
      setDownsampling (Downsampling method, double leaf_size = 0)
      {
        preprocess_.downsampling = method;
        preprocess_.leaf_size = leaf_size;
      }

      /** \brief Get the downsampling method. */
      inline Downsampling
      getDownsampling () const { return (preprocess_.downsampling); }

      /** \brief Get the downsampling voxel edge. */
      inline double
      getDownsamplingLeafSize () const { return (preprocess_.leaf_size); }

      /** \brief Estimate normals with PCL before meshing (default off), replacing the
        * point type's own normals. They are flipped toward the viewpoint, by default the
        * input cloud's sensor_origin_ (see setNormalViewPoint).
        * \param[in] enable switch
        * \param[in] k neighbours for the plane fit (PCL tutorial: 20) */
      inline void
      setEstimateNormals (bool enable, int k = 20)
      {
        preprocess_.estimate_normals = enable;
        preprocess_.normal_k = k;
      }

      /** \brief Is normal estimation on? */
      inline bool
      getEstimateNormals () const { return (preprocess_.estimate_normals); }

      /** \brief Flip estimated normals toward this point instead of the sensor origin. */
      inline void
      setNormalViewPoint (float vpx, float vpy, float vpz)
      {
        viewpoint_[0] = vpx; viewpoint_[1] = vpy; viewpoint_[2] = vpz;
        use_sensor_origin_ = false;
      }

      /** \brief Flip estimated normals toward the input cloud's sensor_origin_ (default). */
      inline void
      useSensorOriginAsViewPoint () { use_sensor_origin_ = true; }

      /** \brief All preprocessing settings at once. */
      inline void
      setPreprocessOptions (const PreprocessOptions &options) { preprocess_ = options; }

      /** \brief Get the preprocessing settings. */
      inline const PreprocessOptions &
      getPreprocessOptions () const { return (preprocess_); }

      /** \brief What the last reconstruct () did: counts, spacing used, the error if any. */
      inline const ReconstructionReport &
      getReport () const { return (report_); }

      /** \brief The class name, for PCL's messages. */
      std::string
      getClassName () const override { return ("ParticleTriangulation"); }

    protected:
      /** \brief Triangulate into output.polygons (output.cloud already holds the input). */
      void
      performReconstruction (pcl::PolygonMesh &output) override;

      /** \brief Triangulate into polygons (indices into the input cloud). */
      void
      performReconstruction (std::vector<pcl::Vertices> &polygons) override;

    private:
      /** \brief The shared body: true on success; on failure PCL_ERROR and false. */
      bool
      computePolygons (std::vector<pcl::Vertices> &polygons);

      SurfaceSettings surface_;
      PreprocessOptions preprocess_;
      float viewpoint_[3] = {0.f, 0.f, 0.f};
      bool use_sensor_origin_ = true;
      ReconstructionReport report_;
  };
}

#ifdef PCL_NO_PRECOMPILE
#include <particlemesh_pcl/impl/particle_triangulation.hpp>
#endif
