#include "particlemesh/mesh/ray_crossings.h"

#include <algorithm>
#include <array>
#include <atomic>
#include <limits>
#include <cmath>
#include <numeric>
#include <string>

#include <tbb/combinable.h>

#include "core/parallel.h"
#include "mesh/ray_crossings_impl.h"
#include "particlemesh/core/error.h"

namespace PM_NAMESPACE {

namespace detail {

namespace {

/// Which side of the line a -> b (a the lower-numbered end) q lies on in xy, never 0: on the
/// line, q moved by (eps, eps^2) decides.
double side(const Vec3& a, const Vec3& b, const Vec3& q) {
  const double dx = b.x - a.x, dy = b.y - a.y;
  const double s = dx * (q.y - a.y) - dy * (q.x - a.x);
  if (s != 0) return s;
  if (dy != 0) return -dy;
  return dx != 0 ? dx : 1.0;  // a point edge (coincident ends): any fixed side
}

}  // namespace

RayCrossings::RayCrossings(const std::vector<Vec3>& P, const std::vector<Triangle>& T, const uint32_t* tris,
                           size_t count)
    : P_(P), T_(T) {
  // In parallel (the caller's arena): the box's min and max, and the bucketing's counts and
  // slots, do not depend on the order the triangles are seen in; a cell's triangles may come
  // in any order, and a query only sums over them.
  constexpr size_t kGrain = 8192;
  tbb::combinable<std::array<double, 4>> box([] {
    const double inf = std::numeric_limits<double>::infinity();
    return std::array<double, 4>{inf, inf, -inf, -inf};
  });
  parallel_blocks(count, kGrain, [&](size_t b, size_t e) {
    std::array<double, 4>& m = box.local();
    for (size_t i = b; i < e; ++i)
      for (int k = 0; k < 3; ++k) {
        const Vec3& p = P[T[tris[i]][k]];
        m[0] = std::min(m[0], p.x), m[1] = std::min(m[1], p.y);
        m[2] = std::max(m[2], p.x), m[3] = std::max(m[3], p.y);
      }
  });
  box.combine_each([&](const std::array<double, 4>& m) {
    lo_[0] = std::min(lo_[0], m[0]), lo_[1] = std::min(lo_[1], m[1]);
    hi_[0] = std::max(hi_[0], m[2]), hi_[1] = std::max(hi_[1], m[3]);
  });
  // A grid over the xy box, about 64 triangles' boxes per cell: its counts stay in the
  // cache while the triangles are bucketed (4 per cell took twice as long for 1000 queries:
  // bench/nesting_bench.py), and a query's 64 side tests are a microsecond.
  side_ = std::clamp<size_t>(size_t(std::sqrt(double(count) / 64.0)), 1, 1024);
  for (int a = 0; a < 2; ++a) scale_[a] = hi_[a] > lo_[a] ? double(side_) / (hi_[a] - lo_[a]) : 0.0;
  start_.assign(side_ * side_ + 1, 0);
  std::vector<size_t> at;
  for (int pass = 0; pass < 2; ++pass) {
    if (pass == 1) {
      for (size_t c = 0; c < side_ * side_; ++c) start_[c + 1] += start_[c];
      at.assign(start_.begin(), start_.end() - 1);
      cells_.resize(start_.back());
    }
    parallel_blocks(count, kGrain, [&](size_t b, size_t e) {
      for (size_t i = b; i < e; ++i) {
        const Triangle& t = T[tris[i]];
        size_t c0[2], c1[2];
        for (int a = 0; a < 2; ++a) {
          const double u = std::min({P[t[0]][a], P[t[1]][a], P[t[2]][a]});
          const double v = std::max({P[t[0]][a], P[t[1]][a], P[t[2]][a]});
          c0[a] = cell(u, a), c1[a] = cell(v, a);
        }
        for (size_t y = c0[1]; y <= c1[1]; ++y)
          for (size_t x = c0[0]; x <= c1[0]; ++x) {
            const size_t c = y * side_ + x;
            if (pass == 0) std::atomic_ref<size_t>(start_[c + 1]).fetch_add(1, std::memory_order_relaxed);
            else cells_[std::atomic_ref<size_t>(at[c]).fetch_add(1, std::memory_order_relaxed)] = tris[i];
          }
      }
    });
  }
}

bool ray_crosses(const std::vector<Vec3>& P, const Triangle& t, const Vec3& q) {
  if (t[0] == t[1] || t[1] == t[2] || t[0] == t[2]) return false;  // a segment or a point: no area
  double e[3];
  int sign = 0;
  for (int k = 0; k < 3; ++k) {
    const uint32_t u = t[(k + 1) % 3], v = t[(k + 2) % 3];  // the edge opposite corner k
    e[k] = u < v ? side(P[u], P[v], q) : -side(P[v], P[u], q);
    const int s = e[k] > 0 ? 1 : -1;
    if (sign == 0) sign = s;
    if (s != sign) return false;
  }
  // The triangle's height above q's xy, from the edge values (barycentric weights).
  const double sum = e[0] + e[1] + e[2];
  if (sum == 0) return false;  // seen edge-on: no crossing (its neighbours count it)
  const double z = (e[0] * P[t[0]].z + e[1] * P[t[1]].z + e[2] * P[t[2]].z) / sum;
  return z > q.z;
}

size_t RayCrossings::cell(double v, int a) const {
  const double c = (v - lo_[a]) * scale_[a];
  return c > 0 ? size_t(std::min(c, double(side_ - 1))) : 0;  // (NaN: 0)
}

}  // namespace detail

std::vector<uint64_t> ray_crossings(const TriMesh& mesh, const std::vector<Vec3>& points, int threads) {
  const size_t n = mesh.positions.size();
  if (mesh.triangles.size() >= (size_t(1) << 32)) throw Error(Status::LimitExceeded, "more than 2^32 - 1 triangles");
  for (size_t f = 0; f < mesh.triangles.size(); ++f)
    for (int k = 0; k < 3; ++k)
      if (mesh.triangles[f][k] >= n)
        throw Error(Status::InvalidArgument, "triangle " + std::to_string(f) + " has vertex index " +
                                                 std::to_string(mesh.triangles[f][k]) + ", beyond the " +
                                                 std::to_string(n) + " vertices");
  for (size_t i = 0; i < n; ++i)
    if (!is_finite(mesh.positions[i]))
      throw Error(Status::InvalidInput, "vertex " + std::to_string(i) + " is not finite");
  for (size_t i = 0; i < points.size(); ++i)
    if (!is_finite(points[i])) throw Error(Status::InvalidInput, "point " + std::to_string(i) + " is not finite");
  std::vector<uint64_t> out(points.size(), 0);
  if (mesh.triangles.empty() || points.empty()) return out;
  std::vector<uint32_t> all(mesh.triangles.size());
  std::iota(all.begin(), all.end(), 0u);
  detail::with_threads(threads, [&] {
    const detail::RayCrossings test(mesh.positions, mesh.triangles, all.data(), all.size());
    detail::parallel_blocks(points.size(), 256, [&](size_t b, size_t e) {
      for (size_t i = b; i < e; ++i) out[i] = test.count(points[i]);
    });
  });
  return out;
}

}  // namespace particlemesh
