#include "particlemesh/volume/raycast.h"

#include <algorithm>
#include <cmath>
#include <string>

#include "core/parallel.h"
#include "core/progress_tracker.h"
#include "particlemesh/core/error.h"
#include "volume/anisotropy_impl.h"
#include "volume/ray_cancel.h"
#include "volume/ray_roots.h"
#include "volume/raycast_impl.h"

namespace PM_NAMESPACE {

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr int kLeafSize = 8;  // measured: 8 walks ~10 % faster than 2 or 4, 16 no better
// max over s of |d/dt g(s(t))| x R for Blinn's kernel along a unit-speed ray:
// (2k / R) sqrt(s) e^(-ks) / (1 - eps) is largest at s = 1 / (2k): sqrt(2k) e^(-1/2) / (1 - eps).
const double kBlinnSlope = std::sqrt(2.0 * kBlinnExponent) * std::exp(-0.5) / (1.0 - kBlinnTolerance);

std::string num(double v) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.17g", v);
  return buf;
}


using detail::Active;
using detail::Event;
using detail::Node;
using detail::NodeEntry;
using detail::Scratch;

Scratch& scratch() { return detail::ray_scratch(); }

void check_ray(const Vec3& o, const Vec3& d, size_t i, bool indexed) {
  auto name = [&](const char* base) {
    return indexed ? std::string(base) + "[" + std::to_string(i) + "]" : std::string(base);
  };
  for (int a = 0; a < 3; ++a) {
    if (!std::isfinite(o[a]))
      throw Error(Status::InvalidArgument, name("origins") + "." + "xyz"[a] + " is " + num(o[a]));
    if (!std::isfinite(d[a]))
      throw Error(Status::InvalidArgument, name("directions") + "." + "xyz"[a] + " is " + num(d[a]));
  }
  if (d.x == 0 && d.y == 0 && d.z == 0) throw Error(Status::InvalidArgument, name("directions") + " is zero");
  if (!(squared_norm(d) > 0) || !std::isfinite(squared_norm(d)))
    throw Error(Status::InvalidArgument, name("directions") + " has a length out of the usable range");
}

void check_range(double t_min, double t_max) {
  if (std::isnan(t_min) || std::isnan(t_max) || t_min > t_max)
    throw Error(Status::InvalidArgument,
                "the ray range [t_min, t_max] = [" + num(t_min) + ", " + num(t_max) + "] is empty or NaN");
}

}  // namespace


