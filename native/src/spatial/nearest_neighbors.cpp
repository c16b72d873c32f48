#include "spatial/nearest_neighbors.h"

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstdlib>
#include <optional>
#include <utility>
#include <vector>

#include "core/cpu_clones.h"
#include "core/parallel.h"
#include "core/select_within.h"
#include "spatial/spacing_impl.h"
#include "particlemesh/core/error.h"

namespace PM_NAMESPACE::detail {

// Written over the library's own grid rather than with a k-d tree (nanoflann, PCL's FLANN): the
// grid is the neighbour structure of every other stage, its sorted order breaks ties, and on
// surface samplings the 5^3 cells around a point's cell hold its nearest, gathered once for all
// the cell's points. The cells are found by column (x, y), each a run of the grid's cells, and
// the columns through their sorted keys, walked forward (a look-up per cell cost 125 random
// reads per cell; one per column, every column of every ring, was most of a far point's search).

namespace {

/// A neighbour as (squared distance's bits << 32) | index (its sorted index, or on a finer grid
/// the one it has on the grid searched first): ordered as (distance, index).
__extension__ typedef unsigned __int128 Key;

constexpr uint64_t column_key(int32_t x, int32_t y) { return (uint64_t(uint32_t(x)) << 21) | uint64_t(uint32_t(y)); }

/// The grid's occupied cells grouped by column: cells (x, y, *) are one run of the grid's
/// (lexicographic) cell order, z increasing.
struct Columns {
  std::vector<uint64_t> keys;    // column_key per column, increasing
  std::vector<uint32_t> start;   // first cell of each column; start.back() = cell count

  explicit Columns(const NeighborGrid& grid) {
    const auto cells = uint32_t(grid.cell_count());
    for (uint32_t c = 0; c < cells; ++c) {
      const auto cc = grid.cell_coord(c);
      const uint64_t key = column_key(cc[0], cc[1]);
      if (keys.empty() || keys.back() != key) {
        keys.push_back(key);
        start.push_back(c);
      }
    }
    start.push_back(cells);
  }
};

/// Runs [begin, end) of sorted indices: the points of a block of cells (cells next to each other
/// along z are one run of the grid's points).
using Ranges = std::vector<std::pair<uint32_t, uint32_t>>;

void append(Ranges& ranges, uint32_t begin, uint32_t end) {
  if (begin == end) return;
  if (!ranges.empty() && ranges.back().second == begin)
    ranges.back().second = end;
  else
    ranges.push_back({begin, end});
}

/// Appends to `out` the points of column `col`'s cells with z in [cc.z - ring, cc.z + ring]
/// whose coordinates differ from `cc` by more than `inner` along some axis (dxy: the column's
/// distance in x, y).
void gather_column(const NeighborGrid& grid, const Columns& cols, uint32_t col, int32_t dxy,
                   const NeighborGrid::CellCoord& cc, int32_t ring, int32_t inner, Ranges& out) {
  // z increases along the column's run of cells.
  uint32_t lo = cols.start[col], hi = cols.start[col + 1];
  const uint32_t end = hi;
  while (lo < hi) {  // the first cell with z >= cc.z - ring
    const uint32_t mid = lo + (hi - lo) / 2;
    if (grid.cell_coord(mid)[2] < cc[2] - ring)
      lo = mid + 1;
    else
      hi = mid;
  }
  for (uint32_t c = lo; c < end; ++c) {
    const int32_t dz = grid.cell_coord(c)[2] - cc[2];
    if (dz > ring) break;
    const int32_t d = std::max(dxy, std::abs(dz));
    if (d <= inner) continue;
    append(out, grid.cell_begin(c), grid.cell_end(c));
  }
}

/// The first gather (rings 0 to 2, every cell: the columns within 2 in x and y, in increasing
/// order) for the cells of one block taken in increasing order, found without a hash look-up. The
/// cells' columns never decrease, so for each x offset a cursor into the sorted column keys
/// only moves forward, and the columns (x + dx, y - 2 .. y + 2) are the keys it passes over.
/// Each column's cells within the ring along z are consecutive, so their points join one run
/// (`append` merges them; split by ring into two lists, the runs were a tenth of the search).
class RingTwoColumns {
 public:
  explicit RingTwoColumns(const Columns& cols) : cols_(cols) {}

