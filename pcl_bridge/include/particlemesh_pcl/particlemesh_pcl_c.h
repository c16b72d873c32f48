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
 *  intensity the "intensity" attribute (pm_cloud_get_attribute_count and friends).
 *  `out_info` may be NULL. Failures: PM_STATUS_IO_ERROR (no such file, unreadable),
 *  PM_STATUS_FORMAT_ERROR (malformed), PM_STATUS_INVALID_INPUT (no valid point). */
PM_PCL_EXPORT pm_status pm_pcl_read_cloud(const char* path, pm_cloud** out_cloud, pm_pcl_read_info* out_info);

#ifdef __cplusplus
}
#endif

#endif /* PARTICLEMESH_PCL_C_H */
