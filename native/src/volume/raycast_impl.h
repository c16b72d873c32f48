// Internal: the ray caster's hierarchy and its front-to-back sweep (raycast.h), shared by the
// per-ray queries (raycast.cpp) and the camera's tiles of rays (ray_tiles.cpp).
#pragma once

#include "particlemesh/core/config.h"

#include <algorithm>
#include <cstdint>
#include <limits>
#include <vector>

#include "particlemesh/volume/raycast.h"
#include "volume/anisotropy_impl.h"
#include "volume/ray_cancel.h"

namespace PM_NAMESPACE {

namespace detail {

struct Node {
  double lo[3], hi[3];
  uint32_t first = 0;  // leaf: first particle; inner: first child (the second is first + 1)
  uint32_t count = 0;  // leaf: particles (> 0); inner: 0
};

// A particle whose support the ray is in, with the ray's closest approach to its centre:
// s(t) = (e2 + (t - tstar)^2) ir2 (unit direction), so an interval's polynomial needs no
// vector arithmetic. A sphere: ir2 = 1 / R^2 and e2 the squared distance of the centre from
// the line. An ellipsoid (s = d^T M d): ir2 = dn^T M dn, the same form with tstar where s is
// smallest along the line and e2 = that smallest s / ir2.
struct Active {
  uint32_t k;
  uint32_t slot;  // its place in Scratch::offered
  double tstar, e2, ir2;
  double w;  // the particle's strength
};

struct Event {
  double t;
  uint32_t slot;  // the particle in Scratch::offered
  uint32_t exit;  // 0 or 1 (a whole word: no partial store to stall the copy of an event)
};

struct NodeEntry {
  double t;
  uint32_t node;
};

// Events not yet applied, by increasing t from `head` on. A support found later mostly
// begins and ends later than those found before it (the sources offer them roughly front to
// back), so an event is inserted by a search from the end, moving few or none.
struct EventQueue {
  std::vector<Event> v;
  size_t head = 0;
  bool empty() const { return head == v.size(); }
  size_t size() const { return v.size() - head; }
  const Event& front() const { return v[head]; }
  const Event& second() const { return v[head + 1]; }
  void pop() {
    if (++head == v.size()) clear();
  }
  void clear() {
    v.clear();
    head = 0;
  }
  void insert(double t, uint32_t slot, uint32_t exit) {
    size_t i = v.size();
    v.emplace_back();
    for (; i > head && v[i - 1].t > t; --i) v[i] = v[i - 1];
    v[i].t = t;  // field by field: a whole event assembled first would stall its copy
    v[i].slot = slot;
    v[i].exit = exit;
  }
};

// Per-thread scratch, so queries allocate nothing once warm.
struct Scratch {
  std::vector<NodeEntry> nodes;  // min-heap of nodes to visit, by entry t
  // The events not yet applied, entries and exits apart (the entries wait only for the
  // horizon, the exits are the active particles').
  EventQueue entries, exits;
  std::vector<Active> offered;   // the particles whose supports the ray meets, as found
  std::vector<double> peaks;     // per offered particle: w g(e2 ir2) if w > 0, else 0
  std::vector<uint32_t> where;   // per offered particle: its place in `active` while there
  std::vector<Event> batch;      // the events at one t, applied in a canonical order
  std::vector<Active> active;
  std::vector<RayHit> hits;
};

/// This thread's scratch.
Scratch& ray_scratch();

/// The caster's internals, for the camera's tiles.
struct RayCasterAccess {
  static const RayCaster::Impl* of(const RayCaster& c) { return c.impl_.get(); }
};

}  // namespace detail

struct RayCaster::Impl {
  using Node = detail::Node;
  using Active = detail::Active;
  using Event = detail::Event;
  using Scratch = detail::Scratch;