  void gather(const NeighborGrid& grid, const NeighborGrid::CellCoord& cc, Ranges& block) {
    constexpr int32_t kRing = 2;
    const auto& keys = cols_.keys;
    for (int32_t dx = -kRing; dx <= kRing; ++dx) {
      const int32_t x = cc[0] + dx;
      if (x < 0) continue;
      const uint64_t from = column_key(x, std::max(cc[1] - kRing, 0));
      const uint64_t to = column_key(x, std::min(cc[1] + kRing, NeighborGrid::kMaxCellsPerAxis + 3));
      uint32_t& at = cursor_[size_t(dx + kRing)];
      if (!started_) at = uint32_t(std::lower_bound(keys.begin(), keys.end(), from) - keys.begin());
      while (at < keys.size() && keys[at] < from) ++at;
      // Every cell within the ring (inner -1): a column's cells, consecutive, join one run.
      for (uint32_t col = at; col < keys.size() && keys[col] <= to; ++col)
        gather_column(grid, cols_, col, 0, cc, kRing, -1, block);
    }
    started_ = true;
  }

 private:
  const Columns& cols_;
  std::array<uint32_t, 5> cursor_{};
  bool started_ = false;
};

/// The rings beyond the second around one cell, a shell at a time, without a hash look-up per
/// column: the columns found so far (each with its distance from the cell in x, y) and, per
/// row x of the square, the run of the sorted column keys its columns span, which each ring
/// widens by at most one key at each end. Where a point's neighbours are far in cells (the
/// sparse far field of a lidar sweep, a cloud whose density varies by orders of magnitude)
/// the search goes out to kMaxNeighborRing, and looking up all (2 r + 1)^2 columns of every
/// ring was most of its time.
class Shells {
 public:
  Shells(const NeighborGrid& grid, const Columns& cols) : grid_(grid), cols_(cols) {}

  /// Starts the walk around cell coordinates cc, whose rings 0 to 2 were gathered.
  void start(const NeighborGrid::CellCoord& cc) {
    cc_ = cc;
    ring_ = 2;
    known_.clear();
    rows_.clear();
    first_x_ = cc[0] - ring_;
    for (int32_t x = first_x_; x <= cc[0] + ring_; ++x) rows_.push_back(row(x, ring_));
    for (size_t i = 0; i < rows_.size(); ++i)
      for (uint32_t col = rows_[i].first; col < rows_[i].second; ++col) known_.push_back({col, dxy(col)});
  }

  /// Appends the points of the cells at Chebyshev distance ring_ + 1 from the cell (the next
  /// shell) to `out`, and returns that ring.
  int32_t next(Ranges& out) {
    const int32_t r = ++ring_;
    constexpr int32_t kTop = NeighborGrid::kMaxCellsPerAxis + 3;
    // The columns known so far: their cells r away along z.
    for (const auto& [col, d] : known_) gather_column(grid_, cols_, col, d, cc_, r, r - 1, out);
    const size_t old_known = known_.size();
    // The rows so far: one column more at each end where the keys there are (x, y -/+ r).
    const auto& keys = cols_.keys;
    for (size_t i = 0; i < rows_.size(); ++i) {
      const int32_t x = first_x_ + int32_t(i);
      if (x < 0 || x > kTop) continue;
      auto& [lo, hi] = rows_[i];
      if (cc_[1] - r >= 0 && lo > 0 && keys[lo - 1] == column_key(x, cc_[1] - r)) known_.push_back({--lo, r});
      if (cc_[1] + r <= kTop && hi < keys.size() && keys[hi] == column_key(x, cc_[1] + r)) known_.push_back({hi++, r});
    }
    // Two new rows, x -/+ r.
    rows_.insert(rows_.begin(), row(cc_[0] - r, r));
    rows_.push_back(row(cc_[0] + r, r));
    first_x_ = cc_[0] - r;
    for (const auto& [lo, hi] : {rows_.front(), rows_.back()})
      for (uint32_t col = lo; col < hi; ++col) known_.push_back({col, r});
    // The new columns: every cell of theirs within r along z.
    for (size_t i = old_known; i < known_.size(); ++i)
      gather_column(grid_, cols_, known_[i].first, r, cc_, r, r - 1, out);
    return r;
  }

