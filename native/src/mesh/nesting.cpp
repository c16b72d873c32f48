#include "mesh/nesting.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "core/parallel.h"

namespace PM_NAMESPACE::detail {

namespace {

struct Box {
  static constexpr double kInf = std::numeric_limits<double>::infinity();
  Vec3 lo{kInf, kInf, kInf};
  Vec3 hi{-kInf, -kInf, -kInf};
  void add(const Vec3& p) {
    lo = {std::min(lo.x, p.x), std::min(lo.y, p.y), std::min(lo.z, p.z)};
    hi = {std::max(hi.x, p.x), std::max(hi.y, p.y), std::max(hi.z, p.z)};
  }
  bool holds(const Vec3& p) const {
    return p.x >= lo.x && p.x <= hi.x && p.y >= lo.y && p.y <= hi.y && p.z >= lo.z && p.z <= hi.z;
  }
};

/// Whether the ray from q straight up (+z) meets a closed surface an odd number of times:
/// q is inside it. Watertight (Woop, Benthin and Wald, "Watertight ray/triangle
/// intersection", 2013, in spirit): each edge's side test is evaluated once per edge, from its
/// lower-numbered end, so the two triangles that share an edge see the same number with
/// opposite signs; a point exactly on an edge's line is moved off it symbolically (by
/// (eps, eps^2): Edelsbrunner and Muecke's simulation of simplicity), so it lies in exactly one
/// of the two. Every crossing is counted once, also through edges and vertices.
class ParityTest {
 public:
  ParityTest(const std::vector<Vec3>& P, const std::vector<Triangle>& T, const uint32_t* tris, size_t count)
      : P_(P), T_(T) {
    for (size_t i = 0; i < count; ++i)
      for (int k = 0; k < 3; ++k) {
        const Vec3& p = P[T[tris[i]][k]];
        lo_[0] = std::min(lo_[0], p.x), lo_[1] = std::min(lo_[1], p.y);
        hi_[0] = std::max(hi_[0], p.x), hi_[1] = std::max(hi_[1], p.y);
      }
    // A grid over the xy box, about 64 triangles' boxes per cell: its counts stay in the
    // cache while the triangles are bucketed (4 per cell took twice as long for 1000 queries:
    // bench/nesting_bench.py), and a query's 64 side tests are a microsecond.
    side_ = std::clamp<size_t>(size_t(std::sqrt(double(count) / 64.0)), 1, 1024);
    for (int a = 0; a < 2; ++a) scale_[a] = hi_[a] > lo_[a] ? double(side_) / (hi_[a] - lo_[a]) : 0.0;
    start_.assign(side_ * side_ + 1, 0);
    for (int pass = 0; pass < 2; ++pass) {
      std::vector<size_t> at;
      if (pass == 1) {
        for (size_t c = 0; c < side_ * side_; ++c) start_[c + 1] += start_[c];
        at.assign(start_.begin(), start_.end() - 1);
        cells_.resize(start_.back());
      }
      for (size_t i = 0; i < count; ++i) {
        const Triangle& t = T[tris[i]];
        size_t c0[2], c1[2];
        for (int a = 0; a < 2; ++a) {
          const double u = std::min({P[t[0]][a], P[t[1]][a], P[t[2]][a]});
          const double v = std::max({P[t[0]][a], P[t[1]][a], P[t[2]][a]});
          c0[a] = cell(u, a), c1[a] = cell(v, a);
        }
        for (size_t y = c0[1]; y <= c1[1]; ++y)
          for (size_t x = c0[0]; x <= c1[0]; ++x) {
            if (pass == 0) ++start_[y * side_ + x + 1];
            else cells_[at[y * side_ + x]++] = tris[i];
          }
      }
    }
  }

  bool inside(const Vec3& q) const {
    if (!(q.x >= lo_[0] && q.x <= hi_[0] && q.y >= lo_[1] && q.y <= hi_[1])) return false;
    const size_t c = cell(q.y, 1) * side_ + cell(q.x, 0);
    bool odd = false;
    for (size_t i = start_[c]; i < start_[c + 1]; ++i) {
      const Triangle& t = T_[cells_[i]];
      double e[3];
      int sign = 0;
      bool covered = true;
      for (int k = 0; k < 3 && covered; ++k) {
        const uint32_t u = t[(k + 1) % 3], v = t[(k + 2) % 3];  // the edge opposite corner k
        e[k] = u < v ? side(P_[u], P_[v], q) : -side(P_[v], P_[u], q);
        const int s = e[k] > 0 ? 1 : -1;
        if (sign == 0) sign = s;
        covered = s == sign;
      }
      if (!covered) continue;
      // The triangle's height above q's xy, from the edge values (barycentric weights).
      const double sum = e[0] + e[1] + e[2];
      if (sum == 0) continue;  // seen edge-on: no crossing (its neighbours count it)
      const double z = (e[0] * P_[t[0]].z + e[1] * P_[t[1]].z + e[2] * P_[t[2]].z) / sum;
      if (z > q.z) odd = !odd;
    }
    return odd;
  }

