// Greedy Poisson-disk thinning over a hash of the kept points' cells.
//
// Written here because no library on the list does it on our data: PCL's VoxelGrid and
// UniformSampling keep one point per cell, and two kept points in neighbouring cells can be
// arbitrarily close, which the triangulation's test turns into slivers and holes.
#include "particlemesh/sample/thin.h"

#include <array>
#include <cmath>
#include <string>

#include "core/format_number.h"
#include "core/hashing.h"
#include "particlemesh/core/error.h"

namespace PM_NAMESPACE {

namespace {

// Cells of edge 4 d (d = min_distance) holding the kept points as linked lists. The points
// closer than d to p lie in the cells that the box p +- d touches: 1 or 2 along each axis,
// 3.4 lookups on average (cells of 2 d always need 8, and are slower). Only kept
// points are stored, so the table stays small and no pass sorts all the points.
class KeptCells {
 public:
  using Coord = std::array<int32_t, 3>;
  static constexpr uint32_t kEnd = 0xffffffffu;

  KeptCells() { rehash(1024); }

  uint32_t head(const Coord& c) const {
    const uint64_t key = pack(c);
    for (uint64_t h = mix(key) & mask_;; h = (h + 1) & mask_) {
      const Slot& s = slots_[h];
      if (s.head == kEnd) return kEnd;
      if (s.key == key) return s.head;
    }
  }
  // Kept point k (in the order kept): its position, and the next kept point of its cell.
  const Vec3& position(uint32_t k) const { return nodes_[k].p; }
  uint32_t next(uint32_t k) const { return nodes_[k].next; }

  void add(const Coord& c, const Vec3& p) {
    const uint32_t i = uint32_t(nodes_.size());
    nodes_.push_back({p, kEnd});
    if (2 * (used_ + 1) > slots_.size()) rehash(2 * slots_.size());
    const uint64_t key = pack(c);
    for (uint64_t h = mix(key) & mask_;; h = (h + 1) & mask_) {
      Slot& s = slots_[h];
      if (s.head == kEnd) {
        s = {key, i};
        ++used_;
        return;
      }
      if (s.key == key) {
        nodes_[i].next = s.head;
        s.head = i;
        return;
      }
    }
  }

 private:
  struct Slot {
    uint64_t key = 0;  // the coordinate packed, 21 bits each: one comparison
    uint32_t head = kEnd;
  };
  static uint64_t pack(const Coord& c) {
    return (uint64_t(uint32_t(c[0])) << 42) | (uint64_t(uint32_t(c[1])) << 21) | uint64_t(uint32_t(c[2]));
  }
  static uint64_t mix(uint64_t h) { return detail::mix64(h); }

  void rehash(size_t size) {
    std::vector<Slot> old(size);
    old.swap(slots_);
    mask_ = size - 1;
    used_ = 0;
    for (const Slot& s : old)
      if (s.head != kEnd)
        for (uint64_t h = mix(s.key) & mask_;; h = (h + 1) & mask_)
          if (slots_[h].head == kEnd) {
            slots_[h] = s;
            ++used_;
            break;
          }
  }