 private:
  /// The run of column keys (x, y) with |y - cc.y| <= r (none for x outside the grid's range).
  std::pair<uint32_t, uint32_t> row(int32_t x, int32_t r) const {
    constexpr int32_t kTop = NeighborGrid::kMaxCellsPerAxis + 3;
    const auto& keys = cols_.keys;
    if (x < 0 || x > kTop) return {0, 0};
    const auto lo = std::lower_bound(keys.begin(), keys.end(), column_key(x, std::max(cc_[1] - r, 0)));
    const auto hi = std::upper_bound(lo, keys.end(), column_key(x, std::min(cc_[1] + r, kTop)));
    return {uint32_t(lo - keys.begin()), uint32_t(hi - keys.begin())};
  }
  int32_t dxy(uint32_t col) const {
    const uint64_t key = cols_.keys[col];
    const auto x = int32_t(key >> 21), y = int32_t(key & 0x1fffff);
    return std::max(std::abs(x - cc_[0]), std::abs(y - cc_[1]));
  }

  const NeighborGrid& grid_;
  const Columns& cols_;
  NeighborGrid::CellCoord cc_{};
  int32_t ring_ = 2;
  int32_t first_x_ = 0;                                 // the row of rows_[0]
  std::vector<std::pair<uint32_t, uint32_t>> rows_;     // per row, its run of column keys
  std::vector<std::pair<uint32_t, int32_t>> known_;     // columns found, with their distance in x, y
};

/// What one search over a grid is asked (the whole grid's, or a finer grid's over a crowded
/// part of it: search_crowded).
struct Search {
  /// Per sorted point: the index its ties are broken by and the lists give (null: its own).
  const uint32_t* key_of = nullptr;
  /// Per sorted point: whether to search it (null: every point).
  const uint8_t* asked = nullptr;
  /// Out, per sorted point searched: 1 where its k nearest lay within the rings' reach (exact),
  /// and the k-th nearest's squared distance (+inf with fewer).
  uint8_t* exact = nullptr;
  double* kth2 = nullptr;
  /// Whether to report progress (the whole grid's search only).
  bool ticks = true;
  int depth = 0;
};

/// Up to this many candidates the k nearest are found by counting each one's place (search).
constexpr size_t kRanked = 32;

/// The squared distances from p to the m points of a block (by coordinate) into e, as
/// squared_distance() takes them, and how many are in (0, reach2]: not the point itself, nor
/// a copy of it. (Counted in a double, which the compiler keeps in vector lanes; exact below
/// 2^53.) Compiled per x86-64 level (PM_CPU_CLONES).
PM_CPU_CLONES size_t block_distances(const double* x, const double* y, const double* z, size_t m, const Vec3& p,
                                     double reach2, double* __restrict e) {
  double within = 0;
  for (size_t i = 0; i < m; ++i) {
    const double d2 = squared_distance(Vec3{x[i], y[i], z[i]}, p);
    e[i] = d2;
    within += (d2 > 0 && d2 <= reach2) ? 1.0 : 0.0;
  }
  return size_t(within);
}

/// Each of `count` candidates' place among them, ordered by distance d, then index t (no two
/// alike): how many come before it, every pair compared, in loops without branches that the
/// compiler vectorizes. The arrays are padded to `padded` (a multiple of 4) with +inf.
/// On baseline x86-64 this costs what sorting the ~18 candidates of a point in one by one (an
/// insertion sort of 128-bit keys, its branches mispredicted) did; compiled per x86-64 level
/// (PM_CPU_CLONES) with block_distances, it makes the whole search 11-15 % faster on an
/// AVX-512 machine (bench/RESULTS.md).
PM_CPU_CLONES void places(const double* d, const double* t, size_t count, size_t padded, uint32_t* place) {
  for (size_t i = 0; i < count; ++i) {
    const double di = d[i], ti = t[i];
    double before = 0;
    for (size_t j = 0; j < padded; ++j) before += ((d[j] < di) | ((d[j] == di) & (t[j] < ti))) ? 1.0 : 0.0;
    place[i] = uint32_t(before);
  }
}

/// A cell holding more points than this (a cluster far denser than the cloud's median
/// spacing: a close-up scan merged into a wide one, a small object scanned finely beside a
/// large one) would have each of them measure every point of its 125 cells, quadratic in
/// the cluster: those cells' neighbourhoods are searched on a finer grid of their own.
constexpr size_t kCrowdedCell = 128;
/// Finer grids within finer grids at most.
constexpr int kMaxFinerGrids = 3;

void search(const NeighborGrid& grid, size_t K, const Search& q, std::vector<uint32_t>& out, ProgressTracker& tracker);

/// The points of `grid`'s crowded cells (kCrowdedCell) that q asks about, searched on a finer
/// grid over the points of the cells within two rings of a crowded cell (every point within
/// 2 h of them: all that the search here could take), with cells of twice their median
/// spacing. A point's result there is its result here when it is exact there and its k-th
/// nearest lies within 2 h (nearer than anything outside that set); ties break by the same
/// keys. Those points are marked in `resolved` (sized to the grid's points where any cell is
/// crowded, left empty otherwise); the others are left to the search here.
void search_crowded(const NeighborGrid& grid, size_t K, const Search& q, std::vector<uint32_t>& out,
                    std::vector<uint8_t>& resolved, ProgressTracker& tracker) {
  const double h = grid.cell_size();
  const auto cells = uint32_t(grid.cell_count());
  std::vector<uint8_t> take(cells, 0);  // 2: crowded, 1: within two rings of one
  bool any = false;
  for (uint32_t c = 0; c < cells; ++c) {
    if (grid.cell_end(c) - grid.cell_begin(c) <= kCrowdedCell) continue;
    size_t asked = 0;
    for (uint32_t s = grid.cell_begin(c); s < grid.cell_end(c); ++s) asked += !q.asked || q.asked[s];
    if (asked <= kCrowdedCell) continue;
    any = true;
    take[c] = 2;
    const auto cc = grid.cell_coord(c);
    grid.for_each_cell_in({cc[0] - 2, cc[1] - 2, cc[2] - 2}, {cc[0] + 2, cc[1] + 2, cc[2] + 2},
                          [&](uint32_t b) { take[b] = std::max<uint8_t>(take[b], 1); });
  }
  if (!any) return;
  resolved.assign(grid.point_count(), 0);
  std::vector<Vec3> points;
  std::vector<uint32_t> from;       // per point of the finer grid's input: its sorted index here
  std::vector<uint8_t> in_crowded;  // and whether it lies in a crowded cell
  for (uint32_t c = 0; c < cells; ++c)
    if (take[c])
      for (uint32_t s = grid.cell_begin(c); s < grid.cell_end(c); ++s) {
        points.push_back(grid.sorted_point(s));
        from.push_back(s);
        in_crowded.push_back(take[c] == 2);
      }
  std::optional<NeighborGrid> finer;
  try {
    const ProgressCallback none;
    ProgressTracker quiet(none);
    const double r0 = estimate_spacing_impl(points.data(), points.size(), quiet, 0.0, 1.0).spacing;
    if (!(2 * r0 < h)) return;
    finer.emplace(points.data(), points.size(), 2 * r0);
  } catch (const Error&) {
    return;  // (copies of a few points, or a grid too fine for the key: searched here)
  }
  const size_t m = finer->point_count();
  std::vector<uint32_t> key_of(m), fine_out(m * K, kNoNeighbor);
  std::vector<uint8_t> asked(m), exact(m, 0);
  std::vector<double> kth2(m, INFINITY);
  for (uint32_t t = 0; t < m; ++t) {
    const uint32_t i = finer->original_index(t), s = from[i];
    key_of[t] = q.key_of ? q.key_of[s] : s;
    asked[t] = in_crowded[i] && (!q.asked || q.asked[s]);
  }
  Search fq;
  fq.key_of = key_of.data();
  fq.asked = asked.data();
  fq.exact = exact.data();
  fq.kth2 = kth2.data();
  fq.ticks = false;
  fq.depth = q.depth + 1;
  search(*finer, K, fq, fine_out, tracker);
  for (uint32_t t = 0; t < m; ++t) {
    if (!asked[t] || !exact[t] || !(kth2[t] <= 4 * h * h)) continue;
    const uint32_t s = from[finer->original_index(t)];
    std::copy(fine_out.begin() + ptrdiff_t(size_t(t) * K), fine_out.begin() + ptrdiff_t(size_t(t + 1) * K),
              out.begin() + ptrdiff_t(size_t(s) * K));
    if (q.exact) q.exact[s] = 1;
    if (q.kth2) q.kth2[s] = kth2[t];
    resolved[s] = 1;
  }
}

void search(const NeighborGrid& grid, size_t K, const Search& q, std::vector<uint32_t>& out, ProgressTracker& tracker) {
  const double h = grid.cell_size();
  std::vector<uint8_t> resolved;  // (empty: no point was)
  if (q.depth < kMaxFinerGrids) {
    search_crowded(grid, K, q, out, resolved, tracker);
    tracker.check();
  }
  const auto wanted = [&](uint32_t s) { return (!q.asked || q.asked[s]) && (resolved.empty() || !resolved[s]); };
  const Columns cols(grid);
  parallel_blocks(grid.cell_count(), 256, [&](size_t cb, size_t ce) {
    if (tracker.cancelled()) return;
    Ranges block;  // the points of the cells within `ring` of the cell
    std::vector<uint32_t> open;  // the cell's points whose k nearest are not all found yet
    // The block's points by coordinate (and their sorted indices), and one point's squared
    // distances to them: every point of the cell measures the whole block, in a loop the
    // compiler turns into vector instructions, and then looks only at the few near enough.
    std::vector<double> bx, by, bz, be;
    std::vector<uint32_t> bt, near;
    Key best[64];
    uint32_t best_t[64];
    double guess = 0;  // the last point's k-th nearest squared distance (0: none yet)
    RingTwoColumns ring_two(cols);
    Shells shells(grid, cols);
    const Vec3* P = grid.sorted_points().data();
    for (size_t c = cb; c < ce; ++c) {
      const auto cc = grid.cell_coord(uint32_t(c));
      block.clear();
      open.clear();
      for (uint32_t s = grid.cell_begin(uint32_t(c)); s < grid.cell_end(uint32_t(c)); ++s)
        if (wanted(s)) open.push_back(s);
      if (open.empty()) {
        if (q.ticks) tracker.tick(grid.cell_end(uint32_t(c)) - grid.cell_begin(uint32_t(c)));
        continue;
      }
      // The first two rings at once, a run of points per column (the order of the block's
      // points changes no result: the k nearest are ranked by distance and index).
      ring_two.gather(grid, cc, block);
      bool walking = false;
      for (int32_t ring = 2; !open.empty(); ++ring) {
        if (ring > 2) {
          if (!walking) shells.start(cc);
          walking = true;
          shells.next(block);
        }
        size_t m = 0;
        for (const auto& [tb, te] : block) m += te - tb;
        bx.resize(m), by.resize(m), bz.resize(m), be.resize(m), bt.resize(m), near.resize(m + 16);
        m = 0;
        for (const auto& [tb, te] : block)
          for (uint32_t t = tb; t < te; ++t, ++m)
            bx[m] = P[t].x, by[m] = P[t].y, bz[m] = P[t].z, bt[m] = q.key_of ? q.key_of[t] : t;
        // After ring r the block holds every point within r h of any of the cell's points.
        const double reach2 = double(ring) * h * double(ring) * h;
        size_t still = 0;
        for (uint32_t s : open) {
          const Vec3 p = P[s];
          // Each distance as squared_distance() takes it, and how many lie within the rings'
          // reach (at a distance > 0: not the point itself, nor a copy of it). When k do, the
          // k smallest (distance, index) are all within it, and every point within it is in
          // the block: they are the k nearest.
          const size_t within = block_distances(bx.data(), by.data(), bz.data(), m, p, reach2, be.data());
          // The k smallest kept sorted, first only among the points within a little over the
          // last point's k-th nearest (neighbours are spaced alike: 1.15 x its square), so that
          // few are sorted in; when fewer than k lie that near, again within 1.6 x, then with no
          // bound. Each as one integer key, (distance, index) in order: a distance > 0 orders
          // as its bits do.
          size_t count = 0;
          for (double bound = guess > 0 ? 1.15 * guess : INFINITY;; bound = bound < 1.5 * guess ? 1.6 * guess : INFINITY) {
            const size_t candidates = select_within(be.data(), m, 0.0, bound, nullptr, 0, near.data());
            count = 0;
            if (candidates <= kRanked) {
              // Few candidates (the common case): each one's place among them counted (places),
              // and the first k places are the k smallest, in order. Distances as they are,
              // indices as doubles (exact); the tail padded with +inf in both, so that no
              // candidate, even one at an infinite distance, counts a pad before it.
              alignas(64) double cd[kRanked], ct[kRanked];
              const size_t padded = (candidates + 3) & ~size_t(3);
              for (size_t j = 0; j < candidates; ++j) cd[j] = be[near[j]], ct[j] = double(bt[near[j]]);
              for (size_t j = candidates; j < padded; ++j) cd[j] = INFINITY, ct[j] = INFINITY;
              uint32_t place[kRanked];
              places(cd, ct, candidates, padded, place);
              for (size_t i = 0; i < candidates; ++i)
                if (place[i] < K) best[place[i]] = (Key(std::bit_cast<uint64_t>(cd[i])) << 32) | bt[near[i]];
              count = std::min(candidates, K);
            } else {
              // Many (a bound too wide, or none): sorted in one by one.
              for (size_t j = 0; j < candidates; ++j) {
                const Key key = (Key(std::bit_cast<uint64_t>(be[near[j]])) << 32) | bt[near[j]];
                size_t pos;
                if (count < K) {
                  pos = count++;
                } else {
                  if (key > best[K - 1]) continue;
                  pos = K - 1;
                }
                for (; pos > 0 && key < best[pos - 1]; --pos) best[pos] = best[pos - 1];
                best[pos] = key;
              }
            }
            if (count == K || bound == INFINITY || (within < K && ring < kMaxNeighborRing)) break;
          }
          for (size_t j = 0; j < count; ++j) best_t[j] = uint32_t(best[j]);
          if (count == K) guess = std::bit_cast<double>(uint64_t(best[K - 1] >> 32));
          // At the last ring whatever the block holds.
          if (within >= K || ring == kMaxNeighborRing) {
            std::copy(best_t, best_t + count, out.begin() + ptrdiff_t(size_t(s) * K));
            if (q.exact) q.exact[s] = within >= K;
            if (q.kth2) q.kth2[s] = count == K ? std::bit_cast<double>(uint64_t(best[K - 1] >> 32)) : INFINITY;
          } else {
            open[still++] = s;
          }
        }
        open.resize(still);
      }
      if (q.ticks) tracker.tick(grid.cell_end(uint32_t(c)) - grid.cell_begin(uint32_t(c)));
    }
  });
}

}  // namespace

double nearest_neighbors_cell(const NeighborGrid& grid, size_t K) {
  constexpr size_t kSamples = 512;
  constexpr double kRingTwo = 1.6;
  const size_t n = grid.point_count();
  const double h = grid.cell_size();
  if (n < 8 * kSamples) return 0;  // (a small cloud: a second grid costs more than it saves)
  // Each sample's k-th nearest within 3 cells (+inf beyond), from the 7^3 cells around it; one
  // among more points than kBudget (a crowded cluster: its own grid serves it) counts as near.
  constexpr size_t kBudget = 4096;
  const double r2 = 9 * h * h;
  std::vector<double> kth, d2;
  kth.reserve(kSamples);
  for (size_t i = 0; i < kSamples; ++i) {
    const auto s = uint32_t(i * (n / kSamples));
    const Vec3 p = grid.sorted_point(s);
    const auto cc = grid.coord_of(p);
    d2.clear();
    size_t seen = 0;
    grid.for_each_cell_in({cc[0] - 3, cc[1] - 3, cc[2] - 3}, {cc[0] + 3, cc[1] + 3, cc[2] + 3}, [&](uint32_t c) {
      seen += grid.cell_end(c) - grid.cell_begin(c);
      if (seen > kBudget) return;
      for (uint32_t t = grid.cell_begin(c); t < grid.cell_end(c); ++t) {
        const double e2 = squared_distance(grid.sorted_point(t), p);
        if (e2 > 0 && e2 <= r2) d2.push_back(e2);
      }
    });
    if (seen > kBudget) {
      kth.push_back(0);
    } else if (d2.size() < K) {
      kth.push_back(INFINITY);
    } else {
      std::nth_element(d2.begin(), d2.begin() + ptrdiff_t(K - 1), d2.end());
      kth.push_back(d2[K - 1]);
    }
  }
  std::nth_element(kth.begin(), kth.begin() + kSamples / 2, kth.end());
  const double median = std::sqrt(kth[kSamples / 2]);
  if (!(median > kRingTwo * h)) return 0;
  return std::min(median / kRingTwo, 2 * h);
}

std::vector<uint32_t> nearest_neighbors(const NeighborGrid& grid, int k, ProgressTracker& tracker) {
  if (k < 1 || k > 64) throw Error(Status::InvalidArgument, "the neighbour count must be 1 to 64");
  const auto K = size_t(k);
  const size_t n = grid.point_count();
  std::vector<uint32_t> out(n * K, kNoNeighbor);
  const double cell = nearest_neighbors_cell(grid, K);
  std::optional<NeighborGrid> coarse;
  if (cell > 0) {
    try {
      coarse.emplace(grid.sorted_points().data(), n, cell);
    } catch (const Error&) {
      // (the coarser grid too: searched on this one)
    }
  }
  if (!coarse) {
    search(grid, K, Search{}, out, tracker);
    tracker.check();
    return out;
  }
  // Searched on the coarser grid, ties broken and neighbours named by this grid's indices (its
  // input is this grid's sorted points): the same k nearest wherever they are exact here, that
  // is wherever this grid's search would find its k within its rings (the k-th within
  // kMaxNeighborRing cells); the other points (their k-th farther, or fewer than k in reach)
  // are searched on this grid as before, so every list is the one this grid gives.
  const std::vector<uint32_t>& key_of = coarse->original_indices();
  std::vector<uint32_t> rows(n * K, kNoNeighbor);
  std::vector<uint8_t> exact(n, 0);
  std::vector<double> kth2(n, INFINITY);
  Search q;
  q.key_of = key_of.data();
  q.exact = exact.data();
  q.kth2 = kth2.data();
  search(*coarse, K, q, rows, tracker);
  tracker.check();
  const double h = grid.cell_size();
  const double reach2 = double(kMaxNeighborRing) * h * double(kMaxNeighborRing) * h;  // as search() takes it
  std::vector<uint8_t> again(n, 0);
  bool any = false;
  for (uint32_t t = 0; t < n; ++t) {
    const uint32_t s = key_of[t];
    if (exact[t] && kth2[t] <= reach2) {
      std::copy(rows.begin() + ptrdiff_t(size_t(t) * K), rows.begin() + ptrdiff_t(size_t(t + 1) * K),
                out.begin() + ptrdiff_t(size_t(s) * K));
    } else {
      again[s] = 1;
      any = true;
    }
  }
  if (any) {
    Search rest;
    rest.asked = again.data();
    rest.ticks = false;
    search(grid, K, rest, out, tracker);
    tracker.check();
  }
  return out;
}

}  // namespace particlemesh::detail
