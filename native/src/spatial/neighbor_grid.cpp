#include "particlemesh/spatial/neighbor_grid.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include <tbb/parallel_sort.h>

#include "particlemesh/core/error.h"
#include "spatial/cell_hash.h"

namespace particlemesh {

namespace {
constexpr double kMaxCellsPerAxis = double(1 << 30);
}

NeighborGrid::NeighborGrid(const Vec3* points, size_t n, double cell_size) {
  if (!(cell_size > 0) || !std::isfinite(cell_size))
    throw Error(Status::InvalidArgument, "grid cell size must be positive and finite");
  if (n >= size_t(std::numeric_limits<uint32_t>::max()))
    throw Error(Status::LimitExceeded, "more than 4294967294 points");
  cell_size_ = cell_size;
  inv_cell_ = 1.0 / cell_size;

  Vec3 lo{std::numeric_limits<double>::infinity(), std::numeric_limits<double>::infinity(),
          std::numeric_limits<double>::infinity()};
  Vec3 hi = -lo;
  for (size_t i = 0; i < n; ++i) {
    lo = {std::min(lo.x, points[i].x), std::min(lo.y, points[i].y), std::min(lo.z, points[i].z)};
    hi = {std::max(hi.x, points[i].x), std::max(hi.y, points[i].y), std::max(hi.z, points[i].z)};
  }
  if (n == 0) lo = hi = Vec3{};
  // The origin sits one cell below the data so that queries just outside it stay in range.
  origin_ = lo - Vec3{cell_size, cell_size, cell_size};
  for (int a = 0; a < 3; ++a) {
    if ((hi[a] - lo[a]) * inv_cell_ + 4 > kMaxCellsPerAxis)
      throw Error(Status::LimitExceeded,
                  "the points span " + std::to_string((hi[a] - lo[a]) * inv_cell_) +
                      " cells of size " + std::to_string(cell_size) + " along axis " +
                      std::string(1, "xyz"[a]) +
                      " (at most 2^30): remove far outliers or use a larger spacing");
  }

  struct Entry {
    CellCoord c;
    uint32_t index;
  };
  std::vector<Entry> entries(n);
  for (size_t i = 0; i < n; ++i) entries[i] = {coord_of(points[i]), uint32_t(i)};
  tbb::parallel_sort(entries.begin(), entries.end(), [](const Entry& a, const Entry& b) {
    if (a.c != b.c) return a.c < b.c;
    return a.index < b.index;
  });

  sorted_points_.resize(n);
  original_index_.resize(n);
  cell_start_.clear();
  cell_coords_.clear();
  for (size_t s = 0; s < n; ++s) {
    original_index_[s] = entries[s].index;
    sorted_points_[s] = points[entries[s].index];
    if (s == 0 || entries[s].c != entries[s - 1].c) {
      cell_start_.push_back(uint32_t(s));
      cell_coords_.push_back(entries[s].c);
    }
  }
  cell_start_.push_back(uint32_t(n));

  uint64_t size = 16;
  while (size < 2 * uint64_t(cell_coords_.size())) size <<= 1;
  table_.assign(size, kNoCell);
  table_mask_ = size - 1;
  for (uint32_t c = 0; c < cell_coords_.size(); ++c) {
    uint64_t h = detail::hash_cell(cell_coords_[c]) & table_mask_;
    while (table_[h] != kNoCell) h = (h + 1) & table_mask_;
    table_[h] = c;
  }
}

NeighborGrid::CellCoord NeighborGrid::coord_of(const Vec3& p) const {
  // Clamp so that queries far outside the data cannot overflow int32.
  auto axis = [&](double v, double o) {
    const double f = std::floor((v - o) * inv_cell_);
    return int32_t(std::clamp(f, -2.0, kMaxCellsPerAxis + 8.0));
  };
  return {axis(p.x, origin_.x), axis(p.y, origin_.y), axis(p.z, origin_.z)};
}

uint32_t NeighborGrid::find_cell(const CellCoord& coord) const {
  if (table_.empty()) return kNoCell;
  uint64_t h = detail::hash_cell(coord) & table_mask_;
  while (true) {
    const uint32_t c = table_[h];
    if (c == kNoCell) return kNoCell;
    if (cell_coords_[c] == coord) return c;
    h = (h + 1) & table_mask_;
  }
}

}  // namespace particlemesh