void RayCaster::Impl::build() {
  kernel = field.kernel();
  blinn = !kernel_is_polynomial(kernel);
  threshold = field.threshold();
  if (!blinn) {
    // g(s) = sum_j c_j s^j with s = 1 - tau: d_i = (-1)^i sum_j c_j C(j, i).
    const KernelPolynomial kp = kernel_polynomial(kernel);
    kdeg = kp.degree;
    for (int i = 0; i <= kKernelMaxDegree; ++i) {
      double v = 0;
      for (int j = i; j <= kKernelMaxDegree; ++j) {
        double binom = 1;
        for (int m = 0; m < i; ++m) binom = binom * double(j - m) / double(m + 1);
        v += kp.c[size_t(j)] * binom;
      }
      d[i] = (i % 2 ? -v : v);
    }
    d[0] = 0;  // g(1) = 0 exactly (the sum of the coefficients is 0 up to rounding)
    // The running bound's slope (interval_bounded()): along a unit-speed ray a particle's
    // value w g(s) changes at |w g'(s) 2 ir2 (t - tstar)| <= w sqrt(ir2) 2 sqrt(s) |g'(s)|, as
    // (t - tstar)^2 ir2 <= s. The largest of 2 sqrt(s) |g'(s)| over fine samples of [0, 1],
    // raised by a thousandth (the function is smooth: the samples miss its maximum by far
    // less). Blinn's kernel, marched, keeps no running bound (slope 0).
    constexpr int kSamples = 1 << 14;
    double most = 0;
    for (int i = 0; i <= kSamples; ++i) {
      const double s = double(i) / kSamples;
      most = std::max(most, 2.0 * std::sqrt(s) * std::abs(kernel_derivative(kernel, s)));
    }
    slope = most * 1.001;
  }
  const size_t n = field.size();
  std::vector<uint32_t> idx;
  idx.reserve(n);
  double wmax = 0;
  r_min = kInf;
  aniso = field.anisotropic();
  for (size_t i = 0; i < n; ++i) {
    if (field.strength(i) == 0) continue;
    idx.push_back(uint32_t(i));
    wmax = std::max(wmax, std::abs(field.strength(i)));
    r_min = std::min(r_min, field.radius(i));
  }
  // An ellipsoid's shortest semi-axis is at least R max_stretch^(-2/3) (anisotropy.h).
  if (aniso) r_min *= std::pow(field.params().anisotropy.max_stretch, -2.0 / 3.0);
  // Half extents of the supports by input index (spheres: the radius).
  std::vector<Vec3> ext(n);
  for (uint32_t k = 0; k < uint32_t(n); ++k) {
    const uint32_t i = field.grid().original_index(k);
    if (aniso) {
      const float* e = &field.sorted_half_extents()[3 * size_t(k)];
      ext[i] = {double(e[0]), double(e[1]), double(e[2])};
    } else {
      const double r = field.radius(i);
      ext[i] = {r, r, r};
    }
  }
  eps_f = kTangentTolerance * (threshold + wmax);
  // Per particle w sqrt(ir2) <= wmax / r_min (an ellipsoid's ir2 along any direction is at
  // most 1 / its shortest semi-axis squared).
  slope *= wmax / r_min;
  // Centres by input index, read through the field's grid (which holds them in grid order).
  std::vector<Vec3> P(n);
  for (uint32_t k = 0; k < uint32_t(n); ++k) P[field.grid().original_index(k)] = field.grid().sorted_point(k);
  nodes.clear();
  if (idx.empty()) return;
  // Median split on the longest axis of the centres' box; children stored side by side.
  struct Task {
    uint32_t node, begin, end;
  };
  std::vector<Task> stack{{0, 0, uint32_t(idx.size())}};
  nodes.reserve(2 * (idx.size() / kLeafSize + 1));
  nodes.emplace_back();
  while (!stack.empty()) {
    const Task task = stack.back();
    stack.pop_back();
    Node nd;
    double clo[3] = {kInf, kInf, kInf}, chi[3] = {-kInf, -kInf, -kInf};
    for (int a = 0; a < 3; ++a) {
      nd.lo[a] = kInf;
      nd.hi[a] = -kInf;
    }
    for (uint32_t k = task.begin; k < task.end; ++k) {
      const uint32_t i = idx[k];
      for (int a = 0; a < 3; ++a) {
        nd.lo[a] = std::min(nd.lo[a], P[i][a] - ext[i][a]);
        nd.hi[a] = std::max(nd.hi[a], P[i][a] + ext[i][a]);
        clo[a] = std::min(clo[a], P[i][a]);
        chi[a] = std::max(chi[a], P[i][a]);
      }
    }
    // A hair wider than the spheres, so rounding in the box test never drops a sphere.
    for (int a = 0; a < 3; ++a) {
      const double pad = 1e-12 * (nd.hi[a] - nd.lo[a] + std::abs(nd.lo[a]) + std::abs(nd.hi[a]));
      nd.lo[a] -= pad;
      nd.hi[a] += pad;
    }
    const uint32_t count = task.end - task.begin;
    if (count <= uint32_t(kLeafSize)) {
      nd.first = task.begin;
      nd.count = count;
      nodes[task.node] = nd;
      continue;
    }
    int axis = 0;
    for (int a = 1; a < 3; ++a)
      if (chi[a] - clo[a] > chi[axis] - clo[axis]) axis = a;
    const uint32_t mid = task.begin + count / 2;
    std::nth_element(idx.begin() + task.begin, idx.begin() + mid, idx.begin() + task.end,
                     [&](uint32_t a, uint32_t b) { return P[a][axis] < P[b][axis] || (P[a][axis] == P[b][axis] && a < b); });
    nd.first = uint32_t(nodes.size());
    nd.count = 0;
    nodes[task.node] = nd;
    nodes.emplace_back();
    nodes.emplace_back();
    stack.push_back({nd.first + 1, mid, task.end});
    stack.push_back({nd.first, task.begin, mid});
  }
  pos.resize(idx.size());
  r2.resize(idx.size());
  inv_r2.resize(idx.size());
  w.resize(idx.size());
  bound_r.resize(idx.size());
  if (aniso) metric.resize(6 * idx.size());
  for (size_t k = 0; k < idx.size(); ++k) {
    const size_t i = idx[k];
    pos[k] = P[i];
    const double r = field.radius(i);
    r2[k] = r * r;
    inv_r2[k] = 1.0 / (r * r);
    w[k] = field.strength(i);
    // The support's box holds it: its half diagonal bounds the ellipsoid.
    bound_r[k] = aniso ? norm(ext[i]) : r;
    if (aniso) {
      const std::array<double, 6> m = field.metric(i);
      std::copy(m.begin(), m.end(), metric.begin() + 6 * ptrdiff_t(k));
    }
  }
}

