#include "particlemesh/spatial/spacing.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numeric>
#include <optional>
#include <string>
#include <utility>

#include "core/disjoint_sets.h"
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

/// The corners of the bounding box of n >= 1 points.
std::pair<Vec3, Vec3> box_of(const Vec3* points, size_t n) {
  Vec3 lo = points[0], hi = points[0];
  for (size_t i = 1; i < n; ++i) {
    lo = {std::min(lo.x, points[i].x), std::min(lo.y, points[i].y), std::min(lo.z, points[i].z)};
    hi = {std::max(hi.x, points[i].x), std::max(hi.y, points[i].y), std::max(hi.z, points[i].z)};
  }
  return {lo, hi};
}

// A grid whose cells hold a few points each, so that a point's nearest neighbour is almost
// always in the 27 cells around it. Starts from twice the spacing a surface sample of the
// bounding box would have (a sphere's points fill those cells about 4 to a cell: one grid,
// where the spacing itself left ~1 per cell and cost a second build) and corrects by the
// measured occupancy (which scales as h^2 on surfaces and h^3 in volumes; the loop does not
// need to know which). The median it finds does not depend on the cell size. `crowded`: the
// cells hold few points on average, but a point's cell holds many (over 64, averaged over the
// points): a few points far from a cluster (a particle a simulation flung away, two objects
// far apart for their size) keep cells fine enough for the cluster from fitting the grid's
// key, or many copies of a few points share cells (see far_apart_parts).
NeighborGrid occupancy_grid(const Vec3* points, size_t n, ProgressTracker& tracker, bool& crowded) {
  const auto [lo, hi] = box_of(points, n);
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
    const double next = std::max(h * std::clamp(std::sqrt(4.0 / per_cell), 0.25, 4.0), finest);
    if (it == 5 || (per_cell >= 2.0 && per_cell <= 8.0) || next == h) {
      // The points in a point's cell, averaged over the points: what the search costs a point.
      double shared = 0;
      for (uint32_t c = 0; c < grid.cell_count(); ++c) {
        const double k = double(grid.cell_end(c) - grid.cell_begin(c));
        shared += k * k;
      }
      crowded = shared > 64.0 * double(n);
      return grid;
    }
    h = next;
  }
}

/// Points searched on a grid of their own (copies, with their input indices).
struct Part {
  std::vector<Vec3> points;
  std::vector<uint32_t> original;
};

double largest_side(const std::vector<Vec3>& points) {
  const auto [lo, hi] = box_of(points.data(), points.size());
  return std::max({hi.x - lo.x, hi.y - lo.y, hi.z - lo.z});
}

/// Splits `part` at the widest empty slab across it (along x, y or z) when the slab is wider
/// than either side's bounding box is long (its diagonal), and each side again: every point is
/// then nearer to every other of its side than to any across, so its nearest neighbour is
/// found on its side's own grid, but for a point alone on its side, whose distance (infinite
/// there, at least the slab's width in truth) is above every other either way. So the median
/// is the same.
void split_at_gaps(Part part, std::vector<Part>& out) {
  const size_t m = part.points.size();
  if (m >= 2 && out.size() < 4096) {
    std::vector<double> along(m);
    for (int a = 0; a < 3; ++a) {
      for (size_t i = 0; i < m; ++i) along[i] = part.points[i][a];
      std::sort(along.begin(), along.end());
      double gap = 0, cut = 0;
      for (size_t i = 1; i < m; ++i)
        if (along[i] - along[i - 1] > gap) gap = along[i] - along[i - 1], cut = along[i - 1];
      if (!(gap > 0)) continue;
      Part low, high;
      for (size_t i = 0; i < m; ++i) {
        Part& to = part.points[i][a] <= cut ? low : high;
        to.points.push_back(part.points[i]);
        to.original.push_back(part.original[i]);
      }
      const auto [llo, lhi] = box_of(low.points.data(), low.points.size());
      const auto [hlo, hhi] = box_of(high.points.data(), high.points.size());
      if (!(gap > distance(llo, lhi) && gap > distance(hlo, hhi))) continue;
      split_at_gaps(std::move(low), out);
      split_at_gaps(std::move(high), out);
      return;
    }
  }
  out.push_back(std::move(part));
}

