#include "particlemesh/spatial/spacing.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "core/length_limits.h"
#include "core/parallel.h"
#include "particlemesh/core/error.h"
#include "particlemesh/spatial/neighbor_grid.h"
#include "spatial/grid_search.h"
#include "spatial/neighbor_cell_walk.h"
#include "spatial/spacing_impl.h"

namespace PM_NAMESPACE {
namespace detail {

namespace {

// A grid whose cells hold a few points each, so that a point's nearest neighbour is almost
// always in the 27 cells around it. Starts from twice the spacing a surface sample of the
// bounding box would have (a sphere's points fill those cells about 4 to a cell: one grid,
// where the spacing itself left ~1 per cell and cost a second build) and corrects by the
// measured occupancy (which scales as h^2 on surfaces and h^3 in volumes; the loop does not
// need to know which). The median it finds does not depend on the cell size.
NeighborGrid occupancy_grid(const Vec3* points, size_t n, ProgressTracker& tracker) {
  Vec3 lo = points[0], hi = points[0];
  for (size_t i = 1; i < n; ++i) {
    lo = {std::min(lo.x, points[i].x), std::min(lo.y, points[i].y), std::min(lo.z, points[i].z)};
    hi = {std::max(hi.x, points[i].x), std::max(hi.y, points[i].y), std::max(hi.z, points[i].z)};
  }
  // The largest side, not the diagonal: squaring a side of 1e-300 underflows to 0, and the
  // points would be called coincident.
  const double side = std::max({hi.x - lo.x, hi.y - lo.y, hi.z - lo.z});
  if (!(side > 0)) throw Error(Status::InvalidInput, "all points coincide: there is no spacing");
  check_length(side, "the largest side of the points' bounding box");
  const double diag = distance(lo, hi);
  const double finest = diag / double(NeighborGrid::kMaxCellsPerAxis / 2);
  double h = std::max(2.0 * diag / std::sqrt(double(n)), finest);
  for (int it = 0;; ++it) {
    tracker.check();
    NeighborGrid grid(points, n, h);
    const double per_cell = double(n) / double(grid.cell_count());
    if (it == 5 || (per_cell >= 2.0 && per_cell <= 8.0)) return grid;
    const double next = std::max(h * std::clamp(std::sqrt(4.0 / per_cell), 0.25, 4.0), finest);
    if (next == h) return grid;
    h = next;
  }
}

}  // namespace

SpacingEstimate estimate_spacing_impl(const Vec3* points, size_t n, ProgressTracker& tracker,
                                      double begin, double end, size_t stride) {
  if (n < 2) throw Error(Status::InvalidInput, "at least two points are needed to estimate the spacing");
  tracker.stage("estimating spacing", begin, begin + 0.2 * (end - begin));
  NeighborGrid grid = occupancy_grid(points, n, tracker);

  constexpr double kInf = std::numeric_limits<double>::infinity();
  constexpr int kMaxRing = 3;
  for (int attempt = 0; attempt < 8; ++attempt) {
    tracker.check();
    if (attempt > 0) grid = NeighborGrid(points, n, grid.cell_size() * 4.0);
    const double h = grid.cell_size();
    size_t duplicates = 0;
    std::vector<uint32_t> rep;
    if (stride == 1) rep = find_duplicates(grid, &duplicates);
    const size_t distinct = n - duplicates;
    if (distinct < 2) throw Error(Status::InvalidInput, "all points coincide: there is no spacing");
    // The points whose distance counts: each distinct point once, or the sample.
    const auto counted = [&](uint32_t s) {
      return stride == 1 ? rep[s] == s : grid.original_index(s) % stride == 0;
    };
    tracker.check();

    tracker.stage("estimating spacing", begin + 0.2 * (end - begin), end, grid.cell_count());
    // nn2[s] = squared distance from sorted point s to its nearest distinct point, +inf when
    // that is farther than kMaxRing cells (such points are above the median unless h is far
    // too small, which the retry below detects).
    std::vector<double> nn2(n, kInf);
    parallel_blocks(grid.cell_count(), 512, [&](size_t cb, size_t ce) {
      if (tracker.cancelled()) return;
      uint32_t around[27];
      NeighborCellWalk walk(grid);
      for (size_t c = cb; c < ce; ++c) {
        bool any = false;
        for (uint32_t s = grid.cell_begin(uint32_t(c)); s < grid.cell_end(uint32_t(c)) && !any; ++s) any = counted(s);
        if (!any) {
          tracker.tick(1);
          continue;
        }
        const int na = walk.around(uint32_t(c), around);
        for (uint32_t s = grid.cell_begin(uint32_t(c)); s < grid.cell_end(uint32_t(c)); ++s) {
          if (!counted(s)) continue;
          const Vec3 p = grid.sorted_point(s);
          double best = kInf;
          for (int a = 0; a < na; ++a)
            for (uint32_t t = grid.cell_begin(around[a]); t < grid.cell_end(around[a]); ++t) {
              const double d2 = squared_distance(grid.sorted_point(t), p);
              if (d2 > 0 && d2 < best) best = d2;
            }
          // Every point within h of p is in the 27 cells; beyond that, widen ring by ring.
          const auto cc = grid.cell_coord(uint32_t(c));
          for (int r = 2; best > double(r - 1) * h * double(r - 1) * h && r <= kMaxRing; ++r) {
            for (int dx = -r; dx <= r; ++dx)
              for (int dy = -r; dy <= r; ++dy)
                for (int dz = -r; dz <= r; ++dz) {
                  if (std::max({std::abs(dx), std::abs(dy), std::abs(dz)}) != r) continue;
                  const uint32_t nc = grid.find_cell({cc[0] + dx, cc[1] + dy, cc[2] + dz});
                  if (nc == NeighborGrid::kNoCell) continue;
                  for (uint32_t t = grid.cell_begin(nc); t < grid.cell_end(nc); ++t) {
                    const double d2 = squared_distance(grid.sorted_point(t), p);
                    if (d2 > 0 && d2 < best) best = d2;
                  }
                }
          }
          if (best > double(kMaxRing) * h * double(kMaxRing) * h) best = kInf;
          nn2[s] = best;
        }
        tracker.tick(1);
      }
    });
    tracker.check();

    std::vector<double> values;
    values.reserve(distinct / stride + 1);
    for (size_t s = 0; s < n; ++s)
      if (counted(uint32_t(s))) values.push_back(nn2[s]);
    const size_t mid = (values.size() - 1) / 2;  // the lower median: an actual NN distance
    std::nth_element(values.begin(), values.begin() + long(mid), values.end());
    if (values[mid] == kInf) continue;  // most points are isolated at this cell size: widen
    SpacingEstimate result;
    result.spacing = std::sqrt(values[mid]);
    result.distinct_points = distinct;
    result.duplicate_points = duplicates;
    return result;
  }
  throw Error(Status::InvalidInput,
              "could not estimate the spacing: the points are too sparse for their extent "
              "(give the spacing explicitly)");
}

}  // namespace detail

namespace {

void check_points(const Vec3* points, size_t n) {
  if (points == nullptr && n > 0) throw Error(Status::InvalidArgument, "points is NULL");
  for (size_t i = 0; i < n; ++i)
    if (!is_finite(points[i]))
      throw Error(Status::InvalidInput, "point " + std::to_string(i) + " has a non-finite coordinate");
}

}  // namespace

SpacingEstimate estimate_spacing(const Vec3* points, size_t n, int threads,
                                 const ProgressCallback& progress) {
  check_points(points, n);
  detail::ProgressTracker tracker(progress);
  return detail::with_threads(threads, [&] {
    auto r = detail::estimate_spacing_impl(points, n, tracker, 0.0, 1.0);
    tracker.finish();
    return r;
  });
}

SpacingEstimate estimate_spacing_sampled(const Vec3* points, size_t n, size_t max_samples, int threads) {
  if (max_samples == 0) throw Error(Status::InvalidArgument, "max_samples is 0: at least one point must be sampled");
  check_points(points, n);
  const size_t stride = std::max<size_t>(1, (n + max_samples - 1) / max_samples);
  const ProgressCallback none;  // the tracker keeps a reference: a temporary would dangle
  detail::ProgressTracker tracker(none);
  return detail::with_threads(threads, [&] { return detail::estimate_spacing_impl(points, n, tracker, 0.0, 1.0, stride); });
}

}  // namespace particlemesh