namespace {

// sum_k w_k g(s_k(u)) - T on the interval, u in [0, 1], in the power basis; g(s) = sum_i
// d_i tau^i with tau = 1 - s = A + B u + C u^2 per particle.
template <int Deg>
void interval_polynomial(const RayCaster::Impl& im, double ta, double L, const std::vector<Active>& active,
                         double* c) {
  for (int j = 0; j <= 2 * Deg; ++j) c[j] = 0;
  const double d1 = im.d[1], d2 = im.d[2], d3 = Deg >= 3 ? im.d[3] : 0.0;
  for (const Active& a : active) {
    const double ir2 = a.ir2, wk = a.w;
    const double delta = ta - a.tstar;  // from the closest approach to the interval's start
    const double A = 1.0 - (a.e2 + delta * delta) * ir2;
    const double B = -2.0 * L * delta * ir2;
    const double C = -L * L * ir2;
    // tau^2
    const double t0 = A * A, t1 = 2 * A * B, t2 = B * B + 2 * A * C, t3 = 2 * B * C, t4 = C * C;
    c[0] += wk * (d1 * A + d2 * t0);
    c[1] += wk * (d1 * B + d2 * t1);
    c[2] += wk * (d1 * C + d2 * t2);
    c[3] += wk * (d2 * t3);
    c[4] += wk * (d2 * t4);
    if constexpr (Deg >= 3) {
      // tau^3 = tau^2 * tau
      c[0] += wk * d3 * (t0 * A);
      c[1] += wk * d3 * (t0 * B + t1 * A);
      c[2] += wk * d3 * (t0 * C + t1 * B + t2 * A);
      c[3] += wk * d3 * (t1 * C + t2 * B + t3 * A);
      c[4] += wk * d3 * (t2 * C + t3 * B + t4 * A);
      c[5] += wk * d3 * (t3 * C + t4 * B);
      c[6] += wk * d3 * (t4 * C);
    }
  }
  c[0] -= im.threshold;
}

// kernel_value(K, s), the same bits, without its branch for s >= 1 (t clamped at 0 instead).
template <Kernel K>
inline double kernel_value_clamped(double s) {
  if constexpr (K == Kernel::Blinn) {
    return kernel_value(K, s);
  } else {
    double t = 1.0 - s;
    t = t > 0.0 ? t : 0.0;
    if constexpr (K == Kernel::Wyvill) return t * t * (5.0 + 4.0 * t) * (1.0 / 9.0);
    if constexpr (K == Kernel::Poly4) return t * t;
    return t * t * t;
  }
}

// |kernel_derivative(K, s)| for s in [0, 1), without the kernel switch.
template <Kernel K>
inline double kernel_slope(double s) {
  const double t = 1.0 - s;
  if constexpr (K == Kernel::Wyvill) return t * (10.0 + 12.0 * t) * (1.0 / 9.0);
  if constexpr (K == Kernel::Poly4) return 2.0 * t;
  return 3.0 * t * t;
}

// What the running bound keeps of an exclusion (interval_bounded()): over the particles
// whose closest approach to the ray lies beyond tb, how fast their values can rise from tb
// on, and how far (their peaks less their values at tb).
struct Rise {
  double rate = 0, room = 0;
};

// sum over the positive strengths of w g(s_min), s_min the particle's smallest s on [ta, tb],
// in the order of `active`; the sum so far once it reaches `stop` (no term is negative, so
// the whole sum reaches it too). `rise` (polynomial kernels; when the sum stops short of
// `stop`): a particle closest to the ray at tstar > tb has s >= smin = e2 ir2 from tb on, so
// its value rises at most at w |g'(smin)| 2 ir2 (tstar - tb) (|g'| falls as s grows), and at
// most at `slope` (build()), up to its peak w g(smin).
template <Kernel K>
double field_upper_bound(double ta, double tb, const std::vector<Active>& active, double stop, double slope,
                         Rise* rise) {
  double ub = 0, rate = 0, room = 0;
  for (const Active& a : active) {
    const double wk = a.w;
    if (wk <= 0) continue;
    // The distance from the closest approach to [ta, tb] (d0 <= d1: at most one term is
    // not zero), without branches.
    const double d0 = ta - a.tstar, d1 = tb - a.tstar;
    const double dmin = std::max(d0, 0.0) - std::min(d1, 0.0);
    const double term = wk * kernel_value_clamped<K>((a.e2 + dmin * dmin) * a.ir2);
    ub += term;
    if (ub >= stop) break;
    if constexpr (K != Kernel::Blinn) {
      if (d1 < 0) {
        const double smin = a.e2 * a.ir2;
        rate += std::min(slope, wk * kernel_slope<K>(smin) * 2.0 * a.ir2 * -d1);
        room += wk * kernel_value_clamped<K>(smin) - term;
      }
    }
  }
  rise->rate = rate;
  rise->room = room;
  return ub;
}

}  // namespace