/// The middle of a part still crowded without a gap to split at (particles flung far and wide
/// from a simulation): the points within 8 interquartile ranges (the widest axis') of the
/// middle half along every axis, if that leaves out at most a tenth of them (else the part
/// whole: many copies of a few points crowd the middle half, not strays). Those left out count
/// as infinitely far; as strays their nearest neighbours are farther than the median anyway.
/// The quartiles are those of the distinct places: copies of one point (a scanner's invalid
/// returns written as 0 0 0, ten times as many as the rest) would otherwise be the middle half
/// and leave every other point out.
Part middle_of(const Part& part) {
  const size_t m = part.points.size();
  std::vector<Vec3> places = part.points;
  std::sort(places.begin(), places.end(), [](const Vec3& p, const Vec3& q) {
    return p.x != q.x ? p.x < q.x : p.y != q.y ? p.y < q.y : p.z < q.z;
  });
  places.erase(std::unique(places.begin(), places.end()), places.end());
  const size_t d = places.size();
  std::vector<double> along(d);
  std::array<double, 3> lo{}, hi{};
  double widest = 0;
  for (int a = 0; a < 3; ++a) {
    for (size_t i = 0; i < d; ++i) along[i] = places[i][a];
    const auto quantile = [&](double f) {
      const auto k = ptrdiff_t(f * double(d - 1));
      std::nth_element(along.begin(), along.begin() + k, along.end());
      return along[size_t(k)];
    };
    lo[size_t(a)] = quantile(0.25);
    hi[size_t(a)] = quantile(0.75);
    widest = std::max(widest, hi[size_t(a)] - lo[size_t(a)]);
  }
  Part middle;
  for (size_t i = 0; i < m; ++i) {
    const Vec3& p = part.points[i];
    bool inside = true;
    for (int a = 0; a < 3; ++a)
      inside = inside && p[a] >= lo[size_t(a)] - 8 * widest && p[a] <= hi[size_t(a)] + 8 * widest;
    if (inside) {
      middle.points.push_back(p);
      middle.original.push_back(part.original[i]);
    }
  }
  return middle.points.size() * 10 >= m * 9 ? middle : part;
}

/// The occupancy grid of a part, or for a point alone (or copies of one) a grid of one cell.
NeighborGrid grid_of(const Part& part, ProgressTracker& tracker, bool& crowded) {
  crowded = false;
  if (part.points.size() >= 2 && largest_side(part.points) > 0)
    return occupancy_grid(part.points.data(), part.points.size(), tracker, crowded);
  return NeighborGrid(part.points.data(), part.points.size(), 1.0);
}

/// The points as searched, when one grid cannot hold them finely enough (occupancy_grid's
/// `crowded`: a few particles flung a million times the cloud's size away, two objects as far
/// apart): the clusters split at the gaps between them, each on its own grid (into `grids`);
/// and of a cluster still crowded, its middle. Empty, and `grids` untouched, when one grid
/// serves all after all (as for copies of a few points, which crowd their cells at any size).
std::vector<Part> far_apart_parts(const Vec3* points, size_t n, ProgressTracker& tracker,
                                  std::vector<NeighborGrid>& grids) {
  Part all;
  all.points.assign(points, points + n);
  all.original.resize(n);
  std::iota(all.original.begin(), all.original.end(), 0u);
  std::vector<Part> parts;
  split_at_gaps(std::move(all), parts);
  std::vector<NeighborGrid> own;
  for (Part& part : parts) {
    bool crowded = false;
    NeighborGrid grid = grid_of(part, tracker, crowded);
    if (crowded) {
      Part middle = middle_of(part);
      if (middle.points.size() != part.points.size()) {
        part = std::move(middle);
        grid = grid_of(part, tracker, crowded);
      }
    }
    own.push_back(std::move(grid));
  }
  if (parts.size() == 1 && parts[0].points.size() == n) return {};  // one grid serves after all
  grids = std::move(own);
  return parts;
}

