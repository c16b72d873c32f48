#include "mesh/nesting.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "core/parallel.h"
#include "mesh/ray_crossings_impl.h"

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
      const RayCrossings test(P, T, of.data() + start[d], start[d + 1] - start[d]);
      parallel_blocks(group[g + 1] - group[g], 64, [&](size_t b, size_t e) {
        for (size_t i = group[g] + b; i < group[g] + e; ++i) inside[i] = test.count(P[T[of[start[pairs[i].first]]][0]]) % 2;
      });
    }
  });
  for (size_t i = 0; i < pairs.size(); ++i) depth[pairs[i].first] += inside[i];
  return depth;
}

}  // namespace particlemesh::detail