void RayCaster::Impl::Query::interval_bounded(double ta, double tb, const std::vector<Active>& active,
                                              double peaks_entered, size_t count_entered) {
  if (!started || !inside) {
    // Cheaper, where no crossing waits for the tangent rule: the running bound, taken where
    // the bound below last excluded an interval [ta', rb_t] (its value rb_f). Of the
    // particles active then, one whose closest approach lies behind rb_t only falls from
    // there on (at most its term of rb_f), one ahead of it rises from its term (its value at
    // rb_t) by at most its rate x the distance since and never above its peak (rb_rate,
    // rb_room: field_upper_bound); a particle entered since is 0 where it entered (g(1) = 0)
    // and rises at most at `slope`, and is never above its peak. Below T,
    // with room for the rounding of both bounds, the bound below is below T too and would
    // have excluded the interval the same way: the same state, the same hits.
    if (!has_pending && rb_valid) {
      const double grown = std::min(rb_rate * (tb - rb_t), rb_room);
      const double by_peaks = rb_f + grown + (peaks_entered - rb_entered);
      const double by_slopes = rb_f + grown + im.slope * double(count_entered - rb_count) * (tb - rb_t);
      const double bound = std::min(by_peaks, by_slopes);
      if (bound + 1e-9 * (bound + peaks_entered) < im.threshold) {
        if (!started && ta <= tlo) starts_inside = false;
        started = true;
        inside = false;
        observe(im.threshold - bound);
        return;
      }
    }
    // Cheap certified exclusion: F is at most sum over positive strengths of w g(s_min), s_min
    // the particle's smallest s on the interval (g decreases). Below T: outside throughout.
    double ub = 0;
    Rise rise;
    switch (im.kernel) {
      case Kernel::Wyvill: ub = field_upper_bound<Kernel::Wyvill>(ta, tb, active, im.threshold, im.slope, &rise); break;
      case Kernel::Poly4: ub = field_upper_bound<Kernel::Poly4>(ta, tb, active, im.threshold, im.slope, &rise); break;
      case Kernel::Poly6: ub = field_upper_bound<Kernel::Poly6>(ta, tb, active, im.threshold, im.slope, &rise); break;
      case Kernel::Blinn: ub = field_upper_bound<Kernel::Blinn>(ta, tb, active, im.threshold, im.slope, &rise); break;
    }
    if (ub < im.threshold) {
      if (!started && ta <= tlo) starts_inside = false;
      started = true;
      inside = false;
      observe(im.threshold - ub);
      if (im.slope > 0 && !has_pending) {
        rb_valid = true;
        rb_f = ub;
        rb_rate = rise.rate;
        rb_room = rise.room;
        rb_t = tb;
        rb_entered = peaks_entered;
        rb_count = count_entered;
      }
      return;
    }
    rb_valid = false;
  }
  if (im.blinn) {
    interval_blinn(ta, tb, active);
    return;
  }
  const double L = tb - ta;
  double c[detail::kMaxPolyDegree + 1];
  const int n = 2 * im.kdeg;
  if (im.kdeg == 2) interval_polynomial<2>(im, ta, L, active, c);
  else interval_polynomial<3>(im, ta, L, active, c);
  detail::IntervalCrossings r;
  // Cheap certified exclusion first: Bernstein coefficients of one state mean no crossing.
  double b[detail::kMaxPolyDegree + 1];
  detail::power_to_bernstein(c, n, b);
  b[0] = c[0];
  b[n] = detail::poly_eval(c, n, 1.0);
  bool same = true;
  for (int k = 1; k <= n && same; ++k) same = (b[k] >= 0) == (b[0] >= 0);
  if (same) {
    r.count = 0;
    r.start_inside = r.end_inside = b[0] >= 0;
    r.tail = std::max(std::abs(b[0]), std::abs(b[n]));
  } else {
    ++stats.intervals_solved;
    if (n <= 4) detail::crossings_closed_form(c, n, &r);
    else detail::crossings_bernstein(c, n, &r);
  }
  if (!started) {
    started = true;
    if (ta <= tlo) {
      inside = starts_inside = r.start_inside;
    } else if (r.start_inside) {
      emit(ta, 0.0, active);
    }
  } else if (r.start_inside != inside) {
    emit(ta, 0.0, active);  // a crossing on the boundary between two intervals
  }
  observe(std::abs(c[0]));
  for (int k = 0; k < r.count && !done; ++k) emit(ta + r.c[k].u * L, r.c[k].gap, active);
  if (done) return;
  inside = r.end_inside;
  observe(r.tail);
}