 private:
  size_t cell(double v, int a) const {
    const double c = (v - lo_[a]) * scale_[a];
    return c > 0 ? size_t(std::min(c, double(side_ - 1))) : 0;  // (NaN: 0)
  }
  /// Which side of the line a -> b (a the lower-numbered end) q lies on in xy, never 0: on
  /// the line, q moved by (eps, eps^2) decides.
  static double side(const Vec3& a, const Vec3& b, const Vec3& q) {
    const double dx = b.x - a.x, dy = b.y - a.y;
    const double s = dx * (q.y - a.y) - dy * (q.x - a.x);
    if (s != 0) return s;
    if (dy != 0) return -dy;
    return dx != 0 ? dx : 1.0;  // a point edge (coincident ends): any fixed side
  }

  const std::vector<Vec3>& P_;
  const std::vector<Triangle>& T_;
  double lo_[2] = {std::numeric_limits<double>::infinity(), std::numeric_limits<double>::infinity()};
  double hi_[2] = {-std::numeric_limits<double>::infinity(), -std::numeric_limits<double>::infinity()};
  double scale_[2] = {0, 0};
  size_t side_ = 1;
  std::vector<size_t> start_;
  std::vector<uint32_t> cells_;
};

}  // namespace

std::vector<uint32_t> nesting_depths(const std::vector<Vec3>& P, const std::vector<Triangle>& T,
                                     const uint32_t* component_of, size_t components,
                                     const std::vector<uint8_t>& closed) {
  std::vector<uint32_t> depth(components, 0);
  size_t closed_count = 0;
  for (size_t c = 0; c < components; ++c) closed_count += closed[c] != 0;
  if (closed_count < 2) return depth;
  std::vector<Box> box(components);
  for (size_t f = 0; f < T.size(); ++f)
    if (const uint32_t c = component_of[f]; closed[c])
      for (int k = 0; k < 3; ++k) box[c].add(P[T[f][k]]);
  // The pairs (inner c, outer d) whose boxes nest: closed pieces by their box's low x, and
  // for each d those whose low x lies within d's box.
  std::vector<uint32_t> order;
  order.reserve(closed_count);
  for (size_t c = 0; c < components; ++c)
    if (closed[c] && box[c].lo.x <= box[c].hi.x) order.push_back(uint32_t(c));  // (one with triangles)
  std::sort(order.begin(), order.end(), [&](uint32_t a, uint32_t b) {
    return box[a].lo.x != box[b].lo.x ? box[a].lo.x < box[b].lo.x : a < b;
  });
  std::vector<std::pair<uint32_t, uint32_t>> pairs;
  for (uint32_t d : order) {
    auto it = std::lower_bound(order.begin(), order.end(), box[d].lo.x,
                               [&](uint32_t c, double x) { return box[c].lo.x < x; });
    for (; it != order.end() && box[*it].lo.x <= box[d].hi.x; ++it) {
      const uint32_t c = *it;
      if (c == d) continue;
      if (box[d].holds(box[c].lo) && box[d].holds(box[c].hi)) pairs.push_back({c, d});
    }
  }
  if (pairs.empty()) return depth;
  // Each piece's triangles (counting sort by piece, in triangle order).
  std::vector<size_t> start(components + 1, 0);
  for (size_t f = 0; f < T.size(); ++f) ++start[component_of[f] + 1];
  for (size_t c = 0; c < components; ++c) start[c + 1] += start[c];
  std::vector<uint32_t> of(T.size());
  {
    std::vector<size_t> at(start.begin(), start.end() - 1);
    for (size_t f = 0; f < T.size(); ++f) of[at[component_of[f]]++] = uint32_t(f);
  }
  // Pairs by their outer piece; each outer piece's test built once, its points tested.
  std::sort(pairs.begin(), pairs.end(), [](const auto& a, const auto& b) {
    return a.second != b.second ? a.second < b.second : a.first < b.first;
  });
  std::vector<size_t> group{0};
  for (size_t i = 1; i < pairs.size(); ++i)
    if (pairs[i].second != pairs[i - 1].second) group.push_back(i);
  group.push_back(pairs.size());
  std::vector<uint8_t> inside(pairs.size(), 0);
  parallel_blocks(group.size() - 1, 1, [&](size_t b, size_t e) {
    for (size_t g = b; g < e; ++g) {
      const uint32_t d = pairs[group[g]].second;
      const ParityTest test(P, T, of.data() + start[d], start[d + 1] - start[d]);
      for (size_t i = group[g]; i < group[g + 1]; ++i) inside[i] = test.inside(P[T[of[start[pairs[i].first]]][0]]);
    }
  });
  for (size_t i = 0; i < pairs.size(); ++i) depth[pairs[i].first] += inside[i];
  return depth;
}

}  // namespace particlemesh::detail
