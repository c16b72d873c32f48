// Preprocessing with PCL's filters and features. This is the only translation unit that
// includes PCL's filter, feature and kd-tree headers (they are slow to compile); everything
// runs on pcl::PointCloud<pcl::PointXYZ>, precompiled in PCL, whatever the caller's type.
#include <particlemesh_pcl/preprocessing.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <limits>
#include <string>
#include <thread>

#include <pcl/common/common.h>
#include <pcl/features/normal_3d_omp.h>
#include <pcl/filters/statistical_outlier_removal.h>
#include <pcl/filters/uniform_sampling.h>
#include <pcl/filters/voxel_grid.h>
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>
#include <pcl/search/kdtree.h>
#include <pcl/surface/mls.h>

#include <particlemesh/core/error.h>

namespace particlemesh_pcl
{
  namespace
  {
    using particlemesh::Error;
    using particlemesh::Status;

    /* PCL computes in float: the points less `origin` (a float keeps 7 digits, so
     * georeferenced coordinates, 5e5 m and more, would lose centimetres where they are taken as
     * they are; the steps that move points or fit planes take them about the cloud's centre). */
    pcl::PointCloud<pcl::PointXYZ>::Ptr
    toXYZ (const particlemesh::PointCloud &cloud, const particlemesh::Vec3 &origin = {})
    {
      pcl::PointCloud<pcl::PointXYZ>::Ptr out (new pcl::PointCloud<pcl::PointXYZ>);
      out->resize (cloud.size ());
      for (std::size_t i = 0; i < cloud.size (); ++i)
      {
        const particlemesh::Vec3 p = cloud.positions[i] - origin;
        (*out)[i] = pcl::PointXYZ (float (p.x), float (p.y), float (p.z));
      }
      out->width = static_cast<std::uint32_t> (cloud.size ());
      out->height = 1;
      out->is_dense = true;
      return out;
    }

    // Keep the points listed (ascending) in `keep`; compose `kept`.
    void
    subset (particlemesh::PointCloud &cloud, const pcl::Indices &keep, std::vector<std::uint32_t> &kept)
    {
      particlemesh::PointCloud out;
      out.positions.reserve (keep.size ());
      if (cloud.has_normals ())
        out.normals.reserve (keep.size ());
      std::vector<std::uint32_t> composed;
      composed.reserve (keep.size ());
      for (const pcl::index_t i : keep)
      {
        out.positions.push_back (cloud.positions[i]);
        if (cloud.has_normals ())
          out.normals.push_back (cloud.normals[i]);
        composed.push_back (kept[i]);
      }
      for (const auto &a : cloud.attributes)
      {
        particlemesh::VertexAttribute b{a.name, a.components, {}};
        b.values.reserve (keep.size () * std::size_t (a.components));
        for (const pcl::index_t i : keep)
          for (int c = 0; c < a.components; ++c)
            b.values.push_back (a.values[std::size_t (i) * a.components + c]);
        out.attributes.push_back (std::move (b));
      }
      cloud = std::move (out);
      kept = std::move (composed);
    }

    // The centre of the cloud's bounding box.
    particlemesh::Vec3
    centre (const particlemesh::PointCloud &cloud)
    {
      particlemesh::Vec3 lo = cloud.positions.front (), hi = lo;
      for (const auto &p : cloud.positions)
      {
        lo = {std::min (lo.x, p.x), std::min (lo.y, p.y), std::min (lo.z, p.z)};
        hi = {std::max (hi.x, p.x), std::max (hi.y, p.y), std::max (hi.z, p.z)};
      }
      return (lo + hi) * 0.5;
    }

    // PCL indexes voxels with 32-bit ints (VoxelGrid checks, UniformSampling silently
    // overflows): refuse a leaf too small for the cloud's extent.
    void
    checkVoxelCount (const pcl::PointCloud<pcl::PointXYZ> &cloud, double leaf)
    {
      Eigen::Vector4f lo, hi;
      pcl::getMinMax3D (cloud, lo, hi);
      double voxels = 1;
      for (int c = 0; c < 3; ++c)
        voxels *= std::floor (double (hi[c]) / leaf) - std::floor (double (lo[c]) / leaf) + 1;
      if (!(voxels <= double (std::numeric_limits<std::int32_t>::max ())))
        throw Error (Status::InvalidArgument,
                     "downsampling leaf size " + std::to_string (leaf) + " is too small for the cloud's extent (" +
                     std::to_string (voxels) + " voxels; PCL indexes at most 2^31)");
    }