void RayCaster::Impl::Query::interval_blinn(double ta, double tb, const std::vector<Active>& active) {
  ++stats.intervals_solved;
  double lip = 0;
  // Along the ray |d/dt g(s)| = |g'(s)| 2 ir2 |t - tstar| <= |g'(s)| 2 sqrt(s ir2): the bound
  // of a sphere of radius 1 / sqrt(ir2).
  for (const Active& a : active) lip += std::abs(a.w) * kBlinnSlope * std::sqrt(a.ir2);
  auto f = [&](double t, double* df) {
    const Vec3 x = o + dn * t;
    double v = 0, dv = 0;
    for (const Active& a : active) {
      const uint32_t k = a.k;
      const Vec3 q = x - im.pos[k];
      if (im.aniso) {
        const double* m = &im.metric[6 * size_t(k)];
        const double s = detail::metric_norm2(m, q);
        if (!(s < 1.0)) continue;
        v += im.w[k] * kernel_value(Kernel::Blinn, s);
        if (df) dv += im.w[k] * kernel_derivative(Kernel::Blinn, s) * 2.0 * dot(detail::metric_apply(m, q), dn);
        continue;
      }
      const double s = squared_norm(q) * im.inv_r2[k];
      if (!(s < 1.0)) continue;
      v += im.w[k] * kernel_value(Kernel::Blinn, s);
      if (df) dv += im.w[k] * kernel_derivative(Kernel::Blinn, s) * 2.0 * dot(q, dn) * im.inv_r2[k];
    }
    if (df) *df = dv;
    return v - im.threshold;
  };
  // The step floor: a fraction of the smallest radius, but at most a million steps per
  // interval (a tiny radius beside a huge one marched for minutes; found by fuzzing).
  const double hmin = std::max(kBlinnMinStep * im.r_min, 1e-6 * (tb - ta));
  double t = ta, ft = f(ta, nullptr);
  const bool s0 = ft >= 0;
  if (!started) {
    started = true;
    if (ta <= tlo) inside = starts_inside = s0;
    else if (s0) emit(ta, 0.0, active);
  } else if (s0 != inside) {
    emit(ta, 0.0, active);
  }
  observe(std::abs(ft));
  double gap = std::abs(ft);
  while (t < tb && !done) {
    const double step = std::max(std::abs(ft) / lip, hmin);
    // nextafter: t + step rounds back to t where |t| is huge beside the step (an endless loop).
    const double tn = std::max(std::min(t + step, tb), std::nextafter(t, tb));
    const double fn = f(tn, nullptr);
    if ((fn >= 0) != (ft >= 0)) {
      // Safeguarded Newton inside the bracket [t, tn].
      double lo = t, hi = tn, x = 0.5 * (t + tn);
      const bool lo_in = ft >= 0;
      for (int it = 0; it < 100; ++it) {
        double dfx = 0;
        const double fx = f(x, &dfx);
        if ((fx >= 0) == lo_in) lo = x;
        else hi = x;
        if (hi - lo <= 4e-16 * (std::abs(x) + (tb - ta))) break;
        double nx = dfx != 0 ? x - fx / dfx : lo - 1;
        if (!(nx > lo && nx < hi)) nx = 0.5 * (lo + hi);
        if (std::abs(nx - x) <= 1e-16 * (std::abs(x) + (tb - ta))) {
          x = nx;
          break;
        }
        x = nx;
      }
      emit(x, gap, active);
      gap = 0;
      if (done) return;
    }
    gap = std::max(gap, std::abs(fn));
    observe(std::abs(fn));
    t = tn;
    ft = fn;
  }
  inside = ft >= 0;
}

