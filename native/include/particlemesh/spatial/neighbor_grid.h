// A uniform hash grid over points, for fixed-radius neighbour queries.
//
// Written here rather than taken from a k-d tree library because the triangulation asks
// one kind of question millions of times, "all points within L of this one", on evenly
// spaced data: a grid of cell L answers it from 27 cells with no tree walk, and sorting
// the points by cell makes every query read memory that its neighbours just read.
#pragma once

#include "particlemesh/core/config.h"

#include <algorithm>
#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "particlemesh/core/export.h"
#include "particlemesh/core/vec3.h"

namespace PM_NAMESPACE {

class PM_EXPORT NeighborGrid {
 public:
  using CellCoord = std::array<int32_t, 3>;
  static constexpr uint32_t kNoCell = 0xffffffffu;
  static constexpr int32_t kMaxCellsPerAxis = (1 << 21) - 4;

  NeighborGrid() = default;

  /// Bucket `n` points into cubic cells of edge `cell_size` (> 0). Points are copied.
  /// Cells are ordered lexicographically by (x, y, z) cell coordinate and points by cell,
  /// then by input index, so the layout does not depend on the thread count.
  /// @throws Error(LimitExceeded) if the extent spans more than 2^21 - 4 cells along an axis
  ///         (a sign of far outliers; the message says so).
  NeighborGrid(const Vec3* points, size_t n, double cell_size);

  /// The same with the cells anchored at `lower` instead of at the points' smallest
  /// coordinates (`lower` must be at or below every point on every axis): grids over any
  /// subsets of one cloud built with the same `lower` and cell size then have the same cells,
  /// in the same order, so sums over a cell range visit the points alike (the tiles of a
  /// cloud polygonized apart, see PolygonizeOptions::domain_min).
  /// @throws Error(InvalidArgument) a point below `lower` or `lower` not finite;
  ///         Error(LimitExceeded) as above, measured from `lower`.
  NeighborGrid(const Vec3* points, size_t n, double cell_size, const Vec3& lower);
  /// The same (anchored at *lower, or at the points' smallest coordinates when it is null),
  /// with the points flagged in `apart` (n flags, non-zero = apart) kept out of the cells:
  /// they follow every cell's points in the sorted order, in input order (sorted indices
  /// [apart_begin(), point_count())), and no cell query finds them. For a few points whose
  /// reach is far beyond the others' (one huge particle among small ones), so that the cells
  /// can be sized by the others; the caller visits those apart itself. The bounds (and so the
  /// span limit) are taken over every point.
  NeighborGrid(const Vec3* points, size_t n, double cell_size, const Vec3* lower, const uint8_t* apart);

  double cell_size() const { return cell_size_; }
  size_t point_count() const { return sorted_points_.size(); }
  size_t cell_count() const { return cell_keys_.size(); }
  /// The first sorted index of the points kept apart (point_count() when none are).
  uint32_t apart_begin() const { return cell_start_.empty() ? 0 : cell_start_.back(); }

  /// Points in cell order: sorted_point(s) is the position of input point original_index(s).
  const Vec3& sorted_point(uint32_t s) const { return sorted_points_[s]; }
  uint32_t original_index(uint32_t s) const { return original_index_[s]; }
  const std::vector<Vec3>& sorted_points() const { return sorted_points_; }
  const std::vector<uint32_t>& original_indices() const { return original_index_; }

  /// Sorted-index range [cell_begin(c), cell_end(c)) of the points in cell c.
  uint32_t cell_begin(uint32_t c) const { return cell_start_[c]; }
  uint32_t cell_end(uint32_t c) const { return cell_start_[c + 1]; }
  CellCoord cell_coord(uint32_t c) const { return unpack(cell_keys_[c]); }

  /// Cell coordinate of a position (may lie outside the occupied cells).
  CellCoord coord_of(const Vec3& p) const {
    return {coord_on_axis(p.x, 0), coord_on_axis(p.y, 1), coord_on_axis(p.z, 2)};
  }
  /// Its component along `axis` (0 x, 1 y, 2 z): floor((v - origin) / cell), clamped to
  /// [0, kMaxCellsPerAxis + 3] so that queries far outside the data stay inside the key
  /// range. Inline and without a call to floor (baseline x86-64 has no rounding instruction):
  /// every field evaluation takes two of these per axis.
  int32_t coord_on_axis(double v, int axis) const {
    const double f = (v - origin_[axis]) * inv_cell_;
    if (!(f >= 1.0)) return 0;  // below the first cell's end (also NaN)
    if (!(f < double(kMaxCellsPerAxis + 4))) return kMaxCellsPerAxis + 3;
    return int32_t(f);  // truncation is the floor of a positive value
  }
  /// Index of the occupied cell at `coord`, or kNoCell.
  uint32_t find_cell(const CellCoord& coord) const {
    if (coord[0] < 0 || coord[1] < 0 || coord[2] < 0 || coord[0] > kMaxCellsPerAxis + 3 ||
        coord[1] > kMaxCellsPerAxis + 3 || coord[2] > kMaxCellsPerAxis + 3)
      return kNoCell;
    return find_key(pack(coord));
  }

  /// The occupied cells among the 27 around cell c (c included), in increasing cell order,
  /// so their points come out in increasing sorted index. Returns how many were written.
  int neighbor_cells(uint32_t c, uint32_t out[27]) const;