    pcl::Indices
    uniformSampling (const pcl::PointCloud<pcl::PointXYZ>::Ptr &xyz, double leaf)
    {
      pcl::UniformSampling<pcl::PointXYZ> us (/*extract_removed_indices=*/true);
      us.setInputCloud (xyz);
      us.setRadiusSearch (leaf);  // the voxel edge
      pcl::PointCloud<pcl::PointXYZ> sampled;
      us.filter (sampled);
      std::vector<char> removed (xyz->size (), 0);
      for (const pcl::index_t i : *us.getRemovedIndices ())
        removed[i] = 1;
      pcl::Indices keep;
      keep.reserve (sampled.size ());
      for (std::size_t i = 0; i < removed.size (); ++i)
        if (!removed[i])
          keep.push_back (static_cast<pcl::index_t> (i));
      return keep;
    }

    pcl::Indices
    voxelGrid (const pcl::PointCloud<pcl::PointXYZ>::Ptr &xyz, double leaf)
    {
      pcl::VoxelGrid<pcl::PointXYZ> vg;
      vg.setInputCloud (xyz);
      vg.setLeafSize (float (leaf), float (leaf), float (leaf));
      pcl::PointCloud<pcl::PointXYZ> centroids;
      vg.filter (centroids);
      // MeshConstruction keeps input points as vertices: each centroid is represented by
      // the input point nearest to it (duplicates merged).
      pcl::search::KdTree<pcl::PointXYZ> tree (/*sorted=*/false);
      tree.setInputCloud (xyz);
      pcl::Indices keep;
      keep.reserve (centroids.size ());
      pcl::Indices nn (1);
      std::vector<float> d2 (1);
      for (const auto &c : centroids)
        if (tree.nearestKSearch (c, 1, nn, d2) == 1)
          keep.push_back (nn[0]);
      std::sort (keep.begin (), keep.end ());
      keep.erase (std::unique (keep.begin (), keep.end ()), keep.end ());
      return keep;
    }
  }

  bool
  anyPreprocessing (const PreprocessOptions &o)
  {
    return o.remove_outliers || o.downsampling != Downsampling::None || o.mls_radius > 0 || o.estimate_normals;
  }

