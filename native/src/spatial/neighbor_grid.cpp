#include "particlemesh/spatial/neighbor_grid.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "core/counting_sort.h"
#include "core/format_number.h"
#include "core/hashing.h"
#include "core/first_touch.h"
#include "core/parallel.h"
#include "core/uninit_allocator.h"
#include "particlemesh/core/error.h"

namespace PM_NAMESPACE {

namespace {

struct Entry {
  uint64_t key;  // the cell's coordinates packed, 21 bits each (NeighborGrid::pack)
  uint32_t index;
};

// By key, then by point index: the order a comparison sort by (key, index) gives, at a
// fraction of its cost (a third of a 100k-point grid build went to tbb::parallel_sort). LSD
// radix over the key's used bits only (no coordinate exceeds `top` along its axis: often
// 20-30 bits in all, 2-3 passes of 11 bits); each pass is stable and the entries start in
// index order, so equal keys stay in index order.
// The entries and the sort's second buffer are filled whole by parallel passes: left
// uninitialised (zeroing them, 16 bytes a point each, on one core took a tenth of a 1M-point
// build).
using Entries = std::vector<Entry, detail::UninitAllocator<Entry>>;

void sort_by_key(Entries& entries, const std::array<int32_t, 3>& top) {
  int bits[3];
  for (int a = 0; a < 3; ++a) bits[a] = int(std::bit_width(uint32_t(top[a])));
  // The key with the unused high bits of each field squeezed out: same order, fewer digits.
  constexpr uint64_t kField = (uint64_t(1) << 21) - 1;
  const auto compact = [&](uint64_t k) {
    return ((k >> 42) << (bits[1] + bits[2])) | (((k >> 21) & kField) << bits[2]) | (k & kField);
  };
  constexpr int kDigit = 11;
  constexpr uint64_t kDigitMask = (uint64_t(1) << kDigit) - 1;
  Entries other(entries.size());
  for (int shift = 0; shift < bits[0] + bits[1] + bits[2]; shift += kDigit) {
    const std::vector<size_t> start = detail::counting_place(
        entries.size(), kDigitMask + 1, [&](size_t i) { return (compact(entries[i].key) >> shift) & kDigitMask; },
        [&](size_t i, size_t pos) { other[pos] = entries[i]; }, true);
    if (!detail::one_bucket(start, entries.size())) entries.swap(other);
  }
}

}  // namespace

NeighborGrid::NeighborGrid(const Vec3* points, size_t n, double cell_size) {
  build(points, n, cell_size, nullptr, nullptr);
}

NeighborGrid::NeighborGrid(const Vec3* points, size_t n, double cell_size, const Vec3& lower) {
  build(points, n, cell_size, &lower, nullptr);
}

NeighborGrid::NeighborGrid(const Vec3* points, size_t n, double cell_size, const Vec3* lower, const uint8_t* apart) {
  build(points, n, cell_size, lower, apart);
}

void NeighborGrid::build(const Vec3* points, size_t n, double cell_size, const Vec3* lower, const uint8_t* apart) {
  if (!(cell_size > 0) || !std::isfinite(cell_size))
    throw Error(Status::InvalidArgument, "grid cell size must be positive and finite");
  if (n >= size_t(std::numeric_limits<uint32_t>::max()))
    throw Error(Status::LimitExceeded, "more than 4294967294 points");
  cell_size_ = cell_size;
  inv_cell_ = 1.0 / cell_size;
  if (!std::isfinite(inv_cell_))
    throw Error(Status::InvalidArgument,
                "grid cell size " + detail::format_number(cell_size) + " is too small to divide by");

  Vec3 lo{std::numeric_limits<double>::infinity(), std::numeric_limits<double>::infinity(),
          std::numeric_limits<double>::infinity()};
  Vec3 hi = -lo;
  // Per fixed block of points, then the blocks in order: the same bounds (even the sign of a
  // zero: the first of equal values is kept, as one pass would) for any thread count.
  constexpr size_t kBlock = 65536;
  const size_t blocks = (n + kBlock - 1) / kBlock;
  {
    std::vector<Vec3> block_lo(blocks, lo), block_hi(blocks, hi);
    detail::parallel_blocks(blocks, 1, [&](size_t kb, size_t ke) {
      for (size_t k = kb; k < ke; ++k) {
        Vec3 l = block_lo[k], h = block_hi[k];
        for (size_t i = k * kBlock; i < std::min(n, (k + 1) * kBlock); ++i) {
          l = {std::min(l.x, points[i].x), std::min(l.y, points[i].y), std::min(l.z, points[i].z)};
          h = {std::max(h.x, points[i].x), std::max(h.y, points[i].y), std::max(h.z, points[i].z)};
        }
        block_lo[k] = l, block_hi[k] = h;
      }
    });
    for (size_t k = 0; k < blocks; ++k) {
      const Vec3 &l = block_lo[k], &h = block_hi[k];
      lo = {std::min(lo.x, l.x), std::min(lo.y, l.y), std::min(lo.z, l.z)};
      hi = {std::max(hi.x, h.x), std::max(hi.y, h.y), std::max(hi.z, h.z)};
    }
  }
  if (n == 0) lo = hi = Vec3{};
  const Vec3 points_lo = lo;  // the points' own lower corner (lo may move to *lower)
  if (lower) {
    for (int a = 0; a < 3; ++a) {
      if (!std::isfinite((*lower)[a]))
        throw Error(Status::InvalidArgument, std::string("the grid's lower corner is not finite along ") + "xyz"[a]);
      if (n > 0 && lo[a] < (*lower)[a])
        throw Error(Status::InvalidArgument, std::string("a point lies below the grid's lower corner along ") + "xyz"[a]);
    }
    lo = *lower;
    if (n == 0) hi = lo;
  }
  // The origin sits one cell below the data so that the cells around any point exist.
  origin_ = lo - Vec3{cell_size, cell_size, cell_size};
  for (int a = 0; a < 3; ++a) {
    const double cells = (hi[a] - lo[a]) * inv_cell_;
    if (!(cells < double(kMaxCellsPerAxis - 4))) {
      const std::string axis(1, "xyz"[a]);
      const std::string span = "the points span " + detail::format_number(cells) + " cells of size " +
                               detail::format_number(cell_size) + " along " + axis + " (at most 2097148)";
      if ((hi[a] - points_lo[a]) * inv_cell_ < double(kMaxCellsPerAxis - 4)) {
        // The points alone would fit (one point always does: the gap search below needs two):
        // the span is from the grid's given lower corner.
        throw Error(Status::LimitExceeded,
                    span + ", from the grid's lower corner " + axis + " = " + detail::format_number(lo[a]) +
                        " to " + axis + " = " + detail::format_number(hi[a]) +
                        ": use a lower corner nearer the points, or larger cells");
      }
      // Name the point farthest from the others' median along the axis: usually a stray one (a
      // particle a simulation flung away, a scanner's invalid return at the origin of
      // georeferenced coordinates); and the widest empty stretch along it, with the points on
      // each side (two objects far apart: which box to crop to). Only on this error's path.
      std::vector<double> along(n);
      for (size_t i = 0; i < n; ++i) along[i] = points[i][a];
      std::nth_element(along.begin(), along.begin() + ptrdiff_t(n / 2), along.end());
      const double median = along[n / 2];
      size_t far = 0;
      for (size_t i = 1; i < n; ++i)
        if (std::abs(points[i][a] - median) > std::abs(points[far][a] - median)) far = i;
      std::sort(along.begin(), along.end());
      size_t below = 1;  // the points at or below the widest gap's lower end
      for (size_t i = 2; i < n; ++i)
        if (along[i] - along[i - 1] > along[below] - along[below - 1]) below = i;
      throw Error(Status::LimitExceeded,
                  span + ": point " + std::to_string(far) + " (" + axis + " = " + detail::format_number(points[far][a]) +
                      ") lies " + detail::format_number(std::abs(points[far][a] - median)) +
                      " from the points' median " + axis + " = " + detail::format_number(median) +
                      "; none lies between " + axis + " = " + detail::format_number(along[below - 1]) + " and " +
                      detail::format_number(along[below]) + " (" + std::to_string(below) + " below, " +
                      std::to_string(n - below) + " above); remove far outliers, or use larger cells");
    }
  }

  // The points in cells (all but those apart), m of them.
  Entries entries;
  if (apart == nullptr) {
    entries.resize(n);
    detail::parallel_blocks(n, 4096, [&](size_t b, size_t e) {
      for (size_t i = b; i < e; ++i) entries[i] = {pack(coord_of(points[i])), uint32_t(i)};
    });
  } else {
    for (size_t i = 0; i < n; ++i)
      if (!apart[i]) entries.push_back({pack(coord_of(points[i])), uint32_t(i)});
  }
  const size_t m = entries.size();
  sort_by_key(entries, n == 0 ? CellCoord{0, 0, 0} : coord_of(hi));

  // (Their pages faulted in on all cores, not while resize() zeroes them on this one.)
  detail::resize_touched(sorted_points_, n);
  detail::resize_touched(original_index_, n);
  detail::parallel_blocks(m, 4096, [&](size_t b, size_t e) {
    for (size_t s = b; s < e; ++s) {
      original_index_[s] = entries[s].index;
      sorted_points_[s] = points[entries[s].index];
    }
  });
  for (size_t i = 0, s = m; s < n; ++i)
    if (apart[i]) {
      original_index_[s] = uint32_t(i);
      sorted_points_[s++] = points[i];
    }
  // The cells: where the key changes. Counted per fixed block, then written at each block's
  // offset.
  const size_t cell_blocks = (m + kBlock - 1) / kBlock;
  std::vector<size_t> first_cell(cell_blocks + 1, 0);
  const auto starts_cell = [&](size_t s) { return s == 0 || entries[s].key != entries[s - 1].key; };
  detail::parallel_blocks(cell_blocks, 1, [&](size_t kb, size_t ke) {
    for (size_t k = kb; k < ke; ++k)
      for (size_t s = k * kBlock; s < std::min(m, (k + 1) * kBlock); ++s) first_cell[k + 1] += starts_cell(s);
  });
  for (size_t k = 0; k < cell_blocks; ++k) first_cell[k + 1] += first_cell[k];
  cell_start_.assign(first_cell[cell_blocks] + 1, uint32_t(m));
  cell_keys_.resize(first_cell[cell_blocks]);
  detail::parallel_blocks(cell_blocks, 1, [&](size_t kb, size_t ke) {
    for (size_t k = kb; k < ke; ++k) {
      size_t c = first_cell[k];
      for (size_t s = k * kBlock; s < std::min(m, (k + 1) * kBlock); ++s)
        if (starts_cell(s)) {
          cell_start_[c] = uint32_t(s);
          cell_keys_[c++] = entries[s].key;
        }
    }
  });

  table_mask_ = detail::build_key_table(cell_keys_, table_);
}

uint32_t NeighborGrid::find_key(uint64_t key) const {
  static_assert(kNoCell == detail::kNoKey);
  return detail::find_key(table_, table_mask_, cell_keys_, key);
}

int NeighborGrid::neighbor_cells(uint32_t c, uint32_t out[27]) const {
  const CellCoord cc = cell_coord(c);
  const auto cells = uint32_t(cell_keys_.size());
  int count = 0;
  // Along a column (x, y) the keys of z and z + 1 are next to each other in the sorted keys
  // when both cells are occupied (and when z + 1's is not the next key, that cell is empty):
  // one hash look-up per run of occupied cells, none in c's own column. (The lowest point's
  // cell can round to coordinate 0: the cells below it are then skipped; a coordinate -1
  // along x or y packs to a key no cell has.)
  const uint64_t first_dz = cc[2] == 0 ? 1 : 0;
  for (int dx = -1; dx <= 1; ++dx)
    for (int dy = -1; dy <= 1; ++dy) {
      // The key of z - 1 (wrapped when z is 0, and then unused); z and z + 1 follow.
      const uint64_t base = pack({cc[0] + dx, cc[1] + dy, cc[2]}) - 1;
      const bool own = dx == 0 && dy == 0;
      for (uint64_t dz = first_dz; dz < 3; ++dz) {
        uint32_t nc;
        if (own)
          nc = dz == 1 ? c : dz == 0 ? (c > 0 && cell_keys_[c - 1] == base ? c - 1 : kNoCell)
                                     : (c + 1 < cells && cell_keys_[c + 1] == base + 2 ? c + 1 : kNoCell);
        else
          nc = find_key(base + dz);
        if (nc == kNoCell) continue;
        out[count++] = nc;
        while (dz + 1 < 3 && nc + 1 < cells && cell_keys_[nc + 1] == base + dz + 1) out[count++] = ++nc, ++dz;
        ++dz;  // the cell after the run is empty
      }
    }
  return count;
}

}  // namespace particlemesh
