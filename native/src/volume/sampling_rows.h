// Internal: the arithmetic the two block samplers (sphere_sampling.cpp for spherical kernels,
// anisotropic_sampling.cpp for ellipsoidal ones) share: integer floor and ceil, and adding a
// kernel's values to a row of 8 nodes as two 4-float vectors (GCC/Clang vector extensions:
// portable, one SSE2 / NEON operation each). Written this way because the plain loop keeps a
// branch for the clamp and stays scalar, and 8-wide vectors get their comparisons split lane by
// lane on hardware with 4-wide registers.
#pragma once

#include "particlemesh/core/config.h"

#include <cstdint>
#include <cstring>

#include "particlemesh/volume/kernel.h"

namespace PM_NAMESPACE::detail {

// floor / ceil for |v| < 2^31 without a library call (baseline x86-64 has no rounding
// instruction, and these run several times per particle and block).
inline int ifloor(double v) {
  const int i = int(v);
  return i - (double(i) > v);
}
inline int iceil(double v) {
  const int i = int(v);
  return i + (double(i) < v);
}

typedef float Float4 __attribute__((vector_size(4 * sizeof(float))));
typedef int32_t Int4 __attribute__((vector_size(4 * sizeof(int32_t))));

inline Float4 load4(const float* p) {
  Float4 v;
  std::memcpy(&v, p, sizeof v);
  return v;
}
inline void store4(float* p, Float4 v) { std::memcpy(p, &v, sizeof v); }

/// A particle's strength w split for the polynomial kernels written in t = 1 - s:
/// w g = t^2 (wa + wb t), so wa = 5w/9, wb = 4w/9 for Wyvill, wa = w for Poly4, wb = w for Poly6.
template <Kernel K>
inline void row_weights(float w, float* wa, float* wb) {
  *wa = K == Kernel::Wyvill ? w * (5.0f / 9.0f) : (K == Kernel::Poly4 ? w : 0.0f);
  *wb = K == Kernel::Wyvill ? w * (4.0f / 9.0f) : (K == Kernel::Poly6 ? w : 0.0f);
}

/// r + w g(s) for four nodes, with t = max(0, 1 - s) taken branch-free: outside the support
/// exactly 0.
template <Kernel K>
inline Float4 add_kernel(Float4 r, Float4 s, float wa, float wb) {
  Float4 t = 1.0f - s;
  t = (Float4)((Int4)t & (t > 0.0f));
  if constexpr (K == Kernel::Wyvill) r += t * t * (wa + wb * t);
  else if constexpr (K == Kernel::Poly4) r += wa * (t * t);
  else r += wb * (t * t * t);
  return r;
}

}  // namespace particlemesh::detail