void RayCaster::Impl::Query::offer(uint32_t k, Scratch& sc) {
  if (!im.aniso) {
    offer_sphere(k, im.pos[k], im.r2[k], im.inv_r2[k], im.w[k], sc);
    return;
  }
  // s(t) = (q + t dn)^T M (q + t dn) = ir2 (t - tstar)^2 + smin.
  const Vec3 q = o - im.pos[k];
  const double* m = &im.metric[6 * size_t(k)];
  const Vec3 Md = detail::metric_apply(m, dn);
  const double ir2 = dot(dn, Md);
  const double tstar = -dot(q, Md) / ir2;
  // The smallest s from the closest point itself (no cancellation for a far origin).
  const double smin = detail::metric_norm2(m, q + dn * tstar);
  const double h2 = (1.0 - smin) / ir2;
  if (h2 > 0) enter(k, tstar, smin / ir2, ir2, im.w[k], h2, sc);
}

void RayCaster::Impl::Query::enter(uint32_t k, double tstar, double e2, double ir2, double wk, double h2,
                                   Scratch& sc) {
  const double hh = std::sqrt(h2);
  const double t_in = tstar - hh, t_out = tstar + hh;
  if (t_out <= tlo || t_in >= thi) return;
  ++stats.spheres_entered;
  const uint32_t slot = uint32_t(sc.offered.size());
  Active& a = sc.offered.emplace_back();
  a.k = k;
  a.slot = slot;
  a.tstar = tstar;
  a.e2 = e2;
  a.ir2 = ir2;
  a.w = wk;
  sc.peaks.push_back(wk > 0 ? wk * kernel_value(im.kernel, e2 * ir2) : 0.0);
  sc.where.push_back(0);
  sc.entries.insert(std::max(t_in, tlo), slot, 0);
  sc.exits.insert(std::min(t_out, thi), slot, 1);
}

