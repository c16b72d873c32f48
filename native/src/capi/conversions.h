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

/// A PM_KERNEL_* number as a Kernel (the numbers are the enumerators').
/// @throws Error(InvalidArgument) for a number that is none of them.
inline Kernel to_kernel(int32_t k) {
  const Kernel kernel = static_cast<Kernel>(k);
  validate_kernel(kernel);
  return kernel;
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