  /// Call f(c) for every occupied cell c whose coordinate lies in the box [lo, hi], in
  /// increasing cell order (= lexicographic coordinate order). Cost: about the box's cells or
  /// the occupied cells in it, whichever are fewer. (A box much larger than the cells, as a
  /// polygonization block of cell size h >> the particles' radius, looked up every empty cell
  /// of it: 3.8e8 lookups per block, found by fuzzing.)
  template <class F>
  void for_each_cell_in(CellCoord lo, CellCoord hi, F&& f) const {
    for (int a = 0; a < 3; ++a) {
      lo[a] = std::max(lo[a], int32_t(0));
      hi[a] = std::min(hi[a], int32_t(kMaxCellsPerAxis + 3));
      if (lo[a] > hi[a]) return;
    }
    const double box = double(hi[0] - lo[0] + 1) * double(hi[1] - lo[1] + 1) * double(hi[2] - lo[2] + 1);
    const auto begin = cell_keys_.begin(), end = cell_keys_.end();
    if (box <= double(cell_keys_.size()) && hi[2] - lo[2] < 3) {
      // A short box (a point's cell and its neighbours): along z a run of occupied cells is a
      // run of the sorted keys, so one look-up per run (and the cell after a run is empty).
      for (int32_t x = lo[0]; x <= hi[0]; ++x)
        for (int32_t y = lo[1]; y <= hi[1]; ++y)
          for (int32_t z = lo[2]; z <= hi[2]; ++z) {
            uint32_t c = find_key(pack({x, y, z}));
            if (c == kNoCell) continue;
            f(c);
            for (; z < hi[2] && c + 1 < cell_keys_.size() && cell_keys_[c + 1] == pack({x, y, z + 1}); ++z) f(++c);
            ++z;
          }
      return;
    }
    // Any other box (a point's surroundings to a few cells, where on a surface most of its
    // cells are empty; a ball as wide as the cloud's sparse parts need): the keys are walked
    // in order from the box's first, each stretch outside it (a column's cells below or above
    // it, a row beyond it, an x with no cells) skipped by a galloping search to the next key
    // that can be inside. Looking every cell up missed on most of them, and a scan of all the
    // keys with x in range read the cells far outside the box in y.
    auto it = gallop(begin, pack(lo));
    while (it != end) {
      const CellCoord cc = unpack(*it);
      if (cc[0] > hi[0]) return;
      if (cc[1] < lo[1]) {
        it = gallop(it, pack({cc[0], lo[1], lo[2]}));
      } else if (cc[1] > hi[1]) {
        if (cc[0] == hi[0]) return;
        it = gallop(it, pack({cc[0] + 1, lo[1], lo[2]}));
      } else if (cc[2] < lo[2]) {
        it = gallop(it, pack({cc[0], cc[1], lo[2]}));
      } else if (cc[2] > hi[2]) {
        if (cc[1] < hi[1]) it = gallop(it, pack({cc[0], cc[1] + 1, lo[2]}));
        else if (cc[0] < hi[0]) it = gallop(it, pack({cc[0] + 1, lo[1], lo[2]}));
        else return;
      } else {
        f(uint32_t(it - begin));
        ++it;
      }
    }
  }

  /// Call f(sorted_index, squared_distance) for every point within `radius` of `p`
  /// (including a point at p itself), in increasing sorted index. Cost: the cells that the
  /// query box [p - radius, p + radius] touches.
  template <class F>
  void for_each_within(const Vec3& p, double radius, F&& f) const {
    const double r2 = radius * radius;
    const CellCoord lo = coord_of(p - Vec3{radius, radius, radius});
    const CellCoord hi = coord_of(p + Vec3{radius, radius, radius});
    for_each_cell_in(lo, hi, [&](uint32_t c) {
      for (uint32_t s = cell_start_[c]; s < cell_start_[c + 1]; ++s) {
        const double d2 = squared_distance(sorted_points_[s], p);
        if (d2 <= r2) f(s, d2);
      }
    });
  }

 private:
  // Cells are keyed by their coordinates packed into 21 bits each: comparing and hashing a
  // key is one integer operation, and key order is lexicographic coordinate order.
  static uint64_t pack(const CellCoord& c) {
    return (uint64_t(uint32_t(c[0])) << 42) | (uint64_t(uint32_t(c[1])) << 21) | uint64_t(uint32_t(c[2]));
  }
  static CellCoord unpack(uint64_t k) {
    return {int32_t(k >> 42), int32_t((k >> 21) & 0x1fffff), int32_t(k & 0x1fffff)};
  }
  uint32_t find_key(uint64_t key) const;
  /// The first key at or after `from` that is not below `key` (keys before `from` are): a
  /// galloping search, a few steps when the key is near.
  std::vector<uint64_t>::const_iterator gallop(std::vector<uint64_t>::const_iterator from, uint64_t key) const {
    const auto end = cell_keys_.end();
    size_t step = 1;
    auto lo = from;
    while (lo != end && *lo < key) {
      const auto next = size_t(end - lo) > step ? lo + ptrdiff_t(step) : end;
      if (next == end || *next >= key) return std::lower_bound(lo + 1, next, key);
      lo = next;
      step *= 2;
    }
    return lo;
  }
  void build(const Vec3* points, size_t n, double cell_size, const Vec3* lower, const uint8_t* apart);

  double cell_size_ = 0;
  double inv_cell_ = 0;
  Vec3 origin_;
  std::vector<Vec3> sorted_points_;
  std::vector<uint32_t> original_index_;
  std::vector<uint32_t> cell_start_;
  std::vector<uint64_t> cell_keys_;
  std::vector<uint32_t> table_;  // open addressing: cell index or kNoCell
  uint64_t table_mask_ = 0;
};

}  // namespace particlemesh