namespace {

// The hierarchy walked front to back for one ray, with a priority queue of nodes ordered by
// where the ray enters their boxes: its smallest entry is the horizon. (A depth-first stack
// is cheaper per step but walks whole subtrees along the ray: three times the nodes before a
// first hit, measured.)
struct HierarchySource {
  std::vector<NodeEntry>& heap;
  static bool cmp(const NodeEntry& a, const NodeEntry& b) { return a.t > b.t; }
  void push(double t, uint32_t node) {
    heap.push_back({t, node});
    std::push_heap(heap.begin(), heap.end(), cmp);
  }
  double horizon() const { return heap.empty() ? kInf : heap.front().t; }
  void advance(RayCaster::Impl::Query& query, Scratch& sc) {
    const NodeEntry ne = heap.front();
    std::pop_heap(heap.begin(), heap.end(), cmp);
    heap.pop_back();
    ++query.stats.nodes_visited;
    const Node& nd = query.im.nodes[ne.node];
    if (nd.count == 0) {
      for (uint32_t c = nd.first; c < nd.first + 2; ++c) {
        double tc;
        if (query.box(query.im.nodes[c], &tc)) push(tc, c);
      }
      return;
    }
    for (uint32_t k = nd.first; k < nd.first + nd.count; ++k) query.offer(k, sc);
  }
};

}  // namespace

void RayCaster::Impl::Query::run(Scratch& sc) {
  HierarchySource source{sc.nodes};
  source.heap.clear();
  if (im.nodes.empty()) return;
  double t_root;
  if (!box(im.nodes[0], &t_root)) return;
  source.push(t_root, 0);
  sweep(sc, source);
}

namespace detail {
Scratch& ray_scratch() {
  thread_local Scratch s;
  return s;
}

ProgressTracker*& ray_tracker() {
  thread_local ProgressTracker* tracker = nullptr;
  return tracker;
}
}  // namespace detail

RayCaster::RayCaster() : impl_(std::make_unique<Impl>()) {}
RayCaster::~RayCaster() = default;
RayCaster::RayCaster(RayCaster&&) noexcept = default;
RayCaster& RayCaster::operator=(RayCaster&&) noexcept = default;

RayCaster::RayCaster(ParticleField field) : impl_(std::make_unique<Impl>()) {
  impl_->field = std::move(field);
  if (impl_->field.size() == 0) throw Error(Status::InvalidInput, "the field has no particles");
  impl_->build();
}

const ParticleField& RayCaster::field() const { return impl_->field; }
size_t RayCaster::node_count() const { return impl_->nodes.size(); }

namespace {

void add_stats(RayStats* to, const RayStats& s) {
  if (!to) return;
  to->nodes_visited += s.nodes_visited;
  to->spheres_entered += s.spheres_entered;
  to->intervals += s.intervals;
  to->intervals_solved += s.intervals_solved;
}

}  // namespace

RayHits RayCaster::all_hits(const Vec3& origin, const Vec3& direction, double t_min, double t_max,
                            RayStats* stats) const {
  check_ray(origin, direction, 0, false);
  check_range(t_min, t_max);
  RayHits r;
  if (!impl_) return r;
  auto q = detail::make_query(*impl_, origin, direction, t_min, t_max, false, &r.hits);
  q.run(scratch());
  r.starts_inside = q.starts_inside;
  add_stats(stats, q.stats);
  return r;
}