  struct Node {
    Vec3 p;  // a copy: the kept points packed together, not spread over the input
    uint32_t next;
  };
  std::vector<Slot> slots_;
  std::vector<Node> nodes_;
  uint64_t mask_ = 0;
  size_t used_ = 0;
};

}  // namespace

namespace {

/// thin_points with point i's distance distance_of(i), at most max_distance.
template <class DistanceOf>
std::vector<uint32_t> thin_greedily(const Vec3* points, size_t n, double max_distance, DistanceOf&& distance_of) {
  if (points == nullptr && n > 0) throw Error(Status::InvalidArgument, "points is NULL");
  if (n > size_t(UINT32_MAX) - 1) throw Error(Status::LimitExceeded, "more than 2^32 - 2 points");
  std::vector<uint32_t> kept;
  if (n == 0) return kept;
  Vec3 lo = points[0], hi = points[0];
  for (size_t i = 0; i < n; ++i) {
    const Vec3& p = points[i];
    if (!is_finite(p))
      throw Error(Status::InvalidInput, "point " + std::to_string(i) + " has a non-finite coordinate");
    lo = {std::min(lo.x, p.x), std::min(lo.y, p.y), std::min(lo.z, p.z)};
    hi = {std::max(hi.x, p.x), std::max(hi.y, p.y), std::max(hi.z, p.z)};
  }
  const double cell = 4 * max_distance, inv = 1.0 / cell;
  constexpr double kMaxCells = double((1 << 21) - 4);  // packed in 21 bits with the margins
  for (int a = 0; a < 3; ++a)
    if (!((hi[a] - lo[a]) * inv < kMaxCells))
      throw Error(Status::LimitExceeded, "the points span " + detail::format_number((hi[a] - lo[a]) * inv) +
                                             " cells of size " + detail::format_number(cell) + " along " +
                                             std::string(1, "xyz"[a]) +
                                             " (at most 2097148): the thinning distance is far too small");
  // One cell of margin below the data, so that p - d never has a negative cell coordinate.
  const Vec3 origin = lo - Vec3{cell, cell, cell};
  // Truncation is floor here: every coordinate asked for is at least a distance above origin.
  const auto axis = [&](double v, int a) { return int32_t((v - origin[a]) * inv); };

  KeptCells cells;
  for (uint32_t i = 0; i < uint32_t(n); ++i) {
    const Vec3& p = points[i];
    const double d = distance_of(i), r2 = d * d;
    KeptCells::Coord from, to;
    for (int a = 0; a < 3; ++a) {
      from[a] = axis(p[a] - d, a);
      to[a] = axis(p[a] + d, a);
    }
    bool free = true;
    for (int32_t x = from[0]; free && x <= to[0]; ++x)
      for (int32_t y = from[1]; free && y <= to[1]; ++y)
        for (int32_t z = from[2]; free && z <= to[2]; ++z)
          for (uint32_t k = cells.head({x, y, z}); k != KeptCells::kEnd; k = cells.next(k))
            if (squared_distance(cells.position(k), p) < r2) {
              free = false;
              break;
            }
    if (!free) continue;
    cells.add({axis(p.x, 0), axis(p.y, 1), axis(p.z, 2)}, p);
    kept.push_back(i);
  }
  return kept;
}

}  // namespace

std::vector<uint32_t> thin_points(const Vec3* points, size_t n, double min_distance) {
  if (!(min_distance > 0) || !std::isfinite(min_distance))
    throw Error(Status::InvalidArgument,
                "min_distance must be a positive finite distance, got " + detail::format_number(min_distance));
  return thin_greedily(points, n, min_distance, [&](uint32_t) { return min_distance; });
}

std::vector<uint32_t> thin_points(const Vec3* points, size_t n, const std::vector<double>& min_distance) {
  if (min_distance.size() != n)
    throw Error(Status::InvalidArgument, "one thinning distance per point is needed, got " +
                                             std::to_string(min_distance.size()) + " for " + std::to_string(n));
  double largest = 0;
  for (size_t i = 0; i < n; ++i) {
    if (!(min_distance[i] > 0) || !std::isfinite(min_distance[i]))
      throw Error(Status::InvalidArgument, "min_distance[" + std::to_string(i) +
                                               "] must be a positive finite distance, got " +
                                               detail::format_number(min_distance[i]));
    largest = std::max(largest, min_distance[i]);
  }
  return thin_greedily(points, n, largest, [&](uint32_t i) { return min_distance[i]; });
}

PointCloud thin_cloud(const PointCloud& cloud, double min_distance) {
  return select_points(cloud, thin_points(cloud.positions.data(), cloud.size(), min_distance));
}

PointCloud thin_cloud(const PointCloud& cloud, const std::vector<double>& min_distance) {
  return select_points(cloud, thin_points(cloud.positions.data(), cloud.size(), min_distance));
}

}  // namespace particlemesh
