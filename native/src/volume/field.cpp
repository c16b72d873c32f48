#include "particlemesh/volume/field.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "core/parallel.h"
#include "core/progress_tracker.h"
#include "particlemesh/core/error.h"
#include "spatial/spacing_impl.h"
#include "volume/field_impl.h"

namespace particlemesh {

namespace {

std::string num(double v) {
  if (std::isnan(v)) return "NaN";
  if (std::isinf(v)) return v > 0 ? "inf" : "-inf";
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.17g", v);
  return buf;
}

// Integral of g(|u|^2) over the unit ball: 4 pi int_0^1 g(r^2) r^2 dr (Simpson, 4096 steps;
// the integrand is smooth on [0, 1], so this is exact to ~1e-13 for every kernel).
double kernel_ball_integral(Kernel kernel) {
  const int n = 4096;
  double sum = 0;
  for (int i = 0; i <= n; ++i) {
    const double r = double(i) / n;
    const double f = kernel_value(kernel, r * r) * r * r;
    sum += f * (i == 0 || i == n ? 1.0 : (i % 2 ? 4.0 : 2.0));
  }
  return 4.0 * 3.14159265358979323846 * sum / (3.0 * n);
}

double median(std::vector<double> v) {
  const size_t mid = v.size() / 2;
  std::nth_element(v.begin(), v.begin() + std::ptrdiff_t(mid), v.end());
  return v[mid];
}

}  // namespace

double lattice_field(Kernel kernel, double radius, double spacing) {
  validate_kernel(kernel);
  if (!(radius > 0) || !std::isfinite(radius))
    throw Error(Status::InvalidArgument, "lattice_field: radius must be a finite length > 0, got " + num(radius));
  if (!(spacing > 0) || !std::isfinite(spacing))
    throw Error(Status::InvalidArgument, "lattice_field: spacing must be a finite length > 0, got " + num(spacing));
  const double ratio = radius / spacing;
  if (ratio > 64.0) {
    // Far more than 10^6 lattice points in the support: the continuum limit is exact to
    // better than 1e-4 relative there, and summing would cost ~ratio^3.
    return ratio * ratio * ratio * kernel_ball_integral(kernel);
  }
  const int m = int(std::floor(ratio));
  const double inv = 1.0 / (ratio * ratio);
  double sum = 0;
  for (int i = -m; i <= m; ++i)
    for (int j = -m; j <= m; ++j)
      for (int k = -m; k <= m; ++k) {
        const double s = double(i * i + j * j + k * k) * inv;
        if (s < 1.0) sum += kernel_value(kernel, s);
      }
  return sum;
}

namespace detail {

ParticleField FieldBuilder::build(const Vec3* positions, size_t n, const FieldParams& params,
                                  ProgressTracker& tracker, double begin, double end) {
  ParticleField f;
  validate_kernel(params.kernel);
  if (n == 0) throw Error(Status::InvalidInput, "there are no particles");
  if (n >= size_t(std::numeric_limits<uint32_t>::max()))
    throw Error(Status::LimitExceeded, "more than 4294967294 particles");
  for (size_t i = 0; i < n; ++i)
    for (int a = 0; a < 3; ++a)
      if (!std::isfinite(positions[i][a]))
        throw Error(Status::InvalidInput, "positions[" + std::to_string(i) + "]." + "xyz"[a] + " is " +
                                              (std::isnan(positions[i][a]) ? "NaN" : "infinite"));
  if (!params.radii.empty()) {
    if (params.radii.size() != n)
      throw Error(Status::InvalidArgument, "radii has " + std::to_string(params.radii.size()) +
                                               " values for " + std::to_string(n) + " particles");
    for (size_t i = 0; i < n; ++i)
      if (!(params.radii[i] > 0) || !std::isfinite(params.radii[i]))
        throw Error(Status::InvalidArgument, "radii[" + std::to_string(i) + "] is " + num(params.radii[i]) +
                                                 " (must be a finite length > 0)");
  } else if (!(params.radius >= 0) || !std::isfinite(params.radius)) {
    throw Error(Status::InvalidArgument,
                "radius is " + num(params.radius) + " (must be a finite length > 0, or 0 for the default)");
  }
  if (!params.strengths.empty()) {
    if (params.strengths.size() != n)
      throw Error(Status::InvalidArgument, "strengths has " + std::to_string(params.strengths.size()) +
                                               " values for " + std::to_string(n) + " particles");
    for (size_t i = 0; i < n; ++i)
      if (!std::isfinite(params.strengths[i]))
        throw Error(Status::InvalidArgument, "strengths[" + std::to_string(i) + "] is " + num(params.strengths[i]));
      else if (std::abs(params.strengths[i]) > kMaxStrength)
        // Sums and gradients of strengths near DBL_MAX overflow to inf / NaN normals (fuzzing).
        throw Error(Status::InvalidArgument, "strengths[" + std::to_string(i) + "] is " + num(params.strengths[i]) +
                                                 " (its magnitude must be at most 1e100)");
  }
  if (!(params.threshold >= 0) || !std::isfinite(params.threshold))
    throw Error(Status::InvalidArgument,
                "threshold is " + num(params.threshold) + " (must be finite and > 0, or 0 for the default)");

  f.params_ = params;
  const bool need_radius = params.radii.empty() && params.radius == 0;
  const bool need_threshold = params.threshold == 0;
  if (need_radius) {
    try {
      f.spacing_ = estimate_spacing_impl(positions, n, tracker, begin, end).spacing;
    } catch (const Error& e) {
      if (e.status() == Status::Cancelled) throw;
      throw Error(e.status(), std::string("the default radius needs the particle spacing, which cannot be "
                                          "estimated: ") + e.what() + " (give a radius)");
    }
    if (!(f.spacing_ > 0)) throw Error(Status::InvalidInput, "the particle spacing estimate is 0 (give a radius)");
  }
  if (need_radius) {
    f.params_.radius = kDefaultRadiusFactor * f.spacing_;
    f.radius_defaulted_ = true;
  } else if (!params.radii.empty()) {
    f.params_.radius = median(params.radii);
  }
  if (need_threshold) {
    const double w = params.strengths.empty() ? 1.0 : median(params.strengths);
    if (!(w > 0))
      throw Error(Status::InvalidArgument,
                  "the default threshold needs a positive median strength (got " + num(w) + "): give a threshold");
    f.params_.threshold = kDefaultThresholdFraction * w * lattice_field(params.kernel, kDefaultRadiusFactor, 1.0);
    // A subnormal median strength underflows to 0 here (found by fuzzing), a huge one to inf.
    if (!(f.params_.threshold > 0) || !std::isfinite(f.params_.threshold))
      throw Error(Status::InvalidArgument, "the default threshold from the median strength " + num(w) +
                                               " is " + num(f.params_.threshold) + ": give a threshold");
    f.threshold_defaulted_ = true;
  }

  f.uniform_ = params.radii.empty();
  f.max_radius_ = f.uniform_ ? f.params_.radius : *std::max_element(params.radii.begin(), params.radii.end());
  f.inv_r2_ = 1.0 / (f.params_.radius * f.params_.radius);
  if (!std::isfinite(f.inv_r2_) || !std::isfinite(f.max_radius_ * f.max_radius_))
    throw Error(Status::InvalidArgument, "radius " + num(f.max_radius_) + " is out of the usable range");

  Vec3 lo = positions[0], hi = positions[0];
  for (size_t i = 0; i < n; ++i) {
    const double r = f.radius(i);
    const Vec3& p = positions[i];
    lo = {std::min(lo.x, p.x - r), std::min(lo.y, p.y - r), std::min(lo.z, p.z - r)};
    hi = {std::max(hi.x, p.x + r), std::max(hi.y, p.y + r), std::max(hi.z, p.z + r)};
  }
  f.support_lo_ = lo;
  f.support_hi_ = hi;

  f.grid_ = NeighborGrid(positions, n, f.max_radius_);  // the particles are kept once, in grid order
  f.sorted_index_.resize(n);
  for (uint32_t s = 0; s < n; ++s) f.sorted_index_[f.grid_.original_index(s)] = s;
  if (!f.uniform_) {
    f.sorted_inv_r2_.resize(n);
    for (uint32_t s = 0; s < n; ++s) {
      const double r = params.radii[f.grid_.original_index(s)];
      f.sorted_inv_r2_[s] = 1.0 / (r * r);
    }
  }
  if (!params.strengths.empty()) {
    f.sorted_strength_.resize(n);
    for (uint32_t s = 0; s < n; ++s) f.sorted_strength_[s] = params.strengths[f.grid_.original_index(s)];
  }
  return f;
}

}  // namespace detail

ParticleField::ParticleField(std::vector<Vec3> positions, const FieldParams& params, int threads,
                             const ProgressCallback& progress) {
  detail::ProgressTracker tracker(progress);
  *this = detail::with_threads(threads, [&] {
    return detail::FieldBuilder::build(positions.data(), positions.size(), params, tracker, 0.0, 1.0);
  });
  tracker.finish();
}

ParticleField::ParticleField(const PointCloud& cloud, const FieldParams& params, int threads,
                             const ProgressCallback& progress) {
  detail::ProgressTracker tracker(progress);
  *this = detail::with_threads(threads, [&] {
    return detail::FieldBuilder::build(cloud.positions.data(), cloud.positions.size(), params, tracker, 0.0, 1.0);
  });
  tracker.finish();
}

double ParticleField::value_and_gradient(const Vec3& x, Vec3* gradient) const {
  double v = 0;
  Vec3 g{};
  if (size() == 0) {
    if (gradient) *gradient = g;
    return 0;
  }
  const auto& P = grid_.sorted_points();
  const bool unit = sorted_strength_.empty();
  detail::dispatch_kernel(params_.kernel, [&]<Kernel K>() {
    grid_.for_each_within(x, max_radius_, [&](uint32_t s, double d2) {
      const double inv_r2 = uniform_ ? inv_r2_ : sorted_inv_r2_[s];
      const double q = d2 * inv_r2;
      if (!(q < 1.0)) return;
      const double w = unit ? 1.0 : sorted_strength_[s];
      v += w * detail::kernel_value_t<K>(q);
      if (gradient) g += (x - P[s]) * (2.0 * w * inv_r2 * detail::kernel_derivative_t<K>(q));
    });
  });
  if (gradient) *gradient = g;
  return v;
}

double ParticleField::value(const Vec3& x) const { return value_and_gradient(x, nullptr); }

Vec3 ParticleField::gradient(const Vec3& x) const {
  Vec3 g;
  value_and_gradient(x, &g);
  return g;
}

}  // namespace particlemesh
