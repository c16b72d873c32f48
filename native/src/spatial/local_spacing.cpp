#include "particlemesh/spatial/local_spacing.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numbers>
#include <string>

#include <Eigen/Eigenvalues>

#include "core/parallel.h"
#include "core/uninit_allocator.h"
#include "particlemesh/core/error.h"
#include "particlemesh/spatial/neighbor_grid.h"
#include "spatial/grid_search.h"
#include "spatial/local_spacing_impl.h"
#include "spatial/nearest_neighbors.h"
#include "spatial/spacing_impl.h"

namespace PM_NAMESPACE {
namespace detail {

namespace {

constexpr int kK = kLocalSpacingNeighbors;

constexpr uint32_t kNone = kNoNeighbor;

/// The median of v (the upper one of an even count).
double median_of(double* v, int count) {
  std::nth_element(v, v + count / 2, v + count);
  return v[count / 2];
}

/// How far point s must reach to be a corner of any triangle at all, from its m nearest
/// neighbours `ids`: the longest edge of the shortest triangle it makes with two of them that
/// is not flat (no angle over kFlatAngle). On an even sampling this is about kSectorReach x its
/// spacing too (the shortest triangle at a point is about as long as its sector reach), so
/// where no plane spans the neighbourhood - a curve of samples (one row of a depth camera
/// after downsampling, a wire), a small cluster - the point still gets the reach that lets
/// the surface take it in. 0 when no such triangle exists (fewer than two neighbours, or all
/// in line).
double triangle_reach(const NeighborGrid& grid, uint32_t s, const uint32_t* ids, int m) {
  const Vec3 p = grid.sorted_point(s);
  const double min_cos = std::cos(kFlatAngle * std::numbers::pi / 180.0);
  double best = INFINITY;
  for (int a = 0; a < m; ++a) {
    const Vec3 qa = grid.sorted_point(ids[a]);
    const double pa = distance(p, qa);
    if (pa >= best) break;  // the neighbours come nearest first: no shorter triangle is left
    for (int b = a + 1; b < m; ++b) {
      const Vec3 qb = grid.sorted_point(ids[b]);
      const double pb = distance(p, qb), ab = distance(qa, qb);
      const double longest = std::max({pa, pb, ab});
      if (longest >= best || !(ab > 0)) continue;  // two neighbours may coincide
      // Every corner's cosine above cos(kFlatAngle), by the law of cosines.
      const double cp = (pa * pa + pb * pb - ab * ab) / (2 * pa * pb);
      const double ca = (pa * pa + ab * ab - pb * pb) / (2 * pa * ab);
      const double cb = (pb * pb + ab * ab - pa * pa) / (2 * pb * ab);
      if (cp >= min_cos && ca >= min_cos && cb >= min_cos) best = longest;
    }
  }
  return std::isfinite(best) ? best : 0;
}

/// How far point s must reach to be connected all around, from its m nearest neighbours `ids`:
/// in the plane fitted to them, the nearest neighbour in each of six sectors of 60 degrees
/// (centred on the direction the neighbours spread most along), and the third nearest of those
/// (among the sectors that have one, at least four). On an even sampling every sector's
/// nearest is about one spacing away; where the sampling is denser along one direction than
/// across it (a depth camera's rows on a surface seen at a grazing angle, a line scanner's
/// scan lines) at most two sectors' nearest lie along, and the reach is the spacing across.
/// The third, not the median: at the rim of a small opening up to three sectors see its far
/// side, and the reach must not grow with it (nor, then, the fill limit that keeps the
/// opening open). Where the nearest
/// neighbours all lie along one line, the neighbourhood is widened (a ball of twice, then four
/// times the farthest's distance; only when it is not cut off by a gap) until it spans the
/// surface. Where it never does (or with fewer than six neighbours, or fewer than four sectors
/// with one), the triangle reach. `thickness` receives sqrt(lambda_0 / lambda_1) of the
/// neighbours' first plane fit (LocalSpacing::thickness), NaN with fewer than six.
double sector_reach(const NeighborGrid& grid, uint32_t s, const uint32_t* ids, int m, bool may_widen,
                    std::vector<Vec3>& d, double& thickness) {
  thickness = NAN;
  if (m < 6) return triangle_reach(grid, s, ids, m);
  const Vec3 p = grid.sorted_point(s);
  // (Written by index: a push_back's possible reallocation, a call, kept the running largest
  // in memory.)
  d.resize(size_t(m));
  double farthest2 = 0;  // squared: the square root of the largest is the largest root
  for (int k = 0; k < m; ++k) {
    d[size_t(k)] = grid.sorted_point(ids[k]) - p;
    farthest2 = std::max(farthest2, squared_norm(d[size_t(k)]));
  }
  const double farthest = std::sqrt(farthest2);
  Eigen::Vector3d u, w;
  for (int round = 0;; ++round) {
    Vec3 c;
    for (const Vec3& x : d) c += x;
    c = c * (1.0 / double(d.size()));
    // The covariance's six distinct sums (y_i y_j = y_j y_i exactly).
    double xx = 0, xy = 0, xz = 0, yy = 0, yz = 0, zz = 0;
    for (const Vec3& x : d) {
      const double a = x.x - c.x, b = x.y - c.y, e = x.z - c.z;
      xx += a * a, xy += a * b, xz += a * e, yy += b * b, yz += b * e, zz += e * e;
    }
    Eigen::Matrix3d cov;
    cov << xx, xy, xz, xy, yy, yz, xz, yz, zz;
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig;
    eig.computeDirect(cov);
    u = eig.eigenvectors().col(2);
    w = eig.eigenvectors().col(1);
    if (round == 0 && eig.eigenvalues()(1) > 0)
      thickness = std::sqrt(std::max(0.0, eig.eigenvalues()(0)) / eig.eigenvalues()(1));
    if (eig.eigenvalues()(1) >= kElongated * eig.eigenvalues()(2)) break;
    if (round == 2 || !may_widen) return triangle_reach(grid, s, ids, m);
    const double reach = farthest * double(2 << round);
    d.clear();
    grid.for_each_within(p, reach, [&](uint32_t t, double e2) {
      if (e2 > 0) d.push_back(grid.sorted_point(t) - p);
    });
  }
  // Each sector's least squared distance (the root of the least is the least root), kept in
  // six running minima that every offset updates, its own sector's by a select: indexing an
  // array by the sector made each update wait for the last one's store.
  double n0 = INFINITY, n1 = INFINITY, n2 = INFINITY, n3 = INFINITY, n4 = INFINITY, n5 = INFINITY;
  constexpr double kHalfSqrt3 = 0.8660254037844386;
  for (const Vec3& x : d) {
    const double a = x.x * u.x() + x.y * u.y() + x.z * u.z();
    const double b = x.x * w.x() + x.y * w.y() + x.z * w.z();
    // Sector k is centred on the direction at 60 k degrees from u: the one the offset is
    // closest to, from its components along the directions at 0, 60 and 120 degrees.
    const double c[3] = {a, 0.5 * a + kHalfSqrt3 * b, -0.5 * a + kHalfSqrt3 * b};
    int best = 0;
    for (int j = 1; j < 3; ++j)
      if (std::abs(c[j]) > std::abs(c[best])) best = j;
    const int sector = c[best] >= 0 ? best : best + 3;
    const double e = squared_norm(x);
    n0 = sector == 0 ? std::min(n0, e) : n0;
    n1 = sector == 1 ? std::min(n1, e) : n1;
    n2 = sector == 2 ? std::min(n2, e) : n2;
    n3 = sector == 3 ? std::min(n3, e) : n3;
    n4 = sector == 4 ? std::min(n4, e) : n4;
    n5 = sector == 5 ? std::min(n5, e) : n5;
  }
  const std::array<double, 6> nearest{n0, n1, n2, n3, n4, n5};
  std::array<double, 6> found;
  int f = 0;
  for (double x : nearest)
    if (std::isfinite(x)) found[size_t(f++)] = std::sqrt(x);
  if (f < 4) return triangle_reach(grid, s, ids, m);
  std::nth_element(found.begin(), found.begin() + 2, found.begin() + f);
  return found[2];
}

/// The median of the finite values of v (reordered in place), 0 if none.
template <class Vector>
double median_of_finite(Vector& v) {
  const auto known = std::remove_if(v.begin(), v.end(), [](double x) { return !std::isfinite(x); });
  const auto mid = v.begin() + (known - v.begin()) / 2;
  std::nth_element(v.begin(), mid, known);
  return known == v.begin() ? 0.0 : *mid;
}

/// local_spacing_impl over the points of `grid`, none of which coincide.
std::vector<double> local_spacing_of_distinct(const NeighborGrid& grid, double r0, ProgressTracker& tracker,
                                              SamplingShape* shape) {
  const size_t n = grid.point_count();
  const std::vector<uint32_t> knn = nearest_neighbors(grid, kK, tracker);
  auto dist = [&](uint32_t s, int k) {
    const uint32_t t = knn[size_t(s) * kK + size_t(k)];
    return t == kNone ? INFINITY : distance(grid.sorted_point(s), grid.sorted_point(t));
  };
  // Each point's neighbourhood: its nearest neighbours up to the first gap (a neighbour more
  // than kGap times as far as the one before): a small cluster of particles far from the rest
  // is a neighbourhood of its own, and the rest's spacing is not its.
  // Per-point arrays that the parallel passes below fill whole: left uninitialised rather
  // than zeroed on one core first.
  using Doubles = std::vector<double, UninitAllocator<double>>;
  Doubles nn(n), raw(n), out_sorted(n);
  std::vector<uint8_t, UninitAllocator<uint8_t>> size(n);
  parallel_blocks(n, 4096, [&](size_t b, size_t e) {
    for (size_t s = b; s < e; ++s) {
      nn[s] = dist(uint32_t(s), 0);
      int k = std::isfinite(nn[s]) ? 1 : 0;
      double previous = nn[s];  // dist(s, k - 1), each distance taken once
      while (k < kK && knn[s * kK + size_t(k)] != kNone) {
        const double d = dist(uint32_t(s), k);
        if (k >= 2 && !(d <= kGap * previous)) break;
        previous = d;
        ++k;
      }
      size[s] = uint8_t(k);
    }
  });
  tracker.check();
  // Per point: the median nearest-neighbour distance around it, and the sector reach (in units
  // of an even sampling's spacing; 0 where it is not taken); and how much those distances
  // vary (their coefficient of variation, NaN with fewer than five).
  Doubles reach(n), variation(n), thickness(n);
  parallel_blocks(n, 4096, [&](size_t b, size_t e) {
    std::array<double, kK + 1> v;
    std::vector<Vec3> work;
    for (size_t s = b; s < e; ++s) {
      const int m = size[s];
      int count = 0;
      v[size_t(count++)] = nn[s];
      for (int k = 0; k < m; ++k) v[size_t(count++)] = nn[knn[s * kK + size_t(k)]];
      double sum = 0, sum2 = 0;
      for (int k = 0; k < count; ++k) sum += v[size_t(k)];
      const double mean = sum / count;
      for (int k = 0; k < count; ++k) sum2 += (v[size_t(k)] - mean) * (v[size_t(k)] - mean);
      variation[s] = count >= 5 && mean > 0 ? std::sqrt(sum2 / count) / mean : NAN;
      raw[s] = median_of(v.data(), count);
      reach[s] = sector_reach(grid, uint32_t(s), knn.data() + s * kK, m, m == kK, work, thickness[s]) / kSectorReach;
    }
  });
  tracker.check();
  // Smoothed over the neighbourhood, and the larger taken: the median of the nearest-neighbour
  // spacings; a high quantile of the reaches (scaled back so that an even sampling keeps its
  // spacing), so that where the sampling needs a long reach (across a depth camera's rows)
  // every point around has it, whichever way its own nearest neighbours happen to lie.
  parallel_blocks(n, 4096, [&](size_t b, size_t e) {
    std::array<double, kK + 1> v, w;
    for (size_t s = b; s < e; ++s) {
      int count = 0;
      v[size_t(count)] = raw[s];
      w[size_t(count++)] = reach[s];
      for (int k = 0; k < size[s]; ++k) {
        const uint32_t t = knn[s * kK + size_t(k)];
        v[size_t(count)] = raw[t];
        w[size_t(count++)] = reach[t];
      }
      const int q = std::min(count - 1, int(kSmoothQuantile * count));
      std::nth_element(w.begin(), w.begin() + q, w.begin() + count);
      out_sorted[s] = std::max(median_of(v.data(), count), w[size_t(q)] / kSmoothBias);
    }
  });
  tracker.check();
  if (shape) {
    // Medians over the points that have one (NaN where a neighbour is at infinity, or with no
    // plane fitted).
    // (Two selections over a million values each: side by side.)
    parallel_blocks(2, 1, [&](size_t b, size_t e) {
      for (size_t k = b; k < e; ++k) {
        if (k == 0) shape->irregularity = median_of_finite(variation);
        else shape->thickness = median_of_finite(thickness);
      }
    });
    // Past the cap: rows far apart for their spacing along them (several times the nearest
    // distance), or a part sampled sparser all round (about once).
    std::vector<double> over;
    for (size_t s = 0; s < n; ++s)
      if (out_sorted[s] > kMaxLocalSpacing * r0 && raw[s] > 0) over.push_back(out_sorted[s] / raw[s]);
    shape->capped_spacing_over_nn = median_of_finite(over);
  }
  std::vector<double> out(n);
  for (uint32_t s = 0; s < n; ++s) {
    // A point with no neighbour at all within reach (a far outlier) keeps the cloud's spacing.
    const double v = out_sorted[s];
    out[grid.original_index(s)] = std::isfinite(v) && v > 0 ? v : r0;
  }
  return out;
}

}  // namespace

std::vector<double> local_spacing_impl(const Vec3* points, size_t n, double r0, ProgressTracker& tracker,
                                       double begin, double end, SamplingShape* shape) {
  const NeighborGrid grid(points, n, 2 * r0);
  size_t duplicates = 0;
  const std::vector<uint32_t> rep = find_duplicates(grid, &duplicates);
  tracker.stage("local spacing", begin, end, n - duplicates);
  if (duplicates == 0) return local_spacing_of_distinct(grid, r0, tracker, shape);
  // Exact copies of a point (a scan merged with itself, Blender's jittered emission repeating
  // its pattern on faces, a file written twice) would fill each other's neighbourhoods: the 16
  // nearest would then hold a few distinct places, the spacing shrink and an even sampling look
  // irregular (or a random one regular). The estimate is taken over one copy of each place
  // (the first in input order), and every copy gets its place's spacing.
  std::vector<uint32_t> distinct;  // sorted indices of the representatives, in input order
  distinct.reserve(n - duplicates);
  for (uint32_t s = 0; s < n; ++s)
    if (rep[s] == s) distinct.push_back(s);
  std::sort(distinct.begin(), distinct.end(),
            [&](uint32_t a, uint32_t b) { return grid.original_index(a) < grid.original_index(b); });
  std::vector<Vec3> places(distinct.size());
  std::vector<uint32_t> place_of(n);  // per sorted representative: its index in `places`
  for (size_t i = 0; i < distinct.size(); ++i) {
    places[i] = grid.sorted_point(distinct[i]);
    place_of[distinct[i]] = uint32_t(i);
  }
  const std::vector<double> spacing =
      local_spacing_of_distinct(NeighborGrid(places.data(), places.size(), 2 * r0), r0, tracker, shape);
  std::vector<double> out(n);
  for (uint32_t s = 0; s < n; ++s) out[grid.original_index(s)] = spacing[place_of[rep[s]]];
  return out;
}

}  // namespace detail

LocalSpacing estimate_local_spacing(const Vec3* points, size_t n, int threads, const ProgressCallback& progress) {
  if (points == nullptr && n > 0) throw Error(Status::InvalidArgument, "points is NULL");
  for (size_t i = 0; i < n; ++i)
    if (!is_finite(points[i]))
      throw Error(Status::InvalidInput, "point " + std::to_string(i) + " has a non-finite coordinate");
  detail::ProgressTracker tracker(progress);
  return detail::with_threads(threads, [&] {
    LocalSpacing r;
    r.median_nn = detail::estimate_spacing_impl(points, n, tracker, 0.0, 0.3).spacing;
    detail::SamplingShape shape;
    r.spacing = detail::local_spacing_impl(points, n, r.median_nn, tracker, 0.3, 1.0, &shape);
    r.irregularity = shape.irregularity;
    r.reach_factor = detail::irregular_reach(shape.irregularity);
    r.thickness = shape.thickness;
    tracker.finish();
    return r;
  });
}

}  // namespace particlemesh