  PreprocessReport
  preprocess (particlemesh::PointCloud &cloud, const PreprocessOptions &o,
              std::vector<std::uint32_t> *kept_out)
  {
    const auto start = std::chrono::steady_clock::now ();
    PreprocessReport report;
    report.input_points = cloud.size ();
    std::vector<std::uint32_t> kept (cloud.size ());
    for (std::size_t i = 0; i < kept.size (); ++i)
      kept[i] = static_cast<std::uint32_t> (i);

    if (o.remove_outliers && (o.outlier_mean_k < 1 || !std::isfinite (o.outlier_stddev_mul)))
      throw Error (Status::InvalidArgument, "outlier removal needs mean_k >= 1 and a finite stddev multiplier");
    if (o.downsampling != Downsampling::None && !(o.leaf_size > 0 && std::isfinite (o.leaf_size)))
      throw Error (Status::InvalidArgument, "downsampling needs a leaf size > 0 (got " + std::to_string (o.leaf_size) + ")");
    if (!(o.mls_radius >= 0 && std::isfinite (o.mls_radius)))
      throw Error (Status::InvalidArgument, "smoothing needs a finite radius >= 0 (got " + std::to_string (o.mls_radius) + ")");
    if (o.mls_order < 0 || o.mls_order > 5)
      throw Error (Status::InvalidArgument, "the smoothing polynomial's order must be 0 to 5 (got " + std::to_string (o.mls_order) + ")");
    if (o.estimate_normals && o.normal_k < 3)
      throw Error (Status::InvalidArgument, "normal estimation needs k >= 3 (got " + std::to_string (o.normal_k) + ")");
    if (o.threads < 0)
      throw Error (Status::InvalidArgument, "threads must be >= 0 (0 = all cores)");
    if (cloud.size () > std::size_t (std::numeric_limits<std::int32_t>::max ()))
      throw Error (Status::LimitExceeded, "PCL indexes at most 2^31 points");

    if (anyPreprocessing (o) && !cloud.positions.empty ())
    {
      if (o.remove_outliers)
      {
        auto xyz = toXYZ (cloud);
        pcl::StatisticalOutlierRemoval<pcl::PointXYZ> sor;
        sor.setInputCloud (xyz);
        sor.setMeanK (o.outlier_mean_k);
        sor.setStddevMulThresh (o.outlier_stddev_mul);
        pcl::Indices keep;
        sor.filter (keep);  // ascending input indices
        std::sort (keep.begin (), keep.end ());
        report.outliers_removed = cloud.size () - keep.size ();
        subset (cloud, keep, kept);
      }
      if (o.downsampling != Downsampling::None && !cloud.positions.empty ())
      {
        auto xyz = toXYZ (cloud);
        checkVoxelCount (*xyz, o.leaf_size);
        const pcl::Indices keep = o.downsampling == Downsampling::UniformSampling
                                      ? uniformSampling (xyz, o.leaf_size)
                                      : voxelGrid (xyz, o.leaf_size);
        report.downsampled_away = cloud.size () - keep.size ();
        subset (cloud, keep, kept);
      }
      const unsigned threads = o.threads > 0 ? unsigned (o.threads)
                                             : std::max (1u, std::thread::hardware_concurrency ());
      if (o.mls_radius > 0 && !cloud.positions.empty ())
      {
        const particlemesh::Vec3 origin = centre (cloud);
        auto xyz = toXYZ (cloud, origin);
        pcl::MovingLeastSquares<pcl::PointXYZ, pcl::PointNormal> mls;
        mls.setInputCloud (xyz);
        mls.setSearchMethod (pcl::search::KdTree<pcl::PointXYZ>::Ptr (new pcl::search::KdTree<pcl::PointXYZ> (false)));
        mls.setSearchRadius (o.mls_radius);
        mls.setPolynomialOrder (o.mls_order);
        mls.setComputeNormals (false);
        mls.setNumberOfThreads (threads);
        pcl::PointCloud<pcl::PointNormal> projected;
        mls.process (projected);
        // With several threads PCL joins the threads' outputs in the order they ran: each
        // projection goes back to its own point, so the result does not depend on it. A point
        // with fewer than 3 neighbours within the radius gets none and stays where it was.
        const pcl::PointIndicesPtr from = mls.getCorrespondingIndices ();
        if (!from || from->indices.size () != projected.size ())
          throw Error (Status::Internal, "pcl::MovingLeastSquares did not say which point each projection is of");
        double shift_sum = 0;
        for (std::size_t k = 0; k < projected.size (); ++k)
        {
          const pcl::index_t i = from->indices[k];
          const auto &q = projected[k];
          const particlemesh::Vec3 v = particlemesh::Vec3{q.x, q.y, q.z} + origin;
          if (i < 0 || std::size_t (i) >= cloud.size () || !particlemesh::is_finite (v))
            continue;
          const double shift = particlemesh::distance (v, cloud.positions[std::size_t (i)]);
          cloud.positions[std::size_t (i)] = v;
          ++report.smoothed;
          shift_sum += shift;
          report.smoothing_max_shift = std::max (report.smoothing_max_shift, shift);
        }
        report.smoothing_skipped = cloud.size () - report.smoothed;
        report.smoothing_mean_shift = report.smoothed > 0 ? shift_sum / double (report.smoothed) : 0.0;
      }
      if (o.estimate_normals && !cloud.positions.empty ())
      {
        const particlemesh::Vec3 origin = centre (cloud);
        auto xyz = toXYZ (cloud, origin);
        pcl::NormalEstimationOMP<pcl::PointXYZ, pcl::Normal> ne;
        ne.setNumberOfThreads (threads);
        ne.setInputCloud (xyz);
        ne.setSearchMethod (pcl::search::KdTree<pcl::PointXYZ>::Ptr (new pcl::search::KdTree<pcl::PointXYZ> (false)));
        ne.setKSearch (std::min<int> (o.normal_k, int (cloud.size ())));
        ne.setViewPoint (float (o.viewpoint[0] - origin.x), float (o.viewpoint[1] - origin.y),
                         float (o.viewpoint[2] - origin.z));
        pcl::PointCloud<pcl::Normal> normals;
        ne.compute (normals);
        cloud.normals.resize (cloud.size ());
        for (std::size_t i = 0; i < cloud.size (); ++i)
        {
          const auto &n = normals[i];
          const particlemesh::Vec3 v{n.normal_x, n.normal_y, n.normal_z};
          if (!particlemesh::is_finite (v) || particlemesh::squared_norm (v) == 0)
            ++report.normals_failed;
          cloud.normals[i] = v;
        }
        if (report.normals_failed > 0)
          cloud.normals.clear ();
        report.normals_estimated = report.normals_failed == 0;
      }
    }
    report.output_points = cloud.size ();
    report.seconds = std::chrono::duration<double> (std::chrono::steady_clock::now () - start).count ();
    if (kept_out)
      *kept_out = std::move (kept);
    return report;
  }
}