  ParticleField field;
  Kernel kernel = Kernel::Wyvill;
  bool blinn = false;
  int kdeg = 0;                  // degree of the kernel in s
  double d[kKernelMaxDegree + 1]{};  // the kernel in tau = 1 - s: g = sum d_i tau^i
  double threshold = 0;
  double eps_f = 0;              // tangent tolerance in units of F
  double r_min = 0;
  // The most any particle's value changes per unit t along a unit-speed ray: max over s of
  // 2 sqrt(s) |g'(s)| x wmax / r_min, rounded up (build()); 0 for Blinn (no running bound).
  double slope = 0;
  bool aniso = false;            // ellipsoidal kernels (metric per particle)
  std::vector<Vec3> pos;         // kernel centres in hierarchy order
  std::vector<double> r2, inv_r2, w;
  std::vector<double> metric;    // anisotropic: 6 per particle, hierarchy order
  std::vector<double> bound_r;   // radius of a ball around the support (spheres: R)
  std::vector<Node> nodes;

  void build();

  // ---- one query ------------------------------------------------------------------------
  struct Query {
    explicit Query(const Impl& impl) : im(impl) {}
    const Impl& im;
    Vec3 o, dn;          // origin, unit direction
    double len = 1;      // |direction| as given: t_user = t / len
    double tlo = 0, thi = 0;
    double inv[3]{};
    bool zero[3]{};
    bool first_only = false;
    RayStats stats;
    // sweep state
    bool started = false;
    bool inside = false;
    bool starts_inside = false;
    bool has_pending = false;
    RayHit pending;
    double height = 0;   // max |F - T| sampled since the pending crossing
    bool done = false;
    // The running bound of F outside the surface (interval_bounded()): on [ta, tb], tb >= rb_t,
    // F is at most rb_f + min(rb_rate (tb - rb_t), rb_room) + for the particles entered since,
    // the smaller of their peaks' sum and their count x slope x (tb - rb_t).
    bool rb_valid = false;
    double rb_f = 0, rb_rate = 0, rb_room = 0, rb_t = 0, rb_entered = 0;
    size_t rb_count = 0;
    std::vector<RayHit>* out = nullptr;

    bool box(const Node& n, double* t_enter) const {
      double t0 = tlo, t1 = thi;
      for (int a = 0; a < 3; ++a) {
        const double oa = o[a];
        if (zero[a]) {
          if (oa < n.lo[a] || oa > n.hi[a]) return false;
          continue;
        }
        double ta = (n.lo[a] - oa) * inv[a], tb = (n.hi[a] - oa) * inv[a];
        if (ta > tb) std::swap(ta, tb);
        t0 = std::max(t0, ta);
        t1 = std::min(t1, tb);
        if (t0 > t1) return false;
      }
      *t_enter = t0;
      return true;
    }

    void finalize() {
      if (!has_pending) return;
      has_pending = false;
      out->push_back(pending);
      if (first_only) done = true;
    }

    void observe(double h) {
      height = std::max(height, h);
      if (has_pending && height > im.eps_f) finalize();
    }

    // A change of state at internal t, with `gap` the largest |F - T| sampled since the
    // previous sample (tangent rule: a pair with nothing above eps_f between them is a touch).
    void emit(double t, double gap, const std::vector<Active>& active) {
      const double h = std::max(height, gap);
      const bool entering = !inside;
      inside = !inside;
      if (has_pending && h <= im.eps_f) {
        has_pending = false;  // the pair is a touch: drop both
        height = 0;
        return;
      }
      finalize();
      if (done) return;
      RayHit hit;
      hit.t = t / len;
      hit.position = o + dn * t;
      Vec3 g{};
      for (const Active& a : active) {
        const uint32_t k = a.k;
        const Vec3 q = hit.position - im.pos[k];
        if (im.aniso) {
          const double* m = &im.metric[6 * size_t(k)];
          const double dg = kernel_derivative(im.kernel, detail::metric_norm2(m, q));
          g += detail::metric_apply(m, q) * (2.0 * im.w[k] * dg);
          continue;
        }
        const double s = squared_norm(q) * im.inv_r2[k];
        const double dg = kernel_derivative(im.kernel, s);
        g += q * (2.0 * im.w[k] * im.inv_r2[k] * dg);
      }
      hit.normal = normalized(-g);
      hit.entering = entering;
      pending = hit;
      has_pending = true;
      height = 0;
    }