/// Points asked about in a cell above which its neighbourhood is searched on a finer grid of
/// its own.
constexpr size_t kCrowdedCell = 64;
/// Finer grids within finer grids at most (a cluster within a cluster within a cloud).
constexpr int kMaxFinerGrids = 3;
/// Rings of cells searched at most around a point (beyond, its distance is taken as infinite).
constexpr int kMaxRing = 3;

/// nn2[s] (+inf on entry), for each point s of `grid` that query[s] marks: the squared distance
/// to its nearest other point (at a distance > 0), +inf when that lies farther than kMaxRing cells
/// (such points are above the median unless the cells are far too small, which the caller
/// detects). A cell holding more than kCrowdedCell points (a cluster far denser than the
/// cells: a close-up scan merged into a wide one, a lidar's near field) would have each of its
/// points measure every point of the 27 cells, n^2 over the cluster: the points of those cells'
/// neighbourhoods are gridded again, finer (the occupancy grid of their own), and searched
/// there, recursively; a distance found there within the cell size is the one the 27 cells
/// give (every point within it lies in them, and they are all in the finer grid), else the
/// point is searched here as the others.
void nearest_squared(const NeighborGrid& grid, const std::vector<uint8_t>& query, std::vector<double>& nn2,
                     ProgressTracker& tracker, int depth = 0) {
  constexpr double kInf = std::numeric_limits<double>::infinity();
  const double h = grid.cell_size();
  const auto cells = uint32_t(grid.cell_count());
  // A point whose distance the finer grid found (within h: finite) is not searched here again.
  const auto found = [&](uint32_t s) { return nn2[s] <= h * h; };
  if (depth < kMaxFinerGrids) {
    // The crowded cells, and every cell around one (its neighbourhood's points): crowded by
    // the points asked about (copies of one point are asked once).
    const std::vector<uint8_t> take = crowded_cells(grid, kCrowdedCell, [&](uint32_t s) { return query[s] != 0; });
    if (!take.empty()) {
      std::vector<Vec3> points;
      std::vector<uint32_t> from;  // per point of the finer grid's input, its sorted index here
      std::vector<uint8_t> asked;  // and whether it is asked about here and in a crowded cell
      for (uint32_t c = 0; c < cells; ++c)
        if (take[c])
          for (uint32_t s = grid.cell_begin(c); s < grid.cell_end(c); ++s) {
            points.push_back(grid.sorted_point(s));
            from.push_back(s);
            asked.push_back(take[c] == 2 && query[s]);
          }
      // (Copies of one point crowd a cell at any size: no finer grid holds them apart.)
      bool crowded = false;
      const std::optional<NeighborGrid> finer =
          largest_side(points) > 0 ? std::optional<NeighborGrid>(occupancy_grid(points.data(), points.size(), tracker, crowded))
                                   : std::nullopt;
      if (finer && finer->cell_size() < h) {
        const auto here = [&](uint32_t t) { return from[finer->original_index(t)]; };
        std::vector<double> fine(finer->point_count(), kInf);
        std::vector<uint8_t> asked_there(finer->point_count());
        for (uint32_t t = 0; t < finer->point_count(); ++t) asked_there[t] = asked[finer->original_index(t)];
        nearest_squared(*finer, asked_there, fine, tracker, depth + 1);
        for (uint32_t t = 0; t < finer->point_count(); ++t)
          if (asked_there[t] && fine[t] <= h * h) nn2[here(t)] = fine[t];
      }
    }
  }
  parallel_blocks(cells, 512, [&](size_t cb, size_t ce) {
    if (tracker.cancelled()) return;
    uint32_t around[27];
    NeighborCellWalk walk(grid);
    // The 27 cells' points by coordinate: each point of the cell measures them all in a loop
    // the compiler turns into vector instructions.
    std::vector<double> bx, by, bz;
    for (size_t c = cb; c < ce; ++c) {
      bool any = false;
      for (uint32_t s = grid.cell_begin(uint32_t(c)); s < grid.cell_end(uint32_t(c)) && !any; ++s)
        any = query[s] && !found(s);
      if (!any) {
        if (depth == 0) tracker.tick(1);
        continue;
      }
      const int na = walk.around(uint32_t(c), around);
      // (Written by index into room for all: push_back's possible reallocation kept the copy
      // from running as a plain loop.)
      size_t m = 0;
      for (int a = 0; a < na; ++a) m += grid.cell_end(around[a]) - grid.cell_begin(around[a]);
      if (bx.size() < m) bx.resize(m), by.resize(m), bz.resize(m);
      m = 0;
      for (int a = 0; a < na; ++a)
        for (uint32_t t = grid.cell_begin(around[a]); t < grid.cell_end(around[a]); ++t, ++m) {
          const Vec3& q = grid.sorted_point(t);
          bx[m] = q.x, by[m] = q.y, bz[m] = q.z;
        }
      for (uint32_t s = grid.cell_begin(uint32_t(c)); s < grid.cell_end(uint32_t(c)); ++s) {
        if (!query[s] || found(s)) continue;
        const Vec3 p = grid.sorted_point(s);
        // The least distance > 0 (0: the point itself, or a copy), each as squared_distance(q, p)
        // takes it, in four running minima (the least is the least in any order).
        double lanes[4] = {kInf, kInf, kInf, kInf};
        for (size_t i = 0; i < m; ++i) {
          const double dx = bx[i] - p.x, dy = by[i] - p.y, dz = bz[i] - p.z;
          const double d2 = dx * dx + dy * dy + dz * dz;
          double& l = lanes[i & 3];
          l = d2 > 0 && d2 < l ? d2 : l;
        }
        double best = std::min(std::min(lanes[0], lanes[1]), std::min(lanes[2], lanes[3]));
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
      if (depth == 0) tracker.tick(1);
    }
  });
}

}  // namespace

