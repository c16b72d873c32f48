#include "particlemesh/surface/triangulate.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <string>

#include <tbb/parallel_sort.h>

#include "core/cpu_clones.h"
#include "core/format_number.h"
#include "core/length_limits.h"
#include "core/parallel.h"
#include "core/progress_tracker.h"
#include "particlemesh/core/error.h"
#include "particlemesh/spatial/neighbor_grid.h"
#include "spatial/grid_search.h"
#include "surface/neighbor_lists.h"
#include "surface/raw_triangulation.h"
#include "surface/smallest_sphere.h"
#include "spatial/local_spacing_impl.h"
#include "spatial/spacing_impl.h"

namespace PM_NAMESPACE {

namespace {

using Clock = std::chrono::steady_clock;
double seconds_since(Clock::time_point t) {
  return std::chrono::duration<double>(Clock::now() - t).count();
}

void check_options(const TriangulateOptions& o) {
  if (!std::isfinite(o.spacing) || o.spacing < 0)
    throw Error(Status::InvalidArgument,
                "spacing must be a finite positive length (or 0 to estimate it), got " +
                    detail::format_number(o.spacing));
  if (!std::isfinite(o.max_edge_factor) || o.max_edge_factor <= 0 || o.max_edge_factor > 100)
    throw Error(Status::InvalidArgument,
                "max_edge_factor must be in (0, 100], got " + std::to_string(o.max_edge_factor));
  if (o.threads < 0) throw Error(Status::InvalidArgument, "threads must be >= 0 (0 = all cores)");
  if (o.max_neighbors < 2) throw Error(Status::InvalidArgument, "max_neighbors must be at least 2");
}

/// The pairs among h items: the triplets a point with h higher neighbours within L examines.
constexpr uint64_t pairs_of(uint64_t h) { return h * (h - (h > 0)) / 2; }

struct TestCounters {
  size_t candidates = 0, degenerate = 0, ties = 0;
  uint64_t triplets = 0;
};

/// The first i in [from, n), other than skip1 and skip2, whose detail::sphere_gap against the
/// sphere `s` (the n points by coordinate) is not above tol; n when there is none. Its gap in
/// *gap. The same arithmetic as sphere_contains(), so the same bits, and the same verdict on a
/// NaN gap (not above tol). Eight points at a time where the processor has AVX-512 (checked
/// once at run time), stopping at the first vector that holds one: the triangle test measures
/// a point's neighbours against each of its triplets' spheres, and on an irregular sampling
/// the first blocker comes ~15 points into a list of up to a hundred (all of them measured
/// first, then scanned, was most of the test's own loop).
size_t first_near_gap_scalar(const double* x, const double* y, const double* z, size_t n, size_t from,
                             const detail::SmallestSphere& s, double tol, size_t skip1, size_t skip2, double* gap) {
  for (size_t i = from; i < n; ++i) {
    if (i == skip1 || i == skip2) continue;
    const double g = detail::sphere_gap(s, Vec3{x[i], y[i], z[i]});
    if (!(g > tol)) {
      *gap = g;
      return i;
    }
  }
  return n;
}

/// first_near_gap() over the points list[from, n) (indices into points), skipping the triplet's
/// corners i, j, k by index: the test of a triplet whose widest corner is not the point at
/// hand, over that corner's list (a fifth of the candidates on an irregular sampling).
size_t first_near_gap_indexed_scalar(const Vec3* points, const uint32_t* list, size_t n, size_t from,
                                     const detail::SmallestSphere& s, double tol, uint32_t i, uint32_t j, uint32_t k,
                                     double* gap) {
  for (size_t at = from; at < n; ++at) {
    const uint32_t q = list[at];
    if (q == i || q == j || q == k) continue;
    const double g = detail::sphere_gap(s, points[q]);
    if (!(g > tol)) {
      *gap = g;
      return at;
    }
  }
  return n;
}

/// The places c in [from, n) of a point's higher neighbours within L (coordinates x, y, z, edge
/// limits l) that pair with the one at p (limit lp): squared_distance(p, q_c) not above
/// pair_limit(lp, l_c)^2 (so NaN pairs, as in the test's loop), in order, into out; their count.
/// Eight at a time where the processor has AVX-512: the triangle test's pairs (j, k), ~100 a
/// point on an irregular sampling, a third of them too long (one at a time, a branch each that
/// the processor could not predict).
size_t pairs_within_scalar(const double* x, const double* y, const double* z, const double* l, size_t from, size_t n,
                           const Vec3& p, double lp, uint32_t* out) {
  size_t kept = 0;
  for (size_t c = from; c < n; ++c) {
    const double limit = detail::pair_limit(lp, l[c]);
    if (!(squared_distance(p, Vec3{x[c], y[c], z[c]}) > limit * limit)) out[kept++] = uint32_t(c);
  }
  return kept;
}

#ifdef PM_HAVE_AVX512
PM_TARGET_AVX512 size_t pairs_within_avx512(const double* x, const double* y, const double* z, const double* l,
                                            size_t from, size_t n, const Vec3& p, double lp, uint32_t* out) {
  const __m512d px = _mm512_set1_pd(p.x), py = _mm512_set1_pd(p.y), pz = _mm512_set1_pd(p.z);
  const __m512d lpv = _mm512_set1_pd(lp), half = _mm512_set1_pd(0.5);
  const __m512i lanes = _mm512_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15);
  size_t kept = 0;
  for (size_t c = from; c < n; c += 8) {
    const size_t left = n - c;
    const __mmask8 in = __mmask8(left >= 8 ? 0xff : (1u << left) - 1);
    // squared_distance(p, q) = squared_norm(p - q), x then y then z; pair_limit(lp, l) squared.
    const __m512d dx = _mm512_sub_pd(px, _mm512_maskz_loadu_pd(in, x + c));
    const __m512d dy = _mm512_sub_pd(py, _mm512_maskz_loadu_pd(in, y + c));
    const __m512d dz = _mm512_sub_pd(pz, _mm512_maskz_loadu_pd(in, z + c));
    const __m512d d2 = _mm512_add_pd(_mm512_add_pd(_mm512_mul_pd(dx, dx), _mm512_mul_pd(dy, dy)), _mm512_mul_pd(dz, dz));
    const __m512d limit = _mm512_mul_pd(half, _mm512_add_pd(lpv, _mm512_maskz_loadu_pd(in, l + c)));
    const __mmask8 keep = _mm512_mask_cmp_pd_mask(in, d2, _mm512_mul_pd(limit, limit), _CMP_NGT_UQ);
    _mm512_mask_compressstoreu_epi32(out + kept, __mmask16(keep), _mm512_add_epi32(_mm512_set1_epi32(int(c)), lanes));
    kept += size_t(__builtin_popcount(keep));
  }
  return kept;
}

PM_TARGET_AVX512 size_t first_near_gap_avx512(const double* x, const double* y, const double* z,
                                                                size_t n, size_t from, const detail::SmallestSphere& s,
                                                                double tol, size_t skip1, size_t skip2, double* gap) {
  const detail::SphereGaps8 gaps(s);
  const __m512d limit = _mm512_set1_pd(tol);
  const __m512i lanes = _mm512_setr_epi64(0, 1, 2, 3, 4, 5, 6, 7);
  const __m512i s1 = _mm512_set1_epi64(int64_t(skip1)), s2 = _mm512_set1_epi64(int64_t(skip2));
  for (size_t i = from; i < n; i += 8) {
    const size_t left = n - i;
    const __mmask8 in = __mmask8(left >= 8 ? 0xff : (1u << left) - 1);
    const __m512d g = gaps(_mm512_maskz_loadu_pd(in, x + i), _mm512_maskz_loadu_pd(in, y + i), _mm512_maskz_loadu_pd(in, z + i));
    const __m512i at = _mm512_add_epi64(_mm512_set1_epi64(int64_t(i)), lanes);
    const __mmask8 other = _mm512_mask_cmpneq_epi64_mask(_mm512_cmpneq_epi64_mask(at, s1), at, s2);
    const __mmask8 near = _mm512_mask_cmp_pd_mask(__mmask8(in & other), g, limit, _CMP_NGT_UQ);
    if (near) return i + size_t(detail::SphereGaps8::first(near, g, gap));
  }
  return n;
}

PM_TARGET_AVX512 size_t first_near_gap_indexed_avx512(const Vec3* points, const uint32_t* list, size_t n,
                                                      size_t from, const detail::SmallestSphere& s, double tol,
                                                      uint32_t i, uint32_t j, uint32_t k, double* gap) {
  static_assert(sizeof(Vec3) == 3 * sizeof(double));
  const double* base = &points[0].x;
  const detail::SphereGaps8 gaps(s);
  const __m512d limit = _mm512_set1_pd(tol);
  const __m512i vi = _mm512_set1_epi64(i), vj = _mm512_set1_epi64(j), vk = _mm512_set1_epi64(k);
  const __m256i lane_numbers = _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7);
  for (size_t at = from; at < n; at += 8) {
    const size_t left = n - at;
    const __mmask8 in = __mmask8(left >= 8 ? 0xff : (1u << left) - 1);
    // The indices (the tail's by an AVX2 masked load, which reads only its lanes), and the
    // points' coordinates gathered by them (Vec3 is three doubles: point q's x at 3 q).
    const __m256i ids = left >= 8 ? _mm256_loadu_si256(reinterpret_cast<const __m256i*>(list + at))
                                  : _mm256_maskload_epi32(reinterpret_cast<const int*>(list + at),
                                                          _mm256_cmpgt_epi32(_mm256_set1_epi32(int(left)), lane_numbers));
    const __m512i q = _mm512_maskz_cvtepu32_epi64(in, ids);
    const __m512i q3 = _mm512_add_epi64(q, _mm512_add_epi64(q, q));
    const __mmask8 other = _mm512_mask_cmpneq_epi64_mask(
        _mm512_mask_cmpneq_epi64_mask(_mm512_mask_cmpneq_epi64_mask(in, q, vi), q, vj), q, vk);
    using detail::sphere_lanes::gather_coordinate;
    const __m512d g = gaps(gather_coordinate(base, q3, other), gather_coordinate(base + 1, q3, other),
                           gather_coordinate(base + 2, q3, other));
    const __mmask8 near = _mm512_mask_cmp_pd_mask(other, g, limit, _CMP_NGT_UQ);
    if (near) return at + size_t(detail::SphereGaps8::first(near, g, gap));
  }
  return n;
}
#endif

