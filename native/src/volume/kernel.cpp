#include "particlemesh/volume/kernel.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <string>

namespace PM_NAMESPACE {

void validate_kernel(Kernel kernel) {
  switch (kernel) {
    case Kernel::Wyvill:
    case Kernel::Poly4:
    case Kernel::Poly6:
    case Kernel::Blinn:
      return;
  }
  throw Error(Status::InvalidArgument,
              "kernel is " + std::to_string(int32_t(kernel)) + " (must be 0 wyvill, 1 poly4, 2 poly6 or 3 blinn)");
}

const char* kernel_name(Kernel kernel) {
  switch (kernel) {
    case Kernel::Wyvill: return "wyvill";
    case Kernel::Poly4: return "poly4";
    case Kernel::Poly6: return "poly6";
    case Kernel::Blinn: return "blinn";
  }
  return "unknown";
}

Kernel kernel_from_name(std::string_view name) {
  std::string lower(name);
  std::transform(lower.begin(), lower.end(), lower.begin(), [](unsigned char c) { return char(std::tolower(c)); });
  for (Kernel k : {Kernel::Wyvill, Kernel::Poly4, Kernel::Poly6, Kernel::Blinn})
    if (lower == kernel_name(k)) return k;
  throw Error(Status::InvalidArgument,
              "unknown kernel '" + std::string(name) + "' (use wyvill, poly4, poly6 or blinn)");
}

double kernel_inverse(Kernel kernel, double value) {
  validate_kernel(kernel);
  if (!(value >= 0.0 && value <= 1.0))
    throw Error(Status::InvalidArgument,
                "kernel_inverse: value must be in [0, 1], got " + std::to_string(value));
  if (value == 0.0) return 1.0;
  if (value == 1.0) return 0.0;
  switch (kernel) {
    case Kernel::Poly4: return 1.0 - std::sqrt(value);
    case Kernel::Poly6: return 1.0 - std::cbrt(value);
    case Kernel::Blinn:
      return std::clamp(-std::log(value * (1.0 - kBlinnTolerance) + kBlinnTolerance) / kBlinnExponent, 0.0, 1.0);
    case Kernel::Wyvill: {
      // g = t^2 (5 + 4t) / 9 with t = 1 - s, increasing in t on [0, 1]: Newton in t,
      // kept inside a shrinking bracket.
      double lo = 0.0, hi = 1.0, t = std::sqrt(value);
      for (int it = 0; it < 100; ++it) {
        const double g = t * t * (5.0 + 4.0 * t) / 9.0 - value;
        if (g > 0) hi = t; else lo = t;
        const double dg = t * (10.0 + 12.0 * t) / 9.0;
        double next = dg > 0 ? t - g / dg : 0.5 * (lo + hi);
        if (!(next > lo && next < hi)) next = 0.5 * (lo + hi);
        if (std::abs(next - t) < 1e-16 || hi - lo < 1e-16) {
          t = next;
          break;
        }
        t = next;
      }
      return 1.0 - t;
    }
  }
  return 1.0;
}

}  // namespace particlemesh