namespace {

/// Of the points in cells cells[0..count) that `distinct` accepts, other than s: counts in
/// `within` those closer to p than sqrt(far2), up to 2, the last one counted in `partner`.
template <typename Distinct>
void count_near(const NeighborGrid& grid, const uint32_t* cells, int count, uint32_t s, const Vec3& p, double far2,
                const Distinct& distinct, uint32_t& within, uint32_t& partner) {
  for (int a = 0; a < count && within < 2; ++a)
    for (uint32_t t = grid.cell_begin(cells[a]); t < grid.cell_end(cells[a]); ++t) {
      if (t == s || !distinct(t)) continue;
      if (squared_distance(grid.sorted_point(t), p) < far2) {
        partner = t;
        if (++within == 2) return;
      }
    }
}

/// For each distinct point of `grid` whose nearest distinct neighbour (nn2: squared distance)
/// lies within kTwinRatio of the cell size, and every other distinct point beyond
/// 1 / kTwinRatio times that: twin[its input index] = its neighbour's. Both are within the 27
/// cells around the point, which hold every point within one cell size of it, so the test is
/// exact. On an even sampling nearly no point has so near a neighbour (a cell holds a few
/// points), and the pass costs a look at nn2. An exact copy's twin is the first copy. The
/// point's own cell is searched first: most points find a second one that near there and
/// stop. A cell holding more than kCrowdedCell such points (a cluster far denser than the
/// cells) would have each of them scan the cluster, which lies in the 27 cells: their search
/// runs on a finer grid of the distinct points of those cells' neighbourhoods instead, ring
/// by ring out to the one that holds every point within the far distance (kMaxRing rings at
/// most: a point not decided by then is searched here). The result does not depend on the
/// order of the search.
void find_twins(const NeighborGrid& grid, const std::vector<uint32_t>& rep, const std::vector<double>& nn2,
                const std::vector<uint32_t>* original, std::vector<uint32_t>& twin) {
  const double h = grid.cell_size(), near2 = kTwinRatio * kTwinRatio * h * h;
  const auto input = [&](uint32_t s) { return original ? (*original)[grid.original_index(s)] : grid.original_index(s); };
  const auto asked = [&](uint32_t s) { return rep[s] == s && nn2[s] <= near2; };
  const auto cells = uint32_t(grid.cell_count());
  // The crowded cells (2) and the cells around them (1).
  const std::vector<uint8_t> take = crowded_cells(grid, kCrowdedCell, asked);
  const bool any_crowded = !take.empty();
  // Per point: 1 in a crowded cell, 2 once its search is done.
  std::vector<uint8_t> done(any_crowded ? grid.point_count() : 0);
  if (any_crowded) {
    for (uint32_t c = 0; c < cells; ++c)
      if (take[c] == 2) std::fill(done.begin() + grid.cell_begin(c), done.begin() + grid.cell_end(c), 1);
    std::vector<Vec3> points;
    std::vector<uint32_t> from;  // per point of the finer grid's input, its sorted index here
    for (uint32_t c = 0; c < cells; ++c)
      if (take[c])
        for (uint32_t s = grid.cell_begin(c); s < grid.cell_end(c); ++s)
          if (rep[s] == s) {
            points.push_back(grid.sorted_point(s));
            from.push_back(s);
          }
    bool crowded = false;
    const ProgressCallback none;
    ProgressTracker quiet(none);
    const NeighborGrid finer = occupancy_grid(points.data(), points.size(), quiet, crowded);
    const double hf = finer.cell_size();
    if (hf < h)
      parallel_blocks(finer.cell_count(), 512, [&](size_t cb, size_t ce) {
        // The occupied cells at ring r around the cell (shells[r - 1]), found once per cell.
        std::array<std::vector<uint32_t>, kMaxRing> shells;
        int found = 0;
        const auto all = [](uint32_t) { return true; };
        for (size_t c = cb; c < ce; ++c) {
          const auto cc = finer.cell_coord(uint32_t(c));
          found = 0;
          for (uint32_t t = finer.cell_begin(uint32_t(c)); t < finer.cell_end(uint32_t(c)); ++t) {
            const uint32_t s = from[finer.original_index(t)];
            if (done[s] != 1 || !asked(s)) continue;
            const double far2 = nn2[s] / (kTwinRatio * kTwinRatio);
            // Every point within the far distance lies within `rings` rings; out to kMaxRing at
            // most here (a second one found ends it either way), the rest on this grid below.
            const double rings = std::ceil(std::sqrt(far2) / hf);
            const Vec3 p = finer.sorted_point(t);
            uint32_t within = 0, partner = t;
            const uint32_t own = uint32_t(c);
            count_near(finer, &own, 1, t, p, far2, all, within, partner);
            for (int r = 1; r <= kMaxRing && r <= rings && within < 2; ++r) {
              auto& shell = shells[size_t(r - 1)];
              if (found < r) {
                shell.clear();
                for (int dx = -r; dx <= r; ++dx)
                  for (int dy = -r; dy <= r; ++dy)
                    for (int dz = -r; dz <= r; ++dz) {
                      if (std::max({std::abs(dx), std::abs(dy), std::abs(dz)}) != r) continue;
                      const uint32_t nc = finer.find_cell({cc[0] + dx, cc[1] + dy, cc[2] + dz});
                      if (nc != NeighborGrid::kNoCell) shell.push_back(nc);
                    }
                found = r;
              }
              count_near(finer, shell.data(), int(shell.size()), t, p, far2, all, within, partner);
            }
            if (within < 2 && rings > double(kMaxRing)) continue;
            if (within == 1) twin[input(s)] = input(from[finer.original_index(partner)]);
            done[s] = 2;
          }
        }
      });
  }
  parallel_blocks(cells, 512, [&](size_t cb, size_t ce) {
    uint32_t around[27];
    NeighborCellWalk walk(grid);
    const auto distinct = [&](uint32_t t) { return rep[t] == t; };
    for (size_t c = cb; c < ce; ++c) {
      int na = -1;
      for (uint32_t s = grid.cell_begin(uint32_t(c)); s < grid.cell_end(uint32_t(c)); ++s) {
        if (rep[s] != s) twin[input(s)] = input(rep[s]);  // an exact copy goes with its first
        if (!asked(s) || (any_crowded && done[s] == 2)) continue;
        if (na < 0) {
          // Its own cell first, then the others.
          na = walk.around(uint32_t(c), around);
          std::stable_partition(around, around + na, [&](uint32_t x) { return x == uint32_t(c); });
        }
        const Vec3 p = grid.sorted_point(s);
        const double far2 = nn2[s] / (kTwinRatio * kTwinRatio);
        uint32_t within = 0, partner = s;
        count_near(grid, around, na, s, p, far2, distinct, within, partner);
        if (within == 1) twin[input(s)] = input(partner);
      }
    }
  });
}

/// Each group of points joined by twins' links (and exact copies) as its lowest input index:
/// twin[i] becomes that index.
void merge_twins(std::vector<uint32_t>& twin) {
  DisjointSets groups(twin.size());
  for (uint32_t i = 0; i < twin.size(); ++i) groups.unite(i, twin[i]);
  for (uint32_t i = 0; i < twin.size(); ++i) twin[i] = groups.find(i);
}

}  // namespace

