// Internal: numbers in messages, %g-like: "1e+300", "2.5e-05", "0.0421" - never the 300
// digits of std::to_string(1e300) nor the "0.000000" it makes of 1e-7.
#pragma once

#include "particlemesh/core/config.h"

#include <cstdio>
#include <string>

namespace PM_NAMESPACE::detail {

/// `v` with `digits` significant digits (default 6, as %g).
inline std::string format_number(double v, int digits = 6) {
  char s[40];
  std::snprintf(s, sizeof s, "%.*g", digits, v);
  return s;
}

}  // namespace particlemesh::detail
