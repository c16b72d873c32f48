// Internal: what the C entry points convert the same way: the C progress callback into a
// ProgressCallback, a C kernel number into a Kernel, 3-vectors into caller memory.
#pragma once

#include "particlemesh/core/config.h"

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "particlemesh/core/error.h"
#include "particlemesh/core/progress.h"
#include "particlemesh/core/vec3.h"
#include "particlemesh/particlemesh.h"
#include "particlemesh/volume/kernel.h"

namespace PM_NAMESPACE::capi {

/// The C callback as a ProgressCallback (empty for NULL): a non-zero return cancels.
inline ProgressCallback wrap_progress(pm_progress_fn fn, void* user) {
  if (fn == nullptr) return {};
  return [fn, user](std::string_view stage, double fraction) {
    const std::string s(stage);
    return fn(user, s.c_str(), fraction) == 0;
  };
}

/// Line `index` of what a reader did not carry (PointCloud::not_read, TriMesh::not_read), for
/// pm_cloud_get_not_read and pm_mesh_get_not_read: valid while the list lives.
/// @throws Error(InvalidArgument) for an index past the last line.
inline const char* not_read_line(const std::vector<std::string>& lines, size_t index) {
  if (index >= lines.size())
    throw Error(Status::InvalidArgument, "index " + std::to_string(index) + " is out of range: " +
                                             std::to_string(lines.size()) + " lines name what was not read");
  return lines[index].c_str();
}

/// A PM_KERNEL_* number as a Kernel (the numbers are the enumerators').
/// @throws Error(InvalidArgument) for a number that is none of them.
inline Kernel to_kernel(int32_t k) {
  const Kernel kernel = static_cast<Kernel>(k);
  validate_kernel(kernel);
  return kernel;
}

/// The kernel settings pm_polygonize_options and pm_field_options share (the same field names)
/// from those of PolygonizeOptions or FieldParams (`d`: kernel, radius, threshold, anisotropy).
template <class COptions, class Settings>
void kernel_settings_to_c(const Settings& d, COptions* o) {
  o->kernel = int32_t(d.kernel);
  o->radius = d.radius;
  o->threshold = d.threshold;
  o->anisotropic = d.anisotropy.enabled ? 1 : 0;
  o->aniso_neighbor_radius = d.anisotropy.neighbor_radius;
  o->aniso_max_stretch = d.anisotropy.max_stretch;
  o->aniso_min_neighbors = d.anisotropy.min_neighbors;
  o->aniso_smoothing = d.anisotropy.smoothing;
}

/// The inverse of kernel_settings_to_c, with the per-particle radii and strengths (either
/// NULL, or one value for each of `count` particles).
/// @throws Error(InvalidArgument) for an unknown kernel number.
template <class COptions, class Settings>
void kernel_settings_from_c(const COptions& o, const double* radii, const double* strengths, size_t count,
                            Settings* p) {
  p->kernel = to_kernel(o.kernel);
  p->radius = o.radius;
  p->threshold = o.threshold;
  p->anisotropy.enabled = o.anisotropic != 0;
  p->anisotropy.neighbor_radius = o.aniso_neighbor_radius;
  p->anisotropy.max_stretch = o.aniso_max_stretch;
  p->anisotropy.min_neighbors = o.aniso_min_neighbors;
  p->anisotropy.smoothing = o.aniso_smoothing;
  if (radii) p->radii.assign(radii, radii + count);
  if (strengths) p->strengths.assign(strengths, strengths + count);
}

/// @throws Error(InvalidArgument) when caller memory for `capacity` items is short of `needed`.
inline void check_capacity(size_t capacity, size_t needed, const char* what) {
  if (capacity < needed)
    throw Error(Status::InvalidArgument, "capacity " + std::to_string(capacity) + " is less than the " +
                                             std::to_string(needed) + " " + what);
}

/// Copies 3-vectors into caller memory of `capacity` items (3 values each), as T; `what` names
/// the items in the error ("points", "vertices").
template <class T>
void copy_vec3s(const std::vector<Vec3>& v, T* out, size_t capacity, const char* what) {
  check_capacity(capacity, v.size(), what);
  for (size_t i = 0; i < v.size(); ++i) {
    out[3 * i] = T(v[i].x);
    out[3 * i + 1] = T(v[i].y);
    out[3 * i + 2] = T(v[i].z);
  }
}

}  // namespace particlemesh::capi