    // The interval [ta, tb] between two events, with the active particles' peaks' sum, the
    // sum of every peak added since the active list was last empty, and every peak and
    // particle entered so far (the sweep's running sums). The cheap cases here, inlined into
    // the sweep (about half the intervals before the surface end here); the rest in
    // interval_bounded().
    void interval(double ta, double tb, const std::vector<Active>& active, double peak_sum, double peak_added,
                  double peaks_entered, size_t count_entered) {
      if (active.empty()) {
        // Outside every support: F = 0 < T.
        if (started && inside) emit(ta, 0.0, active);
        started = true;
        observe(im.threshold);
        return;
      }
      ++stats.intervals;
      // Outside, where no crossing waits for the tangent rule (so that the size of the margin
      // observed does not matter): the sum of the active particles' peaks bounds the field's
      // upper bound (interval_bounded()) term by term (both rounded upwards alike, in the same
      // order), with room for the rounding of its running total. Below T: excluded, as that
      // bound would have excluded it.
      if ((!started || !inside) && !has_pending && peak_sum + 1e-9 * peak_added < im.threshold) {
        if (!started && ta <= tlo) starts_inside = false;
        started = true;
        inside = false;
        observe(im.threshold - peak_sum);
        return;
      }
      interval_bounded(ta, tb, active, peaks_entered, count_entered);
    }
    // The rest: the running bound, the field's upper bound, the interval's polynomial.
    void interval_bounded(double ta, double tb, const std::vector<Active>& active, double peaks_entered,
                          size_t count_entered);
    void interval_blinn(double ta, double tb, const std::vector<Active>& active);
    // The sphere (or ellipsoid) of particle k: its entry and exit events, if the ray meets it.
    void offer(uint32_t k, Scratch& sc);
    // The same for a sphere given by its centre, R^2, 1 / R^2 and strength (as offer()
    // reads them from the caster).
    void offer_sphere(uint32_t k, const Vec3& p, double r2, double ir2, double w, Scratch& sc) {
      const Chord c = chord(p, r2);
      if (c.h2 > 0) enter(k, c.tstar, c.e2, ir2, w, c.h2, sc);
    }
    // Where the line meets the sphere of centre p and squared radius r2: its closest
    // approach tstar, the squared distance e2 from p there, and the squared half chord h2
    // (> 0 where it meets it).
    struct Chord {
      double tstar, e2, h2;
    };
    Chord chord(const Vec3& p, double r2) const {
      const Vec3 q = o - p;
      const double b = dot(q, dn);
      const Vec3 e = q - dn * b;  // from the centre to the closest point of the line
      const double e2 = squared_norm(e);
      return {-b, e2, r2 - e2};
    }
    // A support the line meets (half chord h2 > 0; the Active's fields): its events, if
    // within [tlo, thi].
    void enter(uint32_t k, double tstar, double e2, double ir2, double w, double h2, Scratch& sc);
    // The front-to-back sweep (below), fed by a source of particles: source.horizon() is a
    // lower bound of the entry of every particle it has not offered yet (+inf when none are
    // left), source.advance(query, scratch) offers some more through offer().
    template <class Source>
    void sweep(Scratch& sc, Source& source);
    // The sweep fed by the hierarchy, walked for this ray alone.
    void run(Scratch& sc);
  };
};

namespace detail {

/// A query of the ray origin + t direction, t_min <= t <= t_max (checked by the caller).
inline RayCaster::Impl::Query make_query(const RayCaster::Impl& im, const Vec3& origin, const Vec3& direction,
                                  double t_min, double t_max, bool first_only, std::vector<RayHit>* out) {
  RayCaster::Impl::Query q(im);
  q.o = origin;
  q.len = norm(direction);
  q.dn = direction / q.len;
  q.tlo = t_min * q.len;
  q.thi = t_max * q.len;
  for (int a = 0; a < 3; ++a) {
    q.zero[a] = q.dn[a] == 0;
    q.inv[a] = q.zero[a] ? 0.0 : 1.0 / q.dn[a];
  }
  q.first_only = first_only;
  q.out = out;
  return q;
}

}  // namespace detail

// Walks the events in increasing t. No particle the source has not offered yet begins before
// its horizon, so the intervals up to there are final and are solved as soon as the horizon
// passes them; a first-hit query stops at its first crossing without offering the particles
// behind it. The intervals' ends are the events' t, whatever order the particles were found
// in; the events at one t are applied in a canonical order (entries, then exits, each by
// particle) so that the active list, and the order of the sums over it, does not depend on
// that order either: every source gives the same hits, bit for bit.
template <class Source>
void RayCaster::Impl::Query::sweep(Scratch& sc, Source& source) {
  auto& entries = sc.entries;
  auto& exits = sc.exits;
  auto& batch = sc.batch;
  auto& active = sc.active;
  const auto& offered = sc.offered;
  const auto& peaks = sc.peaks;
  entries.clear();
  exits.clear();
  active.clear();
  sc.offered.clear();
  sc.peaks.clear();
  sc.where.clear();
  constexpr double kNone = std::numeric_limits<double>::infinity();
  // The running sums in locals, handed to interval() (updating members as a pair and alone
  // stalled the loads that forward them): over the active particles of positive strength,
  // the sum of their largest values along the whole ray, w g(e2 ir2), kept as they enter and
  // leave, and the sum of every value added since the active list was last empty (bounds the
  // rounding of the former); every peak and particle entered so far.
  double psum = 0, padded = 0, entered = 0;
  size_t n_entered = 0;
  auto& where = sc.where;
  // One event applied: an entry appends the particle, an exit moves the last one into its
  // place (each particle is offered once, so its exit follows its entry).
  auto apply = [&](const Event& e) {
    const double peak = peaks[e.slot];
    if (e.exit) {
      const uint32_t i = where[e.slot];
      active[i] = active.back();
      where[active[i].slot] = i;
      active.pop_back();
      psum -= peak;
      if (active.empty()) psum = padded = 0;
    } else {
      where[e.slot] = uint32_t(active.size());
      active.push_back(offered[e.slot]);
      psum += peak;
      padded += peak;
      entered += peak;
      ++n_entered;
    }
  };
  double cur = tlo;
  uint32_t since_check = 0;  // intervals and particle offers since the last cancellation check
  while (!done) {
    if (++since_check >= 32) {
      since_check = 0;
      if (detail::ray_cancelled()) return;  // abandoned: the batch throws Cancelled
    }
    // Strictly before the horizon: events at it may have partners (the same t) not yet found.
    const double horizon = source.horizon();
    while (!done) {
      const double tn = entries.empty() ? kNone : entries.front().t;
      const double tx = exits.empty() ? kNone : exits.front().t;
      const double te = std::min(tn, tx);
      if (!(te < horizon)) break;
      if (te > cur) {
        interval(cur, te, active, psum, padded, entered, n_entered);
        cur = te;
        if (done) break;
        if (++since_check >= 32) {
          since_check = 0;
          if (detail::ray_cancelled()) return;
        }
      }
      // The events at te: one alone (the common case) is applied as it is; several in the
      // canonical order.
      const bool more_n = tn == te && entries.size() > 1 && entries.second().t == te;
      const bool more_x = tx == te && exits.size() > 1 && exits.second().t == te;
      if (!more_n && !more_x && !(tn == te && tx == te)) {
        auto& from = tn == te ? entries : exits;
        apply(from.front());
        from.pop();
        continue;
      }
      batch.clear();
      while (!entries.empty() && entries.front().t == te) {
        batch.push_back(entries.front());
        entries.pop();
      }
      while (!exits.empty() && exits.front().t == te) {
        batch.push_back(exits.front());
        exits.pop();
      }
      std::sort(batch.begin(), batch.end(), [&](const Event& a, const Event& b) {
        return a.exit != b.exit ? b.exit : offered[a.slot].k < offered[b.slot].k;
      });
      for (const Event& e : batch) apply(e);
    }
    if (done || horizon == std::numeric_limits<double>::infinity()) break;  // (events are finite)
    source.advance(*this, sc);
  }
  if (!done) {
    // Past the last support (F = 0 < T), unless the range ended inside one first.
    if (cur < thi) {
      if (started && inside) emit(cur, 0.0, active);
      observe(im.threshold);
    }
    finalize();
  }
}

}  // namespace particlemesh
