// Internal: the lengths the geometry is computed at. The triangle test, the spacing estimate
// and the plane fits form squares and fourth powers of distances; in double precision those
// stay normal numbers (no underflow to 0, no overflow to inf) for lengths between about
// 1e-75 and 1e75. A sampled sphere meshes exactly the same from 1e-60 to 1e60 and loses
// triangles at 1e-75 and 1e75 (every one at 1e-100): lengths outside [1e-50, 1e50] are
// refused with a message saying so, rather than meshed wrongly or called "coincident".
#pragma once

#include "particlemesh/core/config.h"

#include <string>

#include "core/format_number.h"
#include "particlemesh/core/error.h"

namespace PM_NAMESPACE::detail {

inline constexpr double kMinLength = 1e-50;
inline constexpr double kMaxLength = 1e50;

/// Throws InvalidInput (too small) or LimitExceeded (too large) when `length` (an extent, a
/// spacing) is outside [kMinLength, kMaxLength]; `what` says what it is ("the particle
/// spacing r0").
inline void check_length(double length, const std::string& what) {
  if (length < kMinLength)
    throw Error(Status::InvalidInput,
                what + " is " + format_number(length) +
                    ", below the 1e-50 that the geometry resolves in double precision (squares and fourth powers "
                    "of distances would underflow): scale the coordinates up");
  if (length > kMaxLength)
    throw Error(Status::LimitExceeded,
                what + " is " + format_number(length) +
                    ", above the 1e+50 that the geometry holds in double precision (squares and fourth powers of "
                    "distances would overflow): scale the coordinates down, or remove far outliers");
}

}  // namespace particlemesh::detail
