// Internal: building a ParticleField inside a caller's progress tracker and thread arena, and
// the kernel evaluated without a run-time switch in hot loops.
#pragma once

#include "particlemesh/core/config.h"

#include <optional>

#include "core/progress_tracker.h"
#include "particlemesh/volume/field.h"

namespace PM_NAMESPACE::detail {

/// A tile's field anchored as its whole cloud's (see PolygonizeOptions::domain_min): the
/// cloud's lower corner (at or below every particle), largest radius (0: these particles')
/// and, with per-particle radii, its particle_grid_radius (0: the largest radius when
/// max_radius is given, else these particles').
struct FieldDomain {
  std::optional<Vec3> min;
  double max_radius = 0;
  double grid_radius = 0;
};

struct FieldBuilder {
  /// Resolve, validate and build. Runs in the caller's TBB arena; reports progress in
  /// [begin, end) of the overall fraction (only when the spacing has to be estimated).
  static ParticleField build(const Vec3* positions, size_t n, const FieldParams& params,
                             ProgressTracker& tracker, double begin, double end,
                             const FieldDomain& domain = {});
  static void calibrate_anisotropic_threshold(ParticleField& f, const std::vector<KernelEllipsoid>& kernels,
                                              ProgressTracker& tracker);
};

/// field_at_particles with the enclosed share measured against `threshold` instead of the
/// field's own (the default radius is decided at the default threshold, whatever T is given).
FieldAtParticles field_at_particles(const ParticleField& f, double threshold);

/// The radius / spacing ratio x at which a particle deep inside a simple cubic lattice sees
/// the field `level` (lattice_field(kernel, x, 1) = level), within [1, kMaxCalibrationRatio]:
/// what a field level at the particles says about how densely they are packed.
double lattice_ratio_of(Kernel kernel, double level);

/// g(s) and dg/ds for a kernel known at compile time (s >= 0; 0 outside the support).
template <Kernel K>
inline double kernel_value_t(double s) {
  if (!(s < 1.0)) return 0.0;
  const double t = 1.0 - s;
  if constexpr (K == Kernel::Wyvill) return t * t * (5.0 + 4.0 * t) * (1.0 / 9.0);
  else if constexpr (K == Kernel::Poly4) return t * t;
  else if constexpr (K == Kernel::Poly6) return t * t * t;
  else return kernel_value(Kernel::Blinn, s);
}

template <Kernel K>
inline double kernel_derivative_t(double s) {
  if (!(s < 1.0)) return 0.0;
  const double t = 1.0 - s;
  if constexpr (K == Kernel::Wyvill) return -t * (10.0 + 12.0 * t) * (1.0 / 9.0);
  else if constexpr (K == Kernel::Poly4) return -2.0 * t;
  else if constexpr (K == Kernel::Poly6) return -3.0 * t * t;
  else return kernel_derivative(Kernel::Blinn, s);
}

/// Call f.template operator()<K>() with the kernel as a compile-time constant.
template <class F>
decltype(auto) dispatch_kernel(Kernel kernel, F&& f) {
  switch (kernel) {
    case Kernel::Wyvill: return f.template operator()<Kernel::Wyvill>();
    case Kernel::Poly4: return f.template operator()<Kernel::Poly4>();
    case Kernel::Poly6: return f.template operator()<Kernel::Poly6>();
    case Kernel::Blinn: break;
  }
  return f.template operator()<Kernel::Blinn>();
}

}  // namespace particlemesh::detail
