#include "particlemesh/volume/field.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <string>

#include "core/parallel.h"
#include "core/progress_tracker.h"
#include "particlemesh/core/error.h"
#include "spatial/spacing_impl.h"
#include "volume/anisotropy_impl.h"
#include "volume/field_impl.h"

namespace PM_NAMESPACE {

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
// See calibrate_anisotropic_threshold.
constexpr double kMinFaceFraction = 0.1;
// A particle whose neighbours' kernel-weighted mean lies within this many radii of it is in
// the bulk (field_at_particles): 0 inside a lattice, 0.2-0.3 for the particles of its outer
// two layers at the default radius; under 0.1 for about half of a jittered lattice's or an SPH
// fluid's particles.
constexpr double kBulkOffset = 0.1;
// Fewer sampled bulk particles than this (a sheet, a spray, a handful): the packing is read
// from the upper quartile of every sampled particle instead. 8: the core of a 4 x 4 x 4 block.
constexpr size_t kMinBulkSamples = 8;
// The default radius follows the particles' packing when 2 x spacing leaves more than a tenth
// of them outside the surface (on a packed block every particle is inside: its face lies half
// a spacing out) and the packing asks for a radius larger by more than kPackingTolerance.
// Particles that the field at 2 x spacing already holds keep that radius, and their mesh.
constexpr double kMinEnclosedAtTwoSpacings = 0.9;
constexpr double kPackingTolerance = 0.02;

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

double lattice_face_field(Kernel kernel, double radius, const AnisotropyOptions& a) {
  validate_kernel(kernel);
  if (!(radius > 0 && radius <= kMaxCalibrationRatio))
    throw Error(Status::InvalidArgument, "lattice_face_field: radius is " + num(radius) + " spacings (must be in (0, " +
                                             num(kMaxCalibrationRatio) + "])");
  if (a.enabled) validate_anisotropy(a);
  // By the lattice's symmetry every particle of a layer has the same kernel: one per layer,
  // down to the deepest layer whose kernels can reach the face.
  const double stretch = a.enabled ? std::pow(a.max_stretch, 2.0 / 3.0) : 1.0;
  const int layers = int(std::ceil(radius * stretch + 0.5)) + 1;
  std::vector<KernelEllipsoid> layer(static_cast<size_t>(layers));
  for (int k = 0; k < layers; ++k) {
    KernelEllipsoid& ke = layer[size_t(k)];
    const Vec3 p{0.0, 0.0, -double(k)};
    if (!a.enabled) {
      ke.centre = p;
      const double m = 1.0 / (radius * radius);
      ke.metric = {m, m, m, 0.0, 0.0, 0.0};
      continue;
    }
    // The same weighted sums as anisotropic_kernels, over the lattice points within r.
    const double r = a.neighbor_radius * radius;
    const int m = int(std::floor(r));
    double W = 0;
    Vec3 S{};
    std::array<double, 6> Q{};
    uint32_t count = 0;
    for (int z = -m; z <= m; ++z) {
      if (z - k > 0) continue;  // above the outer layer: no particle
      for (int y = -m; y <= m; ++y)
        for (int x = -m; x <= m; ++x) {
          const Vec3 d{double(x), double(y), double(z)};
          const double d2 = squared_norm(d);
          if (!(d2 <= r * r)) continue;
          const double t = std::sqrt(d2) / r;
          const double w = std::max(1.0 - t * t * t, 0.0);
          ++count;
          W += w;
          S += d * w;
          Q[0] += w * d.x * d.x;
          Q[1] += w * d.y * d.y;
          Q[2] += w * d.z * d.z;
          Q[3] += w * d.x * d.y;
          Q[4] += w * d.x * d.z;
          Q[5] += w * d.y * d.z;
        }
    }
    ke = detail::kernel_from_sums(p, radius, r, W, S, Q, count, a);
  }
  // The average over the face's unit cell, 8 x 8 points.
  constexpr int kSamples = 8;
  double sum = 0;
  for (int u = 0; u < kSamples; ++u)
    for (int v = 0; v < kSamples; ++v) {
      const Vec3 x{(u + 0.5) / kSamples, (v + 0.5) / kSamples, 0.5};
      for (const KernelEllipsoid& ke : layer) {
        const Vec3 e = ellipsoid_half_extent(ke.metric);
        const Vec3 c0 = ke.centre;  // the layer's kernel centre above lattice point (0, 0)
        if (x.z - c0.z > e.z) continue;
        for (int j = int(std::floor(x.y - c0.y - e.y)); j <= int(std::ceil(x.y - c0.y + e.y)); ++j)
          for (int i = int(std::floor(x.x - c0.x - e.x)); i <= int(std::ceil(x.x - c0.x + e.x)); ++i) {
            const Vec3 d = x - (c0 + Vec3{double(i), double(j), 0.0});
            sum += kernel_value(kernel, detail::metric_norm2(ke.metric.data(), d));
          }
      }
    }
  return sum / (kSamples * kSamples);
}

FieldAtParticles field_at_particles(const ParticleField& f) { return detail::field_at_particles(f, f.threshold()); }

double particle_grid_radius(const double* radii, size_t n) {
  if (n == 0) return 0;
  if (radii == nullptr) throw Error(Status::InvalidArgument, "radii is NULL");
  for (size_t i = 0; i < n; ++i)
    if (!(radii[i] > 0) || !std::isfinite(radii[i]))
      throw Error(Status::InvalidArgument, "radii[" + std::to_string(i) + "] is " + num(radii[i]) +
                                               " (must be a finite length > 0)");
  // The kMaxApart + 1 largest, largest first, and the median.
  constexpr size_t kMaxApart = 4096;
  // Particles an evaluation looks at in cells of the median radius, taken as two spacings:
  // 27 cells of 2^3 particles.
  constexpr double kCellCost = 216;
  const size_t top = std::min(n, kMaxApart + 1);
  std::vector<double> v(radii, radii + n);
  std::nth_element(v.begin(), v.begin() + ptrdiff_t(n / 2), v.end());
  const double med = v[n / 2];
  std::partial_sort(v.begin(), v.begin() + ptrdiff_t(top), v.end(), std::greater<double>());
  auto cells = [&](double r) { return kCellCost * std::pow(r / med, 3); };
  // m apart: those of radius above v[m] (a tie with v[m] stays in the cells).
  double best = cells(v[0]), cell = v[0];
  for (size_t m = 1; m < top; ++m) {
    if (!(v[m] < v[m - 1])) continue;
    const double cost = double(m) + cells(v[m]);
    if (cost < best) best = cost, cell = v[m];
  }
  // Only a clear gain: where the median radius is less than two spacings the cells cost less
  // than taken here, and a split chosen at a quarter of the cost is at worst 1.8 times slower
  // than none (at a median radius of one spacing).
  return best <= 0.25 * cells(v[0]) ? cell : v[0];
}

namespace detail {

FieldAtParticles field_at_particles(const ParticleField& f, double threshold) {
  FieldAtParticles r;
  const size_t n = f.size();
  if (n == 0) return r;
  const FieldParams& p = f.params();
  const bool spheres = !f.anisotropic() && p.radii.empty();
  // At most ~4096 particles, evenly by input index: the shares and the median are as good,
  // the cost bounded (microseconds to milliseconds).
  const size_t stride = (n + 4095) / 4096;
  std::vector<double> level((n + stride - 1) / stride), offset(level.size(), kInf);
  parallel_blocks(level.size(), 64, [&](size_t b, size_t e) {
    for (size_t k = b; k < e; ++k) {
      const Vec3 x = f.position(k * stride);
      level[k] = f.value(x);
      if (!spheres) continue;
      // How far the kernel-weighted mean of the neighbours lies from the particle, in radii:
      // 0 deep inside an even packing, about 0.3 on its face.
      double W = 0;
      Vec3 S{};
      f.for_each_contributor(x, [&](size_t j, double s) {
        const double g = kernel_value(p.kernel, s);
        W += g;
        S += (f.position(j) - x) * g;
      });
      if (W > 0) offset[k] = std::sqrt(squared_norm(S)) / W / p.radius;
    }
  });
  size_t inside = 0;
  for (double v : level) inside += v >= threshold;
  r.enclosed_fraction = double(inside) / double(level.size());
  if (spheres) {
    const double w = p.strengths.empty() ? 1.0 : median(p.strengths);
    if (w > 0) {
      // The packing is read where the particles have neighbours all around (the bulk: the
      // field there is a lattice's interior level, whatever the particles' shape); too few of
      // them: the upper quartile of every particle's level.
      std::vector<double> bulk;
      for (size_t k = 0; k < level.size(); ++k)
        if (offset[k] < kBulkOffset) bulk.push_back(level[k]);
      double packed;
      if (bulk.size() >= kMinBulkSamples) {
        packed = median(std::move(bulk));
      } else {
        const size_t q = (3 * level.size()) / 4;
        std::nth_element(level.begin(), level.begin() + std::ptrdiff_t(q), level.end());
        packed = level[q];
      }
      const double x = lattice_ratio_of(p.kernel, packed / w);
      r.density_radius = kDefaultRadiusFactor * p.radius / x;
    }
  }
  return r;
}

double lattice_ratio_of(Kernel kernel, double level) {
  // lattice_field(kernel, x, 1) grows with x (from 1: the particle alone, below one spacing).
  double lo = 1.0, hi = kMaxCalibrationRatio;
  if (!(level > lattice_field(kernel, lo, 1.0))) hi = lo;
  else if (level >= lattice_field(kernel, hi, 1.0)) lo = hi;
  for (int it = 0; it < 50 && hi - lo > 1e-6; ++it) {
    const double mid = 0.5 * (lo + hi);
    (lattice_field(kernel, mid, 1.0) < level ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

// The default threshold of anisotropic kernels: the level at which the face of a packed block
// of the particles' own density lies half a spacing outside its outermost particles (see
// FieldParams::threshold). The density is read from the field itself: the median of F at
// the centres of bulk particles (those whose neighbours' weighted mean is within 0.15 r_i:
// 0.32 r_i on a flat face) is the lattice field of an effective ratio R / s, and the
// threshold is the face field of a half-infinite lattice at that ratio with the same kernels.
void FieldBuilder::calibrate_anisotropic_threshold(ParticleField& f, const std::vector<KernelEllipsoid>& kernels,
                                                   ProgressTracker& tracker) {
  const size_t n = kernels.size();
  const FieldParams& p = f.params_;
  const double w = p.strengths.empty() ? 1.0 : median(p.strengths);
  std::vector<uint32_t> bulk;
  for (size_t i = 0; i < n; ++i)
    if (kernels[i].mean_offset < 0.15 && kernels[i].neighbors >= uint32_t(p.anisotropy.min_neighbors))
      bulk.push_back(uint32_t(i));
  double ratio = kDefaultRadiusFactor;
  if (bulk.size() >= 32) {
    // At most ~4096 of them, evenly by input index: the median is as good, the cost bounded.
    const size_t stride = (bulk.size() + 4095) / 4096;
    std::vector<double> level((bulk.size() + stride - 1) / stride);
    detail::parallel_blocks(level.size(), 64, [&](size_t b, size_t e) {
      for (size_t k = b; k < e; ++k) level[k] = f.value(f.position(bulk[k * stride]));
    });
    tracker.check();
    ratio = lattice_ratio_of(p.kernel, median(level) / w);
  }
  f.calibration_ratio_ = ratio;
  // Strong centre smoothing (lambda of 0.3 or more) pulls the outer layer in so far that the
  // field at the face vanishes and no threshold keeps the volume: then the surface is put
  // where the field has fallen to kMinFaceFraction of the bulk level.
  const double interior = lattice_field(p.kernel, ratio, 1.0);
  const double t = w * std::max(lattice_face_field(p.kernel, ratio, p.anisotropy), kMinFaceFraction * interior);
  if (!(t > 0) || !std::isfinite(t))
    throw Error(Status::InvalidArgument, "the default threshold of the anisotropic kernels from the median strength " +
                                             num(w) + " is " + num(t) + ": give a threshold");
  f.params_.threshold = t;
}

ParticleField FieldBuilder::build(const Vec3* positions, size_t n, const FieldParams& params,
                                  ProgressTracker& tracker, double begin, double end,
                                  const FieldDomain& domain) {
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
        // Sums and gradients of strengths near DBL_MAX overflow to inf / NaN normals, and the
        // polygonizer's single-precision samples of strengths beyond FLT_MAX (fuzzing).
        throw Error(Status::InvalidArgument, "strengths[" + std::to_string(i) + "] is " + num(params.strengths[i]) +
                                                 " (its magnitude must be at most 1e30)");
  }
  if (!(params.threshold >= 0) || !std::isfinite(params.threshold))
    throw Error(Status::InvalidArgument,
                "threshold is " + num(params.threshold) + " (must be finite and > 0, or 0 for the default)");

  const bool aniso = params.anisotropy.enabled;
  if (aniso) validate_anisotropy(params.anisotropy);

  f.params_ = params;
  const bool need_radius = params.radii.empty() && params.radius == 0;
  const bool need_threshold = params.threshold == 0;
  // Progress: the spacing estimate, then the anisotropic kernels (the longer of the two).
  const double mid = aniso ? begin + 0.25 * (end - begin) : end;
  if (need_radius) {
    try {
      f.spacing_ = estimate_spacing_impl(positions, n, tracker, begin, mid).spacing;
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
  if (domain.max_radius != 0) {
    if (!(domain.max_radius >= f.max_radius_) || !std::isfinite(domain.max_radius))
      throw Error(Status::InvalidArgument, "domain_max_radius is " + num(domain.max_radius) +
                                               " (must be finite and at least the largest radius, " +
                                               num(f.max_radius_) + ", or 0)");
    f.max_radius_ = domain.max_radius;
  }
  // The cells' radius: per-particle radii far apart keep their largest apart (above it).
  double cell = f.max_radius_;
  if (!params.radii.empty()) {
    if (domain.grid_radius != 0) {
      if (!(domain.grid_radius > 0) || !(domain.grid_radius <= f.max_radius_))
        throw Error(Status::InvalidArgument, "domain_grid_radius is " + num(domain.grid_radius) +
                                                 " (must be > 0 and at most the largest radius, " +
                                                 num(f.max_radius_) + ", or 0)");
      cell = domain.grid_radius;
    } else if (domain.max_radius == 0) {
      cell = particle_grid_radius(params.radii.data(), n);
    }
  }
  // The particles kept apart from the cells (a radius above the cells').
  std::vector<uint8_t> apart;
  if (cell < f.max_radius_) {
    apart.resize(n);
    for (size_t i = 0; i < n; ++i) apart[i] = params.radii[i] > cell;
  }
  f.cell_reach_ = cell;
  f.inv_r2_ = 1.0 / (f.params_.radius * f.params_.radius);
  if (!std::isfinite(f.inv_r2_) || !std::isfinite(f.max_radius_ * f.max_radius_))
    throw Error(Status::InvalidArgument, "radius " + num(f.max_radius_) + " is out of the usable range");
  f.reach_ = f.max_radius_;

  // Kernel centres and, with anisotropic kernels, their ellipsoids (input order).
  std::vector<KernelEllipsoid> kernels;
  std::vector<Vec3> centres;
  std::vector<Vec3> extents;
  if (aniso) {
    // The kernels' neighbour grid: the cells' radius, at most these particles' largest (a
    // tile's domain_max_radius sizes only the field's cells).
    const double largest =
        params.radii.empty() ? f.params_.radius : *std::max_element(params.radii.begin(), params.radii.end());
    kernels = anisotropic_kernels_impl(positions, n, f.params_.radius,
                                       params.radii.empty() ? nullptr : params.radii.data(),
                                       std::min(cell, largest), params.anisotropy, tracker, mid, end);
    centres.resize(n);
    extents.resize(n);
    f.reach_ = 0;
    f.cell_reach_ = 0;  // the longest reach of the ellipsoids in the cells
    for (size_t i = 0; i < n; ++i) {
      centres[i] = kernels[i].centre;
      extents[i] = ellipsoid_half_extent(kernels[i].metric);
      const double e = std::max({extents[i].x, extents[i].y, extents[i].z});
      f.reach_ = std::max(f.reach_, e);
      if (apart.empty() || !apart[i]) f.cell_reach_ = std::max(f.cell_reach_, e);
      f.anisotropic_count_ += kernels[i].anisotropic;
    }
    if (!std::isfinite(f.reach_ * f.reach_))
      throw Error(Status::InvalidArgument, "radius " + num(f.max_radius_) + " is out of the usable range");
  }
  const Vec3* C = aniso ? centres.data() : positions;

  Vec3 lo = C[0], hi = C[0];
  for (size_t i = 0; i < n; ++i) {
    const double r = f.radius(i);
    const Vec3 e = aniso ? extents[i] : Vec3{r, r, r};
    const Vec3& p = C[i];
    lo = {std::min(lo.x, p.x - e.x), std::min(lo.y, p.y - e.y), std::min(lo.z, p.z - e.z)};
    hi = {std::max(hi.x, p.x + e.x), std::max(hi.y, p.y + e.y), std::max(hi.z, p.z + e.z)};
  }
  f.support_lo_ = lo;
  f.support_hi_ = hi;

  // The centres are kept once, in grid order. Anisotropic kernels: cells of the largest radius
  // (most kernels reach about that far) looked up in a dense table (below), not of the longest
  // reach, whose cells hold several times the particles an evaluation needs to look at.
  // The grid's corner is the given domain's (every tile of a cloud then shares the cloud's
  // cells and summation order) or the centres' smallest coordinates.
  try {
    if (domain.min) {
      const Vec3& d = *domain.min;
      for (int a = 0; a < 3; ++a) {
        if (!std::isfinite(d[a]))
          throw Error(Status::InvalidArgument, std::string("domain_min.") + "xyz"[a] + " is " + num(d[a]));
        for (size_t i = 0; i < n; ++i)
          if (positions[i][a] < d[a] || C[i][a] < d[a])
            throw Error(Status::InvalidArgument, std::string("domain_min.") + "xyz"[a] + " is " + num(d[a]) +
                                                     ", above positions[" + std::to_string(i) + "]." + "xyz"[a] +
                                                     " = " + num(std::min(positions[i][a], C[i][a])) +
                                                     " (it must be at or below every particle)");
      }
      f.lower_ = d;
      f.grid_ = NeighborGrid(C, n, cell, &d, apart.empty() ? nullptr : apart.data());
    } else {
      Vec3 m = C[0];
      for (size_t i = 1; i < n; ++i) m = {std::min(m.x, C[i].x), std::min(m.y, C[i].y), std::min(m.z, C[i].z)};
      f.lower_ = m;
      f.grid_ = NeighborGrid(C, n, cell, nullptr, apart.empty() ? nullptr : apart.data());
    }
  } catch (const Error& e) {
    if (e.status() != Status::LimitExceeded) throw;
    throw Error(e.status(), std::string(e.what()) + (domain.min ? " (the grid's lower corner is domain_min; " : " (") +
                                "the cells follow the particle radius)");
  }
  f.sorted_index_.resize(n);
  for (uint32_t s = 0; s < n; ++s) f.sorted_index_[f.grid_.original_index(s)] = s;
  // The dense cell table, when the occupied cells' box has at most 8 times as many cells
  // (plus a million: small clouds always get one).
  NeighborGrid::CellCoord clo{INT32_MAX, INT32_MAX, INT32_MAX}, chi{INT32_MIN, INT32_MIN, INT32_MIN};
  for (uint32_t c = 0; c < f.grid_.cell_count(); ++c) {
    const NeighborGrid::CellCoord cc = f.grid_.cell_coord(c);
    for (size_t a = 0; a < 3; ++a) {
      clo[a] = std::min(clo[a], cc[a]);
      chi[a] = std::max(chi[a], cc[a]);
    }
  }
  const double box = double(chi[0] - clo[0] + 1) * double(chi[1] - clo[1] + 1) * double(chi[2] - clo[2] + 1);
  if (box <= 8.0 * double(f.grid_.cell_count()) + 1e6) {
    f.dense_lo_ = clo;
    for (size_t a = 0; a < 3; ++a) f.dense_size_[a] = chi[a] - clo[a] + 1;
    f.dense_cells_.assign(size_t(box), NeighborGrid::kNoCell);
    for (uint32_t c = 0; c < f.grid_.cell_count(); ++c) {
      const NeighborGrid::CellCoord cc = f.grid_.cell_coord(c);
      f.dense_cells_[(size_t(cc[0] - clo[0]) * size_t(f.dense_size_[1]) + size_t(cc[1] - clo[1])) *
                         size_t(f.dense_size_[2]) +
                     size_t(cc[2] - clo[2])] = c;
    }
  }
  if (aniso) {
    f.sorted_metric_.resize(6 * size_t(n));
    f.sorted_extent_.resize(3 * size_t(n));
    for (uint32_t s = 0; s < n; ++s) {
      const size_t i = f.grid_.original_index(s);
      std::copy(kernels[i].metric.begin(), kernels[i].metric.end(), f.sorted_metric_.begin() + 6 * ptrdiff_t(s));
      for (int a = 0; a < 3; ++a) {
        // Rounded up, so that a test against the float box never drops a contributor.
        float e = float(extents[i][a]);
        if (double(e) < extents[i][a]) e = std::nextafter(e, std::numeric_limits<float>::infinity());
        f.sorted_extent_[3 * size_t(s) + size_t(a)] = e;
      }
    }
    constexpr float kInfF = std::numeric_limits<float>::infinity();
    f.cell_support_.resize(6 * f.grid_.cell_count());
    for (uint32_t c = 0; c < f.grid_.cell_count(); ++c) {
      double blo[3] = {kInf, kInf, kInf}, bhi[3] = {-kInf, -kInf, -kInf};
      for (uint32_t s = f.grid_.cell_begin(c); s < f.grid_.cell_end(c); ++s)
        for (int a = 0; a < 3; ++a) {
          const double e = double(f.sorted_extent_[3 * size_t(s) + size_t(a)]);
          blo[a] = std::min(blo[a], f.grid_.sorted_point(s)[a] - e);
          bhi[a] = std::max(bhi[a], f.grid_.sorted_point(s)[a] + e);
        }
      for (int a = 0; a < 3; ++a) {
        float l = float(blo[a]), h = float(bhi[a]);
        if (double(l) > blo[a]) l = std::nextafter(l, -kInfF);
        if (double(h) < bhi[a]) h = std::nextafter(h, kInfF);
        f.cell_support_[6 * size_t(c) + size_t(a)] = l;
        f.cell_support_[6 * size_t(c) + 3 + size_t(a)] = h;
      }
    }
    if (need_threshold) calibrate_anisotropic_threshold(f, kernels, tracker);
  }
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
  if (need_radius && !aniso) {
    // The default radius from the packing (FieldParams::radius): built again at the radius
    // the field at the particles asks for, when too many of them are outside the surface of
    // the default threshold (whatever threshold is given: the radius is the same for all).
    tracker.check();
    const double w = params.strengths.empty() ? 1.0 : median(params.strengths);
    const FieldAtParticles at =
        field_at_particles(f, kDefaultThresholdFraction * w * lattice_field(params.kernel, kDefaultRadiusFactor, 1.0));
    const double packed = at.density_radius;
    if (at.enclosed_fraction < kMinEnclosedAtTwoSpacings && packed > f.params_.radius * (1.0 + kPackingTolerance)) {
      FieldParams resolved = params;
      resolved.radius = packed;
      ParticleField g = build(positions, n, resolved, tracker, end, end, domain);
      g.spacing_ = f.spacing_;
      g.radius_defaulted_ = true;
      return g;
    }
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

std::array<double, 6> ParticleField::metric(size_t i) const {
  if (sorted_metric_.empty()) {
    const double r = radius(i), k = 1.0 / (r * r);
    return {k, k, k, 0.0, 0.0, 0.0};
  }
  std::array<double, 6> m;
  std::copy_n(sorted_metric_.begin() + 6 * ptrdiff_t(sorted_index_[i]), 6, m.begin());
  return m;
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
  if (!sorted_metric_.empty()) {
    detail::dispatch_kernel(params_.kernel, [&]<Kernel K>() {
      for_each_ellipsoid_near(x, [&](uint32_t s, const Vec3& d) {
        const double* m = &sorted_metric_[6 * size_t(s)];
        const double q = detail::metric_norm2(m, d);
        if (!(q < 1.0)) return;
        const double w = unit ? 1.0 : sorted_strength_[s];
        v += w * detail::kernel_value_t<K>(q);
        if (gradient) g += detail::metric_apply(m, d) * (2.0 * w * detail::kernel_derivative_t<K>(q));
      });
    });
    if (gradient) *gradient = g;
    return v;
  }
  detail::dispatch_kernel(params_.kernel, [&]<Kernel K>() {
    auto add = [&](uint32_t s, double d2) {
      const double inv_r2 = uniform_ ? inv_r2_ : sorted_inv_r2_[s];
      const double q = d2 * inv_r2;
      if (!(q < 1.0)) return;
      const double w = unit ? 1.0 : sorted_strength_[s];
      v += w * detail::kernel_value_t<K>(q);
      if (gradient) g += (x - P[s]) * (2.0 * w * inv_r2 * detail::kernel_derivative_t<K>(q));
    };
    for_each_within(x, cell_reach_, add);
    for (uint32_t s = grid_.apart_begin(); s < grid_.point_count(); ++s) add(s, squared_distance(P[s], x));
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