size_t first_near_gap(const double* x, const double* y, const double* z, size_t n, size_t from,
                      const detail::SmallestSphere& s, double tol, size_t skip1, size_t skip2, double* gap) {
#ifdef PM_HAVE_AVX512
  if (detail::cpu_has_avx512()) return first_near_gap_avx512(x, y, z, n, from, s, tol, skip1, skip2, gap);
#endif
  return first_near_gap_scalar(x, y, z, n, from, s, tol, skip1, skip2, gap);
}

size_t first_near_gap_indexed(const Vec3* points, const uint32_t* list, size_t n, size_t from,
                              const detail::SmallestSphere& s, double tol, uint32_t i, uint32_t j, uint32_t k,
                              double* gap) {
#ifdef PM_HAVE_AVX512
  if (detail::cpu_has_avx512()) return first_near_gap_indexed_avx512(points, list, n, from, s, tol, i, j, k, gap);
#endif
  return first_near_gap_indexed_scalar(points, list, n, from, s, tol, i, j, k, gap);
}

size_t pairs_within(const double* x, const double* y, const double* z, const double* l, size_t from, size_t n,
                    const Vec3& p, double lp, uint32_t* out) {
#ifdef PM_HAVE_AVX512
  if (detail::cpu_has_avx512()) return pairs_within_avx512(x, y, z, l, from, n, p, lp, out);
#endif
  return pairs_within_scalar(x, y, z, l, from, n, p, lp, out);
}

}  // namespace