SpacingEstimate estimate_spacing_impl(const Vec3* points, size_t n, ProgressTracker& tracker,
                                      double begin, double end, size_t stride, std::vector<uint32_t>* twin_of) {
  if (twin_of) twin_of->clear();
  if (n < 2) throw Error(Status::InvalidInput, "at least two points are needed to estimate the spacing");
  tracker.stage("estimating spacing", begin, begin + 0.2 * (end - begin));
  // One grid over every point, or (points far apart) one per part.
  std::vector<NeighborGrid> grids;
  std::vector<Part> parts;
  {
    bool crowded = false;
    grids.push_back(occupancy_grid(points, n, tracker, crowded));
    if (crowded) parts = far_apart_parts(points, n, tracker, grids);
  }
  // The input points that count but lie in no part (left out of a part's middle): all of them,
  // or those of the sample.
  size_t outside = 0;
  if (!parts.empty()) {
    std::vector<uint8_t> searched(n);
    for (const Part& part : parts)
      for (uint32_t i : part.original) searched[i] = 1;
    for (size_t i = 0; i < n; ++i) outside += !searched[i] && (stride == 1 || i % stride == 0);
  }

  constexpr double kInf = std::numeric_limits<double>::infinity();
  for (int attempt = 0; attempt < 8; ++attempt) {
    tracker.check();
    if (attempt > 0)
      for (size_t g = 0; g < grids.size(); ++g)
        grids[g] = parts.empty() ? NeighborGrid(points, n, grids[g].cell_size() * 4.0)
                                 : NeighborGrid(parts[g].points.data(), parts[g].points.size(), grids[g].cell_size() * 4.0);
    size_t duplicates = 0, cells = 0;
    std::vector<std::vector<uint32_t>> reps(grids.size());
    for (size_t g = 0; g < grids.size(); ++g) {
      size_t d = 0;
      if (stride == 1) reps[g] = find_duplicates(grids[g], &d);
      duplicates += d;
      cells += grids[g].cell_count();
    }
    const size_t distinct = n - duplicates;
    if (distinct < 2) throw Error(Status::InvalidInput, "all points coincide: there is no spacing");
    tracker.check();

    tracker.stage("estimating spacing", begin + 0.2 * (end - begin), end, cells);
    std::vector<uint32_t> twins;
    if (stride == 1) {
      twins.resize(n);
      std::iota(twins.begin(), twins.end(), 0u);
    }
    std::vector<double> values;
    values.reserve(distinct / stride + 1);
    for (size_t g = 0; g < grids.size(); ++g) {
      const NeighborGrid& grid = grids[g];
      const std::vector<uint32_t>& rep = reps[g];
      // The points whose distance counts: each distinct point once, or the sample.
      const auto counted = [&](uint32_t s) {
        const uint32_t i = grid.original_index(s);
        return stride == 1 ? rep[s] == s : (parts.empty() ? i : parts[g].original[i]) % stride == 0;
      };
      // nn2[s] = squared distance from sorted point s to its nearest distinct point, +inf when
      // that is farther than kMaxRing cells (nearest_squared).
      std::vector<uint8_t> query(grid.point_count());
      parallel_blocks(grid.point_count(), 65536, [&](size_t b, size_t e) {
        for (size_t s = b; s < e; ++s) query[s] = counted(uint32_t(s));
      });
      std::vector<double> nn2(grid.point_count(), kInf);
      nearest_squared(grid, query, nn2, tracker);
      tracker.check();
      for (size_t s = 0; s < nn2.size(); ++s)
        if (query[s]) values.push_back(nn2[s]);
      if (stride == 1) find_twins(grid, rep, nn2, parts.empty() ? nullptr : &parts[g].original, twins);
    }
    values.insert(values.end(), outside, kInf);
    const size_t mid = (values.size() - 1) / 2;  // the lower median: an actual NN distance
    std::nth_element(values.begin(), values.begin() + long(mid), values.end());
    if (values[mid] == kInf) continue;  // most points are isolated at this cell size: widen
    SpacingEstimate result;
    if (stride == 1) {
      size_t count = 0;
      for (size_t i = 0; i < twins.size(); ++i) count += twins[i] != i;
      if (double(count - std::min(count, duplicates)) >= kTwinnedFraction * double(distinct)) {
        merge_twins(twins);
        size_t merged = 0;
        for (size_t i = 0; i < twins.size(); ++i) merged += twins[i] != i;
        result.near_duplicates = merged - std::min(merged, duplicates);
        if (twin_of) *twin_of = std::move(twins);
      }
    }
    result.spacing = std::sqrt(values[mid]);
    result.distinct_points = distinct;
    result.duplicate_points = duplicates;
    return result;
  }
  // Copies of two points only (each alone on its side of the gap between them counts as
  // infinitely far): their distance.
  const Vec3 first = points[0];
  const Vec3* other = nullptr;
  bool two = true;
  for (size_t i = 1; i < n && two; ++i) {
    if (points[i] == first) continue;
    if (!other) other = &points[i];
    two = points[i] == *other;
  }
  if (two && other) {
    SpacingEstimate result;
    result.spacing = distance(first, *other);
    result.distinct_points = 2;
    result.duplicate_points = n - 2;
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
    std::vector<uint32_t> group;
    auto r = detail::estimate_spacing_impl(points, n, tracker, 0.0, 0.8, 1, &group);
    r.spacing_apart = r.spacing;
    if (!group.empty()) {
      // Twinned: the spacing of the first point of each group, as reconstruct_surface meshes.
      std::vector<Vec3> firsts;
      for (size_t i = 0; i < n; ++i)
        if (group[i] == i) firsts.push_back(points[i]);
      r.spacing_apart = detail::estimate_spacing_impl(firsts.data(), firsts.size(), tracker, 0.8, 1.0).spacing;
    }
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