std::optional<RayHit> RayCaster::first_hit(const Vec3& origin, const Vec3& direction, double t_min, double t_max,
                                           RayStats* stats) const {
  check_ray(origin, direction, 0, false);
  check_range(t_min, t_max);
  if (!impl_) return std::nullopt;
  Scratch& sc = scratch();
  auto& hits = sc.hits;
  hits.clear();
  auto q = detail::make_query(*impl_, origin, direction, t_min, t_max, true, &hits);
  q.run(sc);
  add_stats(stats, q.stats);
  if (hits.empty()) return std::nullopt;
  return hits.front();
}

namespace {

void check_batch(const Vec3* origins, const Vec3* directions, size_t n, const RaycastOptions& o) {
  check_range(o.t_min, o.t_max);
  if (n > 0 && (origins == nullptr || directions == nullptr))
    throw Error(Status::InvalidArgument, origins == nullptr ? "origins is NULL" : "directions is NULL");
  for (size_t i = 0; i < n; ++i) check_ray(origins[i], directions[i], i, true);
}

constexpr size_t kRayGrain = 256;

}  // namespace

FirstHits cast_first_hits(const RayCaster& caster, const Vec3* origins, const Vec3* directions, size_t n,
                          const RaycastOptions& options) {
  check_batch(origins, directions, n, options);
  detail::ProgressTracker tracker(options.progress);
  FirstHits r;
  r.t.assign(n, kInf);
  r.positions.assign(n, Vec3{});
  r.normals.assign(n, Vec3{});
  r.entering.assign(n, 0);
  tracker.stage("ray casting", 0.0, 1.0, (n + kRayGrain - 1) / kRayGrain);
  detail::with_threads(options.threads, [&] {
    detail::parallel_blocks(n, kRayGrain, [&](size_t begin, size_t end) {
      const detail::RayCancelScope scope(&tracker);
      for (size_t i = begin; i < end; ++i) {
        // Every ray: with a huge radius one ray sums thousands of particles per step.
        if (tracker.cancelled()) return;
        tracker.tick(0);
        const auto h = caster.first_hit(origins[i], directions[i], options.t_min, options.t_max);
        if (!h) continue;
        r.t[i] = h->t;
        r.positions[i] = h->position;
        r.normals[i] = h->normal;
        r.entering[i] = h->entering ? 1 : 0;
      }
      tracker.tick();
    });
  });
  tracker.check();
  for (size_t i = 0; i < n; ++i) r.hit_count += r.t[i] < kInf;
  tracker.finish();
  return r;
}

AllHits cast_all_hits(const RayCaster& caster, const Vec3* origins, const Vec3* directions, size_t n,
                      const RaycastOptions& options) {
  check_batch(origins, directions, n, options);
  detail::ProgressTracker tracker(options.progress);
  std::vector<RayHits> per(n);
  tracker.stage("ray casting", 0.0, 1.0, (n + kRayGrain - 1) / kRayGrain);
  detail::with_threads(options.threads, [&] {
    detail::parallel_blocks(n, kRayGrain, [&](size_t begin, size_t end) {
      const detail::RayCancelScope scope(&tracker);
      for (size_t i = begin; i < end; ++i) {
        if (tracker.cancelled()) return;  // every ray (see cast_first_hits)
        tracker.tick(0);
        per[i] = caster.all_hits(origins[i], directions[i], options.t_min, options.t_max);
      }
      tracker.tick();
    });
  });
  tracker.check();
  AllHits r;
  r.offsets.resize(n + 1);
  r.starts_inside.resize(n);
  r.offsets[0] = 0;
  for (size_t i = 0; i < n; ++i) {
    r.offsets[i + 1] = r.offsets[i] + per[i].hits.size();
    r.starts_inside[i] = per[i].starts_inside ? 1 : 0;
  }
  r.hits.reserve(r.offsets[n]);
  for (auto& p : per) r.hits.insert(r.hits.end(), p.hits.begin(), p.hits.end());
  tracker.finish();
  return r;
}

}  // namespace particlemesh
