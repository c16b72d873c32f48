#include "volume/surface_vertices.h"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstring>
#include <limits>
#include <span>

#include "core/cpu_clones.h"
#include "volume/field_impl.h"
#include "volume/mc_table.h"

namespace PM_NAMESPACE::detail {

void EdgeNeighbours::gather(const ParticleField& field, const Vec3& a, int axis, double h) {
  field_ = &field;
  axis_ = axis;
  const double R = field.params().radius;
  inv_r2_ = 1.0 / (R * R);  // as the field's own
  if (axis == 0) gather_along<0>(field, a, h);
  else if (axis == 1) gather_along<1>(field, a, h);
  else gather_along<2>(field, a, h);
}

template <int A>
void EdgeNeighbours::gather_along(const ParticleField& field, const Vec3& a, double h) {
  constexpr int U = (A + 1) % 3, W = (A + 2) % 3;
  const double r = field.cell_reach();
  const double r2 = r * r;
  const NeighborGrid& grid = field.grid();
  // The points on the edge are a + t h e_axis, 0 <= t <= 1, computed as at() in refine():
  // their query boxes [x - r, x + r] lie in the box of the two ends' (rounding is monotone).
  Vec3 b = a;
  (A == 0 ? b.x : A == 1 ? b.y : b.z) += h;
  const Vec3 rv{r, r, r};
  // A particle is kept if its distance to the segment is within r: any point of the edge
  // that has it within r (by the field's rounded test) has it within r (1 + 1e-12) exactly.
  const double keep2 = r2 * (1.0 + 1e-12);
  const double lo_a = get<A>(a), hi_a = get<A>(b);
  const double au = get<U>(a), aw = get<W>(a);
  // The box's cells a column at a time (a run of consecutive particles; along z each cell is
  // a run of its own, for its coordinate on the edge's axis), in the field's cell order; then
  // their particles into room for all of them, each written and kept or not without a branch
  // (about half are dropped, in no predictable pattern).
  size_t room = 0;
  const NeighborGrid::CellCoord box_lo = grid.coord_of(a - rv), box_hi = grid.coord_of(b + rv);
  box_lo_ = box_lo[A];
  box_hi_ = box_hi[A];
  // Room for the most runs the box can have (one per cell: along z, or without the dense
  // table), written through a pointer rather than pushed back one at a time.
  const size_t most_runs = size_t(box_hi[0] - box_lo[0] + 1) * size_t(box_hi[1] - box_lo[1] + 1) *
                           size_t(box_hi[2] - box_lo[2] + 1);
  Box* found = nullptr;
  const auto same = [](const NeighborGrid::CellCoord& p, const NeighborGrid::CellCoord& q) {
    return p[0] == q[0] && p[1] == q[1] && p[2] == q[2];  // (std::array's == calls memcmp)
  };
  for (Box& b : boxes_[A])
    if (b.field == &field && same(b.lo, box_lo) && same(b.hi, box_hi)) found = &b;
  if (found == nullptr) {
    // Not among the last ones: the oldest box's place takes this one's runs.
    Box& box = boxes_[A][next_box_[A]++ % kBoxes];
    if (box.runs.size() < most_runs) box.runs.resize(most_runs);
    Run* const runs = box.runs.data();
    size_t count = 0;
    field.for_each_column_in(box_lo, box_hi, [&](uint32_t c0, uint32_t c1) {
      if constexpr (A == 2) {
        for (uint32_t c = c0; c < c1; ++c) runs[count++] = {grid.cell_begin(c), grid.cell_end(c), grid.cell_coord(c)[2]};
      } else {
        runs[count++] = {grid.cell_begin(c0), grid.cell_begin(c1), grid.cell_coord(c0)[A]};
      }
      room += grid.cell_begin(c1) - grid.cell_begin(c0);
    });
    box.field = &field, box.lo = box_lo, box.hi = box_hi, box.count = count, box.room = room;
    found = &box;
  }
  room = found->room;
  const Run* const runs = found->runs.data();
  const size_t run_count = found->count;
  if (near_.size() < room) near_.resize(room);
  Near* const out = near_.data();
  const Vec3* const points = grid.sorted_points().data();
  size_t n = 0;
  // Each entry is written as one 8-byte word, {s, cell} in Near's layout (sorted index in the
  // low half): one store a particle instead of two, and the loop's counter is that word.
  static_assert(sizeof(Near) == 8 && offsetof(Near, sorted) == 0 && offsetof(Near, cell) == 4);
  for (const Run& run : std::span<const Run>(runs, run_count)) {
    const uint64_t tag = uint64_t(uint32_t(run.cell)) << 32;
    const Vec3* p = points + run.begin;
    for (uint64_t word = tag | run.begin, end = tag | run.end; word != end; ++word, ++p) {
      const double pa = get<A>(*p);
      const double da = pa - std::clamp(pa, lo_a, hi_a), du = get<U>(*p) - au, dw = get<W>(*p) - aw;
      std::memcpy(out + n, &word, sizeof word);
      n += da * da + du * du + dw * dw <= keep2;
    }
  }
  count_ = n;
  // The kept particles by coordinate, where sum_by_coordinate will read them: read back from
  // the grid (in cache), a pair at a time; an odd count gets a pad whose cell (NaN) fails
  // every test.
  if (one_radius_unit_strengths(field) && field.kernel() != Kernel::Blinn) {
    stride_ = (n + 1) & ~size_t(1);
    if (columns_.size() < 4 * stride_) columns_.resize(4 * stride_);
    double* const cx = columns_.data();
    double* const cy = cx + stride_;
    double* const cz = cy + stride_;
    double* const cc = cz + stride_;
    for (size_t k = 0; k < n; ++k) {
      const Vec3& p = points[out[k].sorted];
      cx[k] = p.x, cy[k] = p.y, cz[k] = p.z, cc[k] = double(out[k].cell);
    }
    if (n != stride_) cx[n] = cy[n] = cz[n] = 0.0, cc[n] = std::numeric_limits<double>::quiet_NaN();
  }
  // The particles kept apart from the cells (radii far above the rest), by their own radius.
  apart_.clear();
  const std::vector<double>& inv_r2s = field.sorted_inverse_squared_radii();
  for (uint32_t s = grid.apart_begin(); s < grid.point_count(); ++s) {
    const Vec3& p = points[s];
    const double pa = get<A>(p);
    const double da = pa - std::clamp(pa, lo_a, hi_a), du = get<U>(p) - au, dw = get<W>(p) - aw;
    if ((da * da + du * du + dw * dw) * inv_r2s[s] <= 1.0 + 1e-12) apart_.push_back(s);
  }
}

namespace {

// Two doubles, one SSE2 (or NEON) register: GCC/Clang vector extensions, as sampling_rows.h.
typedef double Double2 __attribute__((vector_size(2 * sizeof(double))));
typedef int64_t Long2 __attribute__((vector_size(2 * sizeof(int64_t))));

inline Double2 load2(const double* p) {
  Double2 v;
  std::memcpy(&v, p, sizeof v);
  return v;
}
// v where the mask is set, else +0.0 (all bits clear).
inline Double2 masked(Double2 v, Long2 keep) { return (Double2)((Long2)v & keep); }

/// EdgeNeighbours::sum_by_coordinate's loop over the columns from cx (x, then y, z and cells,
/// `stride` apart), compiled per x86-64 level (PM_CPU_CLONES: with AVX-512 the loop takes a
/// third less time).
template <Kernel K>
PM_CPU_CLONES double sum_columns(const double* cx, size_t stride, const Vec3& x, double r, double inv_r2, int32_t lo,
                                 int32_t hi, Vec3* gradient) {
  // sum<K, false, AllCells>'s arithmetic, term for term, for two particles at once: the
  // difference, its square, the kernel and its derivative with their products in the same
  // order, the tests as masks. Each term is then added to the running sums one particle after
  // the other, in the gathered order, so the sums are sum()'s bit for bit: a particle that
  // fails a test adds +0.0 where sum() adds nothing, which changes no sum (a sum that starts
  // at +0.0 is never -0.0 under round-to-nearest, and s + 0.0 = s for every other s). The
  // scalar loop's two unpredictable tests a particle (about one in ten fails them) and its
  // serial products were most of its time; the chain of additions is what is left.
  const Double2 X = {x.x, x.x}, Y = {x.y, x.y}, Z = {x.z, x.z};
  const Double2 R2 = {r * r, r * r}, inv = {inv_r2, inv_r2}, two_inv = {2.0 * inv_r2, 2.0 * inv_r2};
  const Double2 LO = {double(lo), double(lo)}, HI = {double(hi), double(hi)};
  const double* const cy = cx + stride;
  const double* const cz = cy + stride;
  const double* const cc = cz + stride;
  double v = 0, gx = 0, gy = 0, gz = 0;
  for (size_t k = 0; k < stride; k += 2) {
    const Double2 dx = X - load2(cx + k), dy = Y - load2(cy + k), dz = Z - load2(cz + k);
    const Double2 d2 = dx * dx + dy * dy + dz * dz;
    const Double2 q = d2 * inv;
    const Double2 c = load2(cc + k);
    const Long2 keep = (d2 <= R2) & (q < 1.0) & (c >= LO) & (c <= HI);
    const Double2 t = 1.0 - q;
    Double2 value, derivative;
    if constexpr (K == Kernel::Wyvill) {
      value = t * t * (5.0 + 4.0 * t) * (1.0 / 9.0);
      derivative = -t * (10.0 + 12.0 * t) * (1.0 / 9.0);
    } else if constexpr (K == Kernel::Poly4) {
      value = t * t;
      derivative = -2.0 * t;
    } else {
      static_assert(K == Kernel::Poly6);
      value = t * t * t;
      derivative = -3.0 * t * t;
    }
    const Double2 s = two_inv * derivative;
    const Double2 tv = masked(value, keep), tx = masked(dx * s, keep), ty = masked(dy * s, keep),
                  tz = masked(dz * s, keep);
    v += tv[0], gx += tx[0], gy += ty[0], gz += tz[0];
    v += tv[1], gx += tx[1], gy += ty[1], gz += tz[1];
  }
  *gradient = {gx, gy, gz};
  return v;
}

}  // namespace

template <Kernel K>
double EdgeNeighbours::sum_by_coordinate(const Vec3& x, Vec3* gradient, int32_t lo, int32_t hi) const {
  return sum_columns<K>(columns_.data(), stride_, x, field_->cell_reach(), inv_r2_, lo, hi, gradient);
}

template <Kernel K, bool General, bool AllCells>
double EdgeNeighbours::sum(const Vec3& x, Vec3* gradient, int32_t lo, int32_t hi) const {
  // ParticleField::value_and_gradient's spherical branch, over the gathered particles that
  // its query at x would visit (the cells along the other axes are the edge's). Not General:
  // one radius, unit strengths and a gradient asked for (the same arithmetic, without the
  // tests for the others in the loop). AllCells: the query's cells along the edge's axis hold
  // the whole gathered box's (most points of an edge: its box is a quarter cell longer), so
  // every gathered particle passes the cell test.
  const ParticleField& field = *field_;
  const double r = field.cell_reach();
  const double r2 = r * r;
  const NeighborGrid& grid = field.grid();
  const bool uniform = !General || field.uniform_radius();
  const double* inv_r2s = field.sorted_inverse_squared_radii().data();
  const double* ws = field.sorted_strengths().data();
  const bool unit = !General || field.sorted_strengths().empty();
  const bool with_gradient = !General || gradient != nullptr;
  const Vec3* points = grid.sorted_points().data();
  const Near* near = near_.data();
  const Vec3 xl = x;
  const double inv_r2_uniform = inv_r2_;
  double v = 0;
  Vec3 g{};
  if constexpr (!General) {
    // The same sum with the difference x - p computed once: its squares are those of p - x
    // (squared_distance's), and it is the gradient's direction as is; 2 w / R^2 (w = 1) is
    // the same product for every particle.
    const double two_inv_r2 = 2.0 * inv_r2_uniform;
    for (size_t k = 0; k < count_; ++k) {
      const Near n = near[k];
      if (!AllCells && (n.cell < lo || n.cell > hi)) continue;
      const Vec3 d = xl - points[n.sorted];
      const double d2 = squared_norm(d);
      if (!(d2 <= r2)) continue;
      const double q = d2 * inv_r2_uniform;
      if (!(q < 1.0)) continue;
      v += kernel_value_t<K>(q);
      g += d * (two_inv_r2 * kernel_derivative_t<K>(q));
    }
    *gradient = g;
    return v;
  }
  for (size_t k = 0; k < count_; ++k) {
    const Near n = near[k];
    if (!AllCells && (n.cell < lo || n.cell > hi)) continue;
    const Vec3& p = points[n.sorted];
    const double d2 = squared_distance(p, xl);
    if (!(d2 <= r2)) continue;
    const double inv_r2 = uniform ? inv_r2_uniform : inv_r2s[n.sorted];
    const double q = d2 * inv_r2;
    if (!(q < 1.0)) continue;
    const double w = unit ? 1.0 : ws[n.sorted];
    v += w * kernel_value_t<K>(q);
    if (with_gradient) g += (xl - p) * (2.0 * w * inv_r2 * kernel_derivative_t<K>(q));
  }
  // The particles kept apart (none with one radius: General only), as the field adds them.
  for (const uint32_t t : apart_) {
    const Vec3& p = points[t];
    const double inv_r2 = inv_r2s[t];
    const double q = squared_distance(p, xl) * inv_r2;
    if (!(q < 1.0)) continue;
    const double w = unit ? 1.0 : ws[t];
    v += w * kernel_value_t<K>(q);
    if (with_gradient) g += (xl - p) * (2.0 * w * inv_r2 * kernel_derivative_t<K>(q));
  }
  if (with_gradient) *gradient = g;
  return v;
}

double EdgeNeighbours::value_and_gradient(const Vec3& x, Vec3* gradient) const {
  const bool general = !one_radius_unit_strengths(*field_) || gradient == nullptr;
  const double r = field_->cell_reach();
  const NeighborGrid& grid = field_->grid();
  // The cells along the edge's axis that the field's query at x visits.
  const int32_t lo = grid.coord_on_axis(x[axis_] - r, axis_), hi = grid.coord_on_axis(x[axis_] + r, axis_);
  const bool all_cells = lo <= box_lo_ && hi >= box_hi_;
  return dispatch_kernel(field_->kernel(), [&]<Kernel K>() {
    if (general) return sum<K, true, false>(x, gradient, lo, hi);
    if constexpr (K != Kernel::Blinn) return sum_by_coordinate<K>(x, gradient, lo, hi);
    return all_cells ? sum<K, false, true>(x, gradient, lo, hi) : sum<K, false, false>(x, gradient, lo, hi);
  });
}

namespace {

// The step (in edges) below which a crossing is taken as found.
constexpr double kStep = 1e-2;

// The crossing on the edge, phi(t) = F(a + t h e_axis) - T, by safeguarded Newton steps
// corrected for the curvature (eval(x, &gradient) is F(x)). Each step goes to the root of
// phi + phi' u + c u^2 nearer the evaluated point, c = phi''/2 estimated from what is known:
// at the first evaluation from the node sample at the farther end of the edge (the quadratic
// through it with the evaluated value and slope), afterwards from the slopes of the last two
// evaluations. Such a step leaves an error of the order of the third derivative times
// step^3, where Newton's leaves (phi''/2phi') step^2: on curved fields (a thin layer of
// particles bends its field within a cell) about a quarter fewer evaluations end closer to
// the iso-surface. The bracket [lo, hi] of the sign change catches a step leaving it
// (bisection). A first Newton step already below kStep is taken as is (as before): the far
// end's curvature is no better than none that close to the root.
template <class Eval>
Crossing refine(const Eval& eval, const Vec3& a, int axis, double h, double fa, double fb, double T) {
  Crossing out;
  double lo = 0, hi = 1;
  const double phi_lo = fa - T;  // sign at t = 0
  double t = std::clamp((T - fa) / (fb - fa), kEdgeClamp, 1.0 - kEdgeClamp);
  // The last evaluation (point, gradient, slope along the edge) and the one before it.
  Vec3 grad{}, prev_grad{};
  double last_t = 0, last_dphi = 0, prev_t = 0, prev_dphi = 0;
  bool two = false;  // two evaluations at distinct points
  auto at = [&](double tt) {
    Vec3 x = a;
    (axis == 0 ? x.x : axis == 1 ? x.y : x.z) += tt * h;
    return x;
  };
  for (int it = 0; it < 8; ++it) {
    if (it > 0) {
      prev_grad = grad;
      prev_t = last_t;
      prev_dphi = last_dphi;
    }
    const double phi = eval(at(t), &grad) - T;
    ++out.evaluations;
    last_t = t;
    last_dphi = grad[axis] * h;
    two = it > 0 && last_t != prev_t;
    if (phi == 0) break;
    if ((phi < 0) == (phi_lo < 0)) lo = t; else hi = t;
    const double dphi = last_dphi;
    double next = 0.5 * (lo + hi);
    if (dphi != 0 && !two && std::abs(phi / dphi) < kStep) {
      next = t - phi / dphi;
    } else if (dphi != 0) {
      double c;
      if (two) {
        c = (dphi - prev_dphi) / (2.0 * (t - prev_t));
      } else {
        const double u = t > 0.5 ? -t : 1.0 - t;  // to the farther end, at least half an edge
        c = ((t > 0.5 ? fa : fb) - T - phi - dphi * u) / (u * u);
      }
      const double disc = dphi * dphi - 4.0 * c * phi;
      if (std::isfinite(c) && disc >= 0) {
        // The root nearer t, in the form without cancellation.
        const double q = dphi + (dphi > 0 ? std::sqrt(disc) : -std::sqrt(disc));
        next = t - 2.0 * phi / q;
      } else {
        next = t - phi / dphi;
      }
    }
    if (!(next > lo && next < hi)) next = 0.5 * (lo + hi);
    const double step = std::abs(next - t);
    t = next;
    // After a step below kStep of the edge the root is close (median 2e-8 h, 99 % within 4e-5 h
    // on a thin shell of particles, the most curved field measured): that last step is taken
    // without another evaluation.
    if (step < kStep) break;
  }
  t = std::clamp(t, kEdgeClamp, 1.0 - kEdgeClamp);
  out.position = at(t);
  // The normal: the gradient carried from the last evaluation to the vertex (up to a
  // hundredth of an edge away) along the line through the last two.
  Vec3 n = grad;
  if (two) {
    const Vec3 moved = grad + (grad - prev_grad) * ((t - last_t) / (last_t - prev_t));
    const double mn = norm(moved);
    if (mn > 0 && std::isfinite(mn)) n = moved;
  }
  const double gn = norm(n);
  if (gn > 0 && std::isfinite(gn)) {
    out.normal = n * (-1.0 / gn);
  } else {
    // No gradient (a flat spot): fall back to the edge direction, from inside to outside.
    Vec3 e{};
    (axis == 0 ? e.x : axis == 1 ? e.y : e.z) = fa >= T ? 1.0 : -1.0;
    out.normal = e;
  }
  return out;
}

}  // namespace

Crossing refine_crossing(const ParticleField& field, const Vec3& a, int axis, double h, double fa, double fb,
                         double T) {
  return refine([&](const Vec3& x, Vec3* g) { return field.value_and_gradient(x, g); }, a, axis, h, fa, fb, T);
}

Crossing refine_crossing(const EdgeNeighbours& near, const Vec3& a, int axis, double h, double fa, double fb,
                         double T) {
  return refine([&](const Vec3& x, Vec3* g) { return near.value_and_gradient(x, g); }, a, axis, h, fa, fb, T);
}

Crossing center_vertex(const ParticleField& field, const Vec3& cell_lo, double h, const float cv[8],
                       const uint8_t* loop, int len, double T) {
  Crossing out;
  Vec3 x{};
  for (int k = 0; k < len; ++k) {
    const int e = loop[k];
    const int lc = mc_edge_lower_corner(e), axis = mc_edge_axis(e);
    const double f0 = cv[lc], f1 = cv[lc + (1 << axis)];
    const double t = std::clamp((T - f0) / (f1 - f0), 0.0, 1.0);
    Vec3 p{double(lc & 1), double((lc >> 1) & 1), double((lc >> 2) & 1)};
    (axis == 0 ? p.x : axis == 1 ? p.y : p.z) += t;
    x += p;
  }
  x = cell_lo + x * (h / len);
  Vec3 grad{};
  for (int it = 0; it < 6; ++it) {
    const double phi = field.value_and_gradient(x, &grad) - T;
    ++out.evaluations;
    const double g2 = squared_norm(grad);
    if (!(g2 > 0) || phi == 0) break;
    Vec3 next = x - grad * (phi / g2);
    next = {std::clamp(next.x, cell_lo.x, cell_lo.x + h), std::clamp(next.y, cell_lo.y, cell_lo.y + h),
            std::clamp(next.z, cell_lo.z, cell_lo.z + h)};
    const double step = distance(next, x);
    x = next;
    if (step < 1e-7 * h) break;
  }
  out.position = x;
  const double gn = norm(grad);
  out.normal = gn > 0 && std::isfinite(gn) ? grad * (-1.0 / gn) : Vec3{0, 0, 1};
  return out;
}

}  // namespace PM_NAMESPACE::detail
