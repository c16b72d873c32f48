/*
 * Optional clean-up of real scans before triangulation, with PCL's own filters.
 *
 * The smallest-sphere triangulation wants surface particles: evenly spaced at about r0 with
 * no strays. Scans are not like that (density falls with depth, stray returns float in
 * front of surfaces, normals are missing). Each step here is off by default and switched on
 * by one field; they run in this order:
 *   1. statistical outlier removal   pcl::StatisticalOutlierRemoval (mean distance to the k
 *                                    nearest neighbours beyond mean + m * stddev)
 *   2. downsampling to a spacing     pcl::UniformSampling (the input point nearest each voxel
 *                                    centre) or pcl::VoxelGrid (each voxel's centroid, then
 *                                    the input point nearest that centroid)
 *   3. smoothing                     pcl::MovingLeastSquares: each point projected onto the
 *                                    polynomial surface fitted (weighted least squares) to
 *                                    its neighbours within a radius; takes out the scanner's
 *                                    noise across the surface
 *   4. normal estimation             pcl::NormalEstimationOMP over the k nearest neighbours,
 *                                    each normal flipped toward the viewpoint
 * Steps 1 and 2 keep a subset of the input points (downsampling never invents a point), so
 * the vertices of a mesh built from the result are input points: MeshConstruction's contract.
 * Smoothing moves them (each output point is still one input point, moved onto the fitted
 * surface, with its normal and attributes), as PCL's own MovingLeastSquares-then-triangulate
 * pipelines do: ask for it only where the noise is worth it.
 */
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include <particlemesh/mesh/point_cloud.h>

namespace particlemesh_pcl
{
  enum class Downsampling
  {
    None,             ///< keep every point
    UniformSampling,  ///< pcl::UniformSampling: per voxel, the point nearest the voxel centre
    VoxelGrid,        ///< pcl::VoxelGrid: per voxel, the point nearest the voxels' centroid
  };

  struct PreprocessOptions
  {
    // 1. statistical outlier removal (off by default)
    bool remove_outliers = false;
    int outlier_mean_k = 50;           ///< neighbours for the mean distance (PCL tutorial: 50)
    double outlier_stddev_mul = 1.0;   ///< threshold: mean + this * stddev (PCL tutorial: 1.0)

    // 2. downsampling (off by default)
    Downsampling downsampling = Downsampling::None;
    /** \brief Voxel edge in world units (the target spacing); must be > 0 when downsampling.
      * \note Voxels are indexed with 32-bit integers (as PCL does): the cloud's bounding box
      * may hold at most 2^31 voxels of this size, else the call fails with InvalidArgument. */
    double leaf_size = 0;

    // 3. smoothing (off by default)
    /** \brief pcl::MovingLeastSquares' search radius in world units, 0 = no smoothing. A few
      * times the spacing: the fit wants a dozen or more neighbours, and noise at the scale of
      * the radius is what it takes out. */
    double mls_radius = 0;
    int mls_order = 2;                 ///< the fitted polynomial's order (PCL's default: 2; 0 or 1 = a plane)

    // 4. normal estimation (off by default); replaces any normals the cloud had
    bool estimate_normals = false;
    int normal_k = 20;                 ///< neighbours for the plane fit (PCL tutorial: 20)
    float viewpoint[3] = {0.f, 0.f, 0.f};  ///< normals are flipped to face this point (the sensor)

    int threads = 0;                   ///< for normal estimation; 0 = all cores
  };

  struct PreprocessReport
  {
    std::size_t input_points = 0;
    std::size_t outliers_removed = 0;
    std::size_t downsampled_away = 0;
    std::size_t smoothed = 0;          ///< points moved onto the fitted surface
    /** \brief Points left where they were: fewer than 3 neighbours within mls_radius. */
    std::size_t smoothing_skipped = 0;
    double smoothing_mean_shift = 0;   ///< the mean distance a smoothed point moved
    double smoothing_max_shift = 0;    ///< the farthest any moved
    std::size_t output_points = 0;
    bool normals_estimated = false;    ///< the output's normals come from PCL's estimation
    /** \brief Points whose normal could not be estimated (fewer than 3 distinct neighbours).
      * If there is any, the output carries no normals at all (see ConversionReport). */
    std::size_t normals_failed = 0;
    double seconds = 0;
  };

  /** \brief Apply the switched-on steps to \a cloud in place (positions, normals and
    * attributes of the kept points, in input order).
    * \param[in,out] cloud a validated particle cloud (finite coordinates)
    * \param[in] options which steps, with their parameters
    * \param[out] kept if not null: kept[i] = index in the input \a cloud of output point i
    * \return counts per step
    * \throws particlemesh::Error(InvalidArgument) on a bad parameter (leaf_size <= 0 when
    * downsampling, mean_k < 1, normal k < 3, too many voxels, an mls_radius that is negative or
    * not finite, mls_order outside 0..5).
    * The same for any thread count (smoothing and normals are computed per point).
    */
  PreprocessReport
  preprocess (particlemesh::PointCloud &cloud, const PreprocessOptions &options,
              std::vector<std::uint32_t> *kept = nullptr);

  /** \brief True when \a options switches on at least one step. */
  bool
  anyPreprocessing (const PreprocessOptions &options);
}
