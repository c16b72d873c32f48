/* particlemesh_pcl C entry points: what the PCL bridge reads, as particlemesh C ABI handles,
 * for hosts that bind C (the Blender add-on's ctypes binding). Plain C, no PCL type.
 *
 * The same rules as particlemesh.h: every call returns a pm_status, no C++ exception crosses,
 * outputs are untouched on failure, and pm_pcl_last_error_message() (this library's own,
 * per thread) says what went wrong, naming the file. The cloud returned is an ordinary
 * pm_cloud of libparticlemesh: read it back and free it with the pm_cloud_* functions.
 */
#ifndef PARTICLEMESH_PCL_C_H
#define PARTICLEMESH_PCL_C_H

#include <stddef.h>
#include <stdint.h>

#include "particlemesh/particlemesh.h"

#if defined(_WIN32)
#define PM_PCL_EXPORT __declspec(dllexport)
#else
#define PM_PCL_EXPORT __attribute__((visibility("default")))
#endif

#ifdef __cplusplus
extern "C" {
#endif

/** Bumped when a function or struct here changes incompatibly; appending does not bump it. */
#define PM_PCL_ABI_VERSION 1

/** What pm_pcl_read_cloud read and dropped. */
typedef struct pm_pcl_read_info {
  uint32_t struct_size;     /**< set by the caller to sizeof(pm_pcl_read_info) */
  uint64_t input_points;    /**< points in the file */
  uint64_t valid_points;    /**< particles kept: all three coordinates finite */
  uint64_t invalid_points;  /**< points dropped: a NaN or infinite coordinate (no depth) */
  uint64_t invalid_normals; /**< kept points with a NaN/Inf/zero normal (then no normals at all) */
  uint32_t width;           /**< of the file's cloud */
  uint32_t height;          /**< > 1: organized (a depth image) */
  int32_t has_normals;      /**< the cloud carries normals */
  int32_t has_color;        /**< the cloud carries "color" (3 floats in [0, 1] from rgb/rgba) */
  int32_t has_intensity;    /**< the cloud carries "intensity" (1 float, as stored) */
  float origin[3];          /**< the PCD's sensor origin (VIEWPOINT), 0 for other formats */
} pm_pcl_read_info;

PM_PCL_EXPORT uint32_t pm_pcl_abi_version(void);
/** Message of the last failed pm_pcl_* call on this thread ("" if none). */
PM_PCL_EXPORT const char* pm_pcl_last_error_message(void);

/** Read particles from `path`: .pcd (ascii, binary, binary_compressed; checked before PCL
 *  reads it) through PCL, anything else (.ply, .xyz) through libparticlemesh's reader.
 *  Points with a NaN or infinite coordinate are dropped (counted in out_info); normals are
 *  kept when every kept point has a usable one; rgb/rgba become the "color" attribute and
 *  intensity the "intensity" attribute, every other field (label, curvature, ...) an attribute
 *  of its name (pm_cloud_get_attribute_count and friends).
 *  `out_info` may be NULL. Failures: PM_STATUS_IO_ERROR (no such file, unreadable),
 *  PM_STATUS_FORMAT_ERROR (malformed), PM_STATUS_INVALID_INPUT (no valid point). */
PM_PCL_EXPORT pm_status pm_pcl_read_cloud(const char* path, pm_cloud** out_cloud, pm_pcl_read_info* out_info);

/** Which points pm_pcl_preprocess's downsampling keeps (particlemesh_pcl::Downsampling). */
#define PM_PCL_DOWNSAMPLE_NONE 0         /**< every point */
#define PM_PCL_DOWNSAMPLE_UNIFORM 1      /**< pcl::UniformSampling: per voxel, the point nearest its centre */
#define PM_PCL_DOWNSAMPLE_VOXEL_GRID 2   /**< pcl::VoxelGrid: per voxel, the point nearest the points' centroid */

/** The clean-up steps of pm_pcl_preprocess (particlemesh_pcl/preprocessing.h says what each
 *  does), every one off until switched on; they run in this order. Fill it with
 *  pm_pcl_preprocess_options_init, then change what you need. */
typedef struct pm_pcl_preprocess_options {
  uint32_t struct_size;      /**< set by pm_pcl_preprocess_options_init */
  /* 1. statistical outlier removal (pcl::StatisticalOutlierRemoval) */
  int32_t remove_outliers;   /**< non-zero: drop points whose mean distance to their k nearest is an outlier */
  int32_t outlier_mean_k;    /**< k (default 50, PCL's tutorial) */
  double outlier_stddev_mul; /**< beyond mean + this x the standard deviation (default 1) */
  /* 2. downsampling to a spacing */
  int32_t downsampling;      /**< PM_PCL_DOWNSAMPLE_* (default NONE) */
  double leaf_size;          /**< the voxels' edge, world units (> 0 when downsampling) */
  /* 3. smoothing (pcl::MovingLeastSquares) */
  double mls_radius;         /**< the fit's search radius, world units (0 = no smoothing; a few spacings) */
  int32_t mls_order;         /**< the fitted polynomial's order, 0..5 (default 2) */
  /* 4. normal estimation (pcl::NormalEstimationOMP), replacing any normals the cloud had */
  int32_t estimate_normals;  /**< non-zero: estimate them */
  int32_t normal_k;          /**< neighbours of each plane fit (default 20) */
  float viewpoint[3];        /**< each normal is flipped to face this point (the scanner) */
  int32_t threads;           /**< for the steps that run in parallel; 0 = all cores */
} pm_pcl_preprocess_options;

/** What pm_pcl_preprocess did, step by step. */
typedef struct pm_pcl_preprocess_report {
  uint32_t struct_size;          /**< set by the caller to sizeof(pm_pcl_preprocess_report) */
  uint64_t input_points;
  uint64_t outliers_removed;
  uint64_t downsampled_away;
  uint64_t smoothed;             /**< points moved onto the fitted surface */
  uint64_t smoothing_skipped;    /**< left where they were: fewer than 3 neighbours within mls_radius */
  double smoothing_mean_shift;   /**< the mean distance a smoothed point moved */
  double smoothing_max_shift;    /**< the farthest any moved */
  uint64_t output_points;
  int32_t normals_estimated;     /**< the output's normals come from the estimation */
  uint64_t normals_failed;       /**< points without an estimated normal (then the output has none) */
  double seconds;
} pm_pcl_preprocess_report;

/** Defaults: every step off, PCL's tutorial parameters. Does nothing for NULL. */
PM_PCL_EXPORT void pm_pcl_preprocess_options_init(pm_pcl_preprocess_options* options);

/** Clean up a scan before triangulating it with PCL's filters (outlier removal, downsampling,
 *  moving least squares, normal estimation: the command-line tool's --remove-outliers,
 *  --voxel-grid / --uniform-sampling, --mls and --estimate-normals). Returns a new cloud in
 *  *out_cloud: the kept points in input order, each with its normal and attributes (smoothing
 *  moves the positions only). out_kept, if not NULL, must hold the input's point count: entry
 *  i becomes the input index of output point i. `options` NULL = every step off (a copy);
 *  `out_report` may be NULL. The same output for any thread count. Failures:
 *  PM_STATUS_INVALID_ARGUMENT (a bad parameter, named), PM_STATUS_INVALID_INPUT (no point). */
PM_PCL_EXPORT pm_status pm_pcl_preprocess(const pm_cloud* cloud, const pm_pcl_preprocess_options* options,
                                          pm_cloud** out_cloud, uint32_t* out_kept,
                                          pm_pcl_preprocess_report* out_report);

#ifdef __cplusplus
}
#endif

#endif /* PARTICLEMESH_PCL_C_H */