namespace detail {

namespace {

/// Within kSpacingBand of r0 a local spacing is sampling noise and r0 stands (an even sampling
/// meshes as with one spacing); beyond, it follows the cloud, less the band (continuous).
double r0_with_band(double h, double r0, double band) {
  if (h > r0 * (1 + band)) return h / (1 + band);
  if (h < r0 * (1 - band)) return h / (1 - band);
  return r0;
}

}  // namespace

RawTriangulation run_raw_triangulation(const PointCloud& cloud, const TriangulateOptions& options,
                                       ProgressTracker& tracker, double begin, double end,
                                       TriangleIndices indices, bool local, const SpacingEstimate* known) {
  check_options(options);
  validate_point_cloud(cloud);
  const size_t n = cloud.size();
  if (n == 0) throw Error(Status::InvalidInput, "the point cloud is empty");
  if (n < 3) throw Error(Status::InvalidInput, "at least three points are needed, got " + std::to_string(n));
  auto at = [&](double f) { return begin + (end - begin) * f; };

  RawTriangulation raw;
  TriangulateStats& st = raw.stats;
  st.points = n;

  // 1. Spacing.
  auto t0 = Clock::now();
  if (options.spacing > 0) {
    st.spacing = options.spacing;
  } else {
    const SpacingEstimate est =
        known ? *known : estimate_spacing_impl(cloud.positions.data(), n, tracker, at(0.0), at(local ? 0.15 : 0.3));
    st.spacing = est.spacing;
    st.spacing_estimated = true;
  }
  check_length(st.spacing, std::string("the particle spacing r0") + (st.spacing_estimated ? " (estimated)" : ""));
  st.max_edge = options.max_edge_factor * st.spacing;
  if (!(st.max_edge > 0) || !std::isfinite(st.max_edge))
    throw Error(Status::InvalidArgument, "the max edge length is not a positive finite number");
  // Each point's own spacing, in the units of r0: scaled so that the cloud's median
  // nearest-neighbour distance is r0 (unchanged when r0 was estimated).
  std::vector<double> local_spacing;
  if (local) {
    const double measured = st.spacing_estimated ? st.spacing
                            : known              ? known->spacing
                                                 : estimate_spacing_impl(cloud.positions.data(), n, tracker, at(0.0), at(0.15)).spacing;
    SamplingShape shape;
    local_spacing = local_spacing_impl(cloud.positions.data(), n, measured, tracker, at(0.15), at(0.3), &shape);
    st.sampling_irregularity = shape.irregularity;
    st.sampling_thickness = shape.thickness;
    st.capped_spacing_over_nn = shape.capped_spacing_over_nn;
    // At most kMaxLocalSpacing r0: sparser than that, samples are too far apart to be one
    // surface at the cloud's scale (stray clusters, a scan's far fringe). On an irregular
    // (random) sampling the covering triangles reach farther than the spacing: every limit,
    // the cap too, lengthened by the same factor (1 on every even sampling).
    st.reach_factor = irregular_reach(st.sampling_irregularity);
    const double scale = st.spacing / measured, cap = kMaxLocalSpacing * st.spacing;
    // The 90th percentile before the cap, where it lies past it (the count first: a selection
    // over a copy only then).
    const size_t p90 = n * 9 / 10;
    const auto over = size_t(std::count_if(local_spacing.begin(), local_spacing.end(), [&](double h) { return h * scale > cap; }));
    if (over >= n - p90) {
      std::vector<double> v(local_spacing);
      std::nth_element(v.begin(), v.begin() + ptrdiff_t(p90), v.end());
      st.uncapped_spacing_p90 = v[p90] / measured;
    }
    for (double& h : local_spacing) h = std::min(r0_with_band(h * scale, st.spacing, kSpacingBand), cap) * st.reach_factor;
    raw.edge_cap = options.max_edge_factor * cap * st.reach_factor;
  }
  st.seconds_spacing = seconds_since(t0);

  // 2. Neighbour lists within R = 2L/sqrt(3). A point strictly inside the smallest sphere of
  //    a triangle with edges <= L is closer than 2 rho <= 2L/sqrt(3) to *every* corner (rho is
  //    at most L/sqrt(3) for an acute triangle, L/2 for an obtuse one), so the list of the
  //    triangle's lowest corner alone holds every possible blocker. With a local spacing each
  //    point has its own L and R, every edge is at most the pair limit of its ends (at most
  //    the larger L), and the list of the corner with the largest L holds every blocker.
  t0 = Clock::now();
  tracker.stage("neighbour search", at(0.3), at(0.55), n);
  const auto to_radius = [](double L) { return L * (2.0 / std::sqrt(3.0)) * (1.0 + 1e-6); };
  const auto from_radius = [](double R) { return R / ((2.0 / std::sqrt(3.0)) * (1.0 + 1e-6)); };
  const double neighbor_radius = to_radius(st.max_edge);
  double cell = neighbor_radius;
  if (local) {
    // Cells of the median radius: a point's box query then spans 2-3 cells per axis, more
    // only where the spacing is larger.
    std::vector<double> r(local_spacing);
    std::nth_element(r.begin(), r.begin() + ptrdiff_t(n / 2), r.end());
    cell = to_radius(options.max_edge_factor * r[n / 2]);
    if (!(cell > 0) || !std::isfinite(cell)) throw Error(Status::InvalidArgument, "the local spacing is not positive and finite");
  }
  try {
    raw.grid = std::make_unique<NeighborGrid>(cloud.positions.data(), n, cell);
  } catch (const Error& e) {
    if (e.status() != Status::LimitExceeded) throw;
    throw Error(e.status(), std::string(e.what()) + " (the cells follow the spacing: a larger spacing makes them larger)");
  }
  const NeighborGrid& grid = *raw.grid;
  size_t duplicates = 0;
  raw.rep = find_duplicates(grid, &duplicates);
  st.duplicate_points = duplicates;
  if (n - duplicates < 3)
    throw Error(Status::InvalidInput, "fewer than three distinct points (all points coincide?)");
  std::vector<double>& Lp = raw.max_edge;
  if (local) {
    Lp.resize(n);
    std::vector<double> radius(n);
    parallel_blocks(n, 8192, [&](size_t b, size_t e) {
      for (size_t s = b; s < e; ++s) {
        // Duplicates take their representative's (the first copy's) spacing.
        Lp[s] = options.max_edge_factor * local_spacing[grid.original_index(uint32_t(s))];
        radius[s] = to_radius(Lp[s]);
      }
    });
    for (size_t s = 0; s < n; ++s) Lp[s] = Lp[raw.rep[s]], radius[s] = radius[raw.rep[s]];
    // A point whose own reach holds more than max_neighbors others (a scanner's rows: the
    // spacing across them sets L, and the rows are sampled far denser along) has its L
    // shortened to the reach that holds max_neighbors when the spacing was estimated: it is
    // the cloud's, not the caller's, so this is no error of theirs. Every blocker of a
    // triangle is still in the list of its corner with the largest L (R = 2L/sqrt(3) per
    // point, as below).
    const bool shorten = st.spacing_estimated;
    // Every particle at r0 (an even sampling): the lists of one radius, as without local
    // spacing (the same lists, built faster).
    bool uniform = std::all_of(Lp.begin(), Lp.end(), [&](double l) { return l == st.max_edge; });
    if (uniform) {
      try {
        raw.neighbors = build_neighbor_lists(grid, raw.rep, neighbor_radius, options.max_neighbors, tracker);
      } catch (const Error& e) {
        if (!shorten || e.status() != Status::LimitExceeded) throw;
        uniform = false;  // the per-point lists below, shortened where crowded
      }
    }
    if (!uniform) {
      raw.neighbors = build_neighbor_lists(grid, raw.rep, radius, options.max_neighbors, shorten, tracker);
      if (raw.neighbors.shortened > 0) {
        for (size_t s = 0; s < n; ++s)
          if (raw.rep[s] == s && radius[s] < to_radius(Lp[s]) * (1 - 1e-12)) Lp[s] = from_radius(radius[s]);
        for (size_t s = 0; s < n; ++s) Lp[s] = Lp[raw.rep[s]];
      }
      st.shortened_limits = raw.neighbors.shortened;
    }
  } else {
    Lp.assign(n, st.max_edge);
    raw.neighbors = build_neighbor_lists(grid, raw.rep, neighbor_radius, options.max_neighbors, tracker);
  }
  const NeighborLists& nbr = raw.neighbors;
  st.max_neighbors_seen = nbr.max_count;
  auto limit2 = [&](uint32_t a, uint32_t b) {
    const double l = pair_limit(Lp[a], Lp[b]);
    return l * l;
  };

  // The test's work, bounded before it starts: the pairs (j, k) of each point's higher
  // neighbours within L are the triplets it examines (max_triplets_per_point). First by the
  // pairs of its higher neighbours, within L or not (no distance taken); only where that bound
  // is over the limit are the triplets counted exactly here (else the test counts them, the
  // same sum, as it goes: the exact count was a pass over every list's distances).
  const auto& P = grid.sorted_points();
  const uint64_t distinct = n - duplicates;
  const uint64_t most_triplets = uint64_t(options.max_triplets_per_point) * distinct;
  uint64_t triplet_bound = 0;
  {
    std::atomic<uint64_t> bound{0};
    parallel_blocks(n, 8192, [&](size_t b, size_t e) {
      uint64_t sum = 0;
      for (size_t i = b; i < e; ++i) {
        const uint32_t* end = nbr.end(uint32_t(i));
        const uint64_t higher = uint64_t(end - std::upper_bound(nbr.begin(uint32_t(i)), end, uint32_t(i)));
        sum += pairs_of(higher);
      }
      bound.fetch_add(sum, std::memory_order_relaxed);
    });
    triplet_bound = bound.load();
  }
  const bool counted = options.max_triplets_per_point > 0 && triplet_bound > most_triplets;
  if (counted) {
    std::atomic<uint64_t> triplets{0};
    // Blocks of about a million list entries (4096 points on even samplings): with huge lists
    // smaller blocks, so that the calling thread, which alone may ask the callback, is never
    // left waiting long on another thread's block.
    const uint64_t entries = nbr.index.size();
    const size_t count_grain = std::clamp<size_t>(size_t((uint64_t(1) << 20) * n / std::max<uint64_t>(1, entries)), 16, 4096);
    parallel_blocks(n, count_grain, [&](size_t b, size_t e) {
      if (tracker.cancelled()) return;
      uint64_t sum = 0;
      for (size_t i = b; i < e; ++i) {
        // Lists of up to max_neighbors (100000) each: a block can take seconds.
        if ((i & 63) == 0) {
          if (tracker.cancelled()) return;
          tracker.tick(0);  // on the calling thread: lets the callback ask to cancel
        }
        uint64_t higher = 0;
        for (const uint32_t* q = std::upper_bound(nbr.begin(uint32_t(i)), nbr.end(uint32_t(i)), uint32_t(i));
             q != nbr.end(uint32_t(i)); ++q)
          higher += squared_distance(P[*q], P[i]) <= limit2(uint32_t(i), *q);
        sum += pairs_of(higher);
      }
      triplets.fetch_add(sum, std::memory_order_relaxed);
    });
    tracker.check();
    st.triplets = triplets.load();
    if (st.triplets > most_triplets)
      throw Error(Status::LimitExceeded,
                  "the triangle test would examine " + std::to_string(st.triplets) + " candidate triplets (" +
                      std::to_string(st.triplets / distinct) + " per point, more than max_triplets_per_point = " +
                      std::to_string(options.max_triplets_per_point) + "): the max edge L = " +
                      format_number(st.max_edge) + " is far too large for the spacing r0 = " +
                      format_number(st.spacing) + " (lower the max edge factor, or raise the limit)");
  }
  st.seconds_neighbors = seconds_since(t0);

  // 3. The test. Each triangle is generated once, from its lowest sorted index i, as a pair
  //    j < k of i's higher neighbours within L.
  t0 = Clock::now();
  tracker.stage("testing triangles", at(0.55), at(0.95), n);
  // Blocks of 1024 points, or fewer when points have many triplets (the limits lifted: up to
  // ~1e6 per point), so that no block keeps the calling thread - the only one that calls the
  // progress callback - waiting for long. The triangles are joined in block order either way.
  // (Without the exact count, by its bound.)
  const uint64_t per_point = (counted ? st.triplets : triplet_bound) / std::max<uint64_t>(1, distinct);
  const size_t block = std::clamp<size_t>(size_t(65536 / std::max<uint64_t>(1, per_point)), 1, 1024);
  const size_t blocks = (n + block - 1) / block;
  std::vector<std::vector<Triangle>> out(blocks);
  std::vector<TestCounters> counters(blocks);
  parallel_blocks(blocks, 1, [&](size_t bb, size_t be) {
    std::vector<uint32_t> near;  // i's higher neighbours within L
    std::vector<uint32_t> near_at;  // their places in i's list
    // i's list by coordinate, for the spheres' gaps (first_near_gap): where i has the largest
    // L of a triplet (every triplet, on an even sampling), its blockers are measured there.
    std::vector<double> lx, ly, lz;
    // The triplets waiting to be judged (see below): their places in `near`, their points'
    // indices (zeroed: smallest_spheres reads all eight), and their spheres.
    uint32_t pend_a[8], pend_c[8], pend_j[8] = {}, pend_k[8] = {};
    SmallestSphere spheres[8];
    // i's higher neighbours within L by coordinate, with their edge limits; one's partners.
    std::vector<double> nx, ny, nz, nl;
    std::vector<uint32_t> partners;
    for (size_t b = bb; b < be; ++b) {
      if (tracker.cancelled()) return;
      auto& tris = out[b];
      auto& cnt = counters[b];
      const uint32_t sb = uint32_t(b * block), se = uint32_t(std::min(n, (b + 1) * block));
      for (uint32_t i = sb; i < se; ++i) {
        const uint32_t* ni = nbr.begin(i);
        const uint32_t* ne = nbr.end(i);
        const Vec3 pi = P[i];
        uint32_t last_blocker = UINT32_MAX;  // the last point found inside one of i's spheres
        near.clear();
        near_at.clear();
        for (const uint32_t* q = std::upper_bound(ni, ne, i); q != ne; ++q)
          if (squared_distance(P[*q], pi) <= limit2(i, *q)) near.push_back(*q), near_at.push_back(uint32_t(q - ni));
        cnt.triplets += pairs_of(near.size());
        const size_t len = size_t(ne - ni);
        if (near.size() >= 2) {
          lx.resize(len), ly.resize(len), lz.resize(len);
          for (size_t at = 0; at < len; ++at) lx[at] = P[ni[at]].x, ly[at] = P[ni[at]].y, lz[at] = P[ni[at]].z;
        }
        // With the limits lifted one point can have ~1e9 triplets, each tested against up to
        // 1e5 neighbours: the cancel flag is checked inside the point's work too (every 256
        // pairs within the limits, eight pairs beyond them counting as one; a check costs a
        // relaxed load, and on the calling thread a clock read).
        uint32_t since_check = 0;
        // The triplets (j, k) within the limits, judged eight at a time: their smallest spheres
        // computed side by side (smallest_spheres), then each judged in turn, in the order of
        // the pairs, as one at a time. (The judgement is kept out of line: inlined into the
        // loop that collects the pairs, the test took 8 % longer.)
        size_t pending = 0;
        const auto judge = [&](size_t a, size_t c, const SmallestSphere& s) __attribute__((noinline)) {
          const uint32_t j = near[a], k = near[c];
          if (s.degenerate) {
            ++cnt.degenerate;
            return;
          }
          ++cnt.candidates;
          // Every possible blocker is in the list of the corner with the largest L.
          uint32_t widest = i;
          if (Lp[j] > Lp[widest]) widest = j;
          if (Lp[k] > Lp[widest]) widest = k;
          bool blocked = false, tie = false;
          // The point that blocked the last triplet first: the spheres of one point's
          // triplets overlap (on an irregular sampling the first blocker in list order comes
          // ~15 points in, and 96 % of candidates have one). Whether a point inside exists
          // does not depend on the order the points are looked at in (every point inside is
          // in the list: see above), so neither does the verdict; only which tie, if any,
          // is met before it (`ties` counts candidates that met one).
          if (last_blocker != UINT32_MAX && last_blocker != j && last_blocker != k &&
              sphere_contains_inline(s, P[last_blocker], &tie)) {
            blocked = true;
          } else if (widest == i) {
            // The verdict of the loop below, in the same order: the first neighbour strictly
            // inside, or in the tie zone and inside by the symbolic tie-break; `tie` for any
            // in the tie zone up to it. (i's own list does not hold i; j and k, the corners,
            // are skipped.)
            const double tol = kTieTolerance * s.r2;
            double g = 0;
            const auto next_near = [&](size_t from) {
              return first_near_gap(lx.data(), ly.data(), lz.data(), len, from, s, tol, near_at[a], near_at[c], &g);
            };
            for (size_t at = next_near(0); at < len; at = next_near(at + 1)) {
              if (g < -tol || sphere_contains(s, P[ni[at]], &tie)) {
                blocked = true;
                last_blocker = ni[at];
                break;
              }
            }
          } else {
            // The same, over the widest corner's list (which holds i and the other corner).
            const uint32_t* list = nbr.begin(widest);
            const size_t count = size_t(nbr.end(widest) - list);
            const double tol = kTieTolerance * s.r2;
            double g = 0;
            const auto next_near = [&](size_t from) {
              return first_near_gap_indexed(P.data(), list, count, from, s, tol, i, j, k, &g);
            };
            for (size_t at = next_near(0); at < count; at = next_near(at + 1)) {
              if (g < -tol || sphere_contains(s, P[list[at]], &tie)) {
                blocked = true;
                last_blocker = list[at];
                break;
              }
            }
          }
          if (tie) ++cnt.ties;
          if (blocked) return;
          if (indices == TriangleIndices::Sorted) {  // i < j < k already
            tris.push_back({i, j, k});
            return;
          }
          Triangle t{grid.original_index(i), grid.original_index(j), grid.original_index(k)};
          if (t[0] > t[1]) std::swap(t[0], t[1]);
          if (t[1] > t[2]) std::swap(t[1], t[2]);
          if (t[0] > t[1]) std::swap(t[0], t[1]);
          tris.push_back(t);
        };
        const auto judge_pending = [&] {
          smallest_spheres(pi, P.data(), pend_j, pend_k, int(pending), spheres);
          for (size_t p = 0; p < pending; ++p) judge(pend_a[p], pend_c[p], spheres[p]);
          pending = 0;
        };
        // The pairs (j, k) of the higher neighbours within L whose edge j k is within its limit:
        // each j's partners found at once (pairs_within, over the neighbours by coordinate).
        const size_t m = near.size();
        if (m >= 2) {
          nx.resize(m), ny.resize(m), nz.resize(m), nl.resize(m), partners.resize(m);
          for (size_t a = 0; a < m; ++a)
            nx[a] = lx[near_at[a]], ny[a] = ly[near_at[a]], nz[a] = lz[near_at[a]], nl[a] = Lp[near[a]];
        }
        for (size_t a = 0; a + 1 < m; ++a) {
          const uint32_t j = near[a];
          const size_t kept = pairs_within(nx.data(), ny.data(), nz.data(), nl.data(), a + 1, m, P[j], Lp[j], partners.data());
          since_check += uint32_t((m - a - 1) / 8);
          for (size_t t = 0; t < kept; ++t) {
            if (++since_check >= 256) {
              since_check = 0;
              if (tracker.cancelled()) return;
              tracker.tick(0);
            }
            const uint32_t c = partners[t];
            pend_a[pending] = uint32_t(a), pend_c[pending] = c;
            pend_j[pending] = j, pend_k[pending] = near[c];
            if (++pending == 8) judge_pending();
          }
        }
        judge_pending();
      }
      tracker.tick(se - sb);
    }
  });
  tracker.check();

  size_t total = 0;
  for (size_t b = 0; b < blocks; ++b) {
    total += out[b].size();
    st.candidates += counters[b].candidates;
    st.degenerate += counters[b].degenerate;
    st.ties += counters[b].ties;
    if (!counted) st.triplets += counters[b].triplets;
  }
  tracker.stage("sorting", at(0.95), at(1.0));
  std::vector<Triangle>& tris = raw.triangles;
  tris.reserve(total);
  for (auto& v : out) {
    tris.insert(tris.end(), v.begin(), v.end());
    std::vector<Triangle>().swap(v);
  }
  // In sorted indices the blocks already come in order: each triangle (i, j, k) from its
  // lowest index i, with j < k taken in list order. Original indices need a sort; packed keys
  // compare as one integer (std::array's operator< goes through memcmp).
  if (indices == TriangleIndices::Original)
    tbb::parallel_sort(tris.begin(), tris.end(), [](const Triangle& x, const Triangle& y) {
      const uint64_t kx = (uint64_t(x[0]) << 32) | x[1], ky = (uint64_t(y[0]) << 32) | y[1];
      return kx != ky ? kx < ky : x[2] < y[2];
    });
  st.kept = tris.size();
  st.seconds_test = seconds_since(t0);
  return raw;
}

}  // namespace detail

TriangulateResult triangulate_raw(const PointCloud& cloud, const TriangulateOptions& options) {
  check_options(options);
  detail::ProgressTracker tracker(options.progress);
  detail::RawTriangulation raw = detail::with_threads(
      options.threads, [&] { return detail::run_raw_triangulation(cloud, options, tracker, 0.0, 1.0); });
  TriangulateResult result;
  result.stats = raw.stats;
  result.mesh.triangles = std::move(raw.triangles);
  result.mesh.positions = cloud.positions;
  result.mesh.normals = cloud.normals;
  result.mesh.attributes = cloud.attributes;
  tracker.finish();
  return result;
}

}  // namespace particlemesh
