#include "surface/orient_outward.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <numeric>
#include <utility>

#include "core/disjoint_sets.h"
#include "core/parallel.h"
#include "mesh/nesting.h"
#include "mesh/orientation.h"

namespace PM_NAMESPACE::detail {

namespace {

/// FlatPieces (orient_outward.h): the closed pieces (roots r with !open[r]) that enclose no
/// volume (vol[r]: six times the signed volume; area[r] their area) opened or removed, and
/// marked open.
void open_flat_pieces(const std::vector<Vec3>& P, std::vector<Triangle>& T, const std::vector<uint32_t>& root,
                      const std::vector<double>& vol, const std::vector<double>& area, std::vector<uint8_t>& open,
                      FlatPieces& flat) {
  const size_t n = P.size();
  // No volume: |6 V| within 1e-9 of (its area)^(3/2), the volume a closed piece of that
  // area has when it is not flat (a regular tetrahedron: 0.0517 A^(3/2) x 6); within
  // rounding of 0 where the plane is tilted, exactly 0 where it is a plane of coordinates.
  std::vector<uint8_t> gone(n, 0);
  for (size_t v = 0; v < n; ++v)
    if (root[v] == v && area[v] > 0 && !open[v] && std::abs(vol[v]) <= 1e-9 * area[v] * std::sqrt(area[v])) {
      gone[v] = 1;
      ++flat.pieces;
    }
  if (flat.pieces == 0) return;
  // Per flat piece (in root order), its triangles; they are few and rare: serial.
  std::vector<std::vector<size_t>> of(n);
  for (size_t i = 0; i < T.size(); ++i)
    if (gone[root[T[i][0]]]) of[root[T[i][0]]].push_back(i);
  std::vector<uint8_t> drop(T.size(), 0);
  for (size_t r = 0; r < n; ++r) {
    if (!gone[r]) continue;
    std::vector<size_t> side;
    if (flat.sides)
      for (size_t i : of[r]) {
        const Triangle& t = T[i];
        const Vec3 f = cross(P[t[1]] - P[t[0]], P[t[2]] - P[t[0]]);
        if (dot(f, (*flat.sides)[t[0]] + (*flat.sides)[t[1]] + (*flat.sides)[t[2]]) > 0) side.push_back(i);
      }
    // The side's outline: its half-edges whose reverse it does not hold; simple loops
    // when no corner starts two of them.
    std::vector<std::pair<uint32_t, uint32_t>> half;
    for (size_t i : side)
      for (int k = 0; k < 3; ++k) half.push_back({T[i][k], T[i][(k + 1) % 3]});
    std::sort(half.begin(), half.end());
    std::vector<std::pair<uint32_t, uint32_t>> outline;
    for (const auto& [a, b] : half)
      if (!std::binary_search(half.begin(), half.end(), std::make_pair(b, a))) outline.push_back({a, b});
    bool simple = !side.empty() && side.size() < of[r].size() && !outline.empty();
    for (size_t k = 1; k < outline.size() && simple; ++k) simple = outline[k].first != outline[k - 1].first;
    if (!simple) {
      ++flat.removed;
      side.clear();
    } else {
      // The loops: each corner starts one outline edge, so following them closes cycles.
      std::vector<uint8_t> walked(outline.size(), 0);
      for (size_t k = 0; k < outline.size(); ++k) {
        if (walked[k]) continue;
        size_t edges = 0;
        for (size_t at = k; !walked[at];) {
          walked[at] = 1;
          ++edges;
          const auto next = std::lower_bound(outline.begin(), outline.end(), std::make_pair(outline[at].second, 0u));
          if (next == outline.end() || next->first != outline[at].second) break;
          at = size_t(next - outline.begin());
        }
        flat.loops.push_back(edges);
      }
    }
    std::sort(side.begin(), side.end());
    for (size_t i : of[r])
      if (!std::binary_search(side.begin(), side.end(), i)) drop[i] = 1;
  }
  std::vector<uint8_t> used(n, 0);
  for (size_t i = 0; i < T.size(); ++i)
    if (!drop[i])
      for (uint32_t v : T[i]) used[v] = 1;
  for (size_t v = 0; v < n; ++v) flat.points += gone[root[v]] && !used[v];
  size_t w = 0;
  for (size_t i = 0; i < T.size(); ++i)
    if (!drop[i]) T[w++] = T[i];
  flat.triangles = T.size() - w;
  T.resize(w);
  // The kept sides are open now: orientation leaves them as they are.
  for (size_t v = 0; v < n; ++v)
    if (gone[v]) open[v] = 1;
}

/// NearlyClosed (orient_outward.h): the open pieces closed but for small openings, each of
/// their loops (v_i -> v_{i+1} boundary half-edges) capped by the fan from its centroid (cap
/// triangles (v_{i+1}, v_i, centroid)); each such piece's cap volume (six times, about the
/// piece's root) added to vol[r] and the piece marked closed. Returns those pieces' roots,
/// ascending.
std::vector<uint32_t> close_nearly_closed_pieces(const std::vector<Vec3>& P,
                                                 const std::vector<std::vector<uint32_t>>& loops,
                                                 const std::vector<uint32_t>& root, const std::vector<double>& area,
                                                 std::vector<double>& vol, std::vector<uint8_t>& open) {
  std::vector<std::pair<uint32_t, std::pair<double, double>>> cap;  // per loop: (root, (area, volume6))
  for (const std::vector<uint32_t>& loop : loops) {
    if (loop.empty()) continue;
    Vec3 centroid{};
    for (const uint32_t v : loop) centroid = centroid + P[v];
    centroid = centroid / double(loop.size());
    const uint32_t r = root[loop[0]];
    double a = 0, v = 0;
    for (size_t i = 0; i < loop.size(); ++i) {
      const Vec3& pa = P[loop[i]];
      const Vec3& pb = P[loop[(i + 1) % loop.size()]];
      a += 0.5 * norm(cross(pa - centroid, pb - centroid));
      v += signed_volume6(P[r], pb, pa, centroid);
    }
    cap.push_back({r, {a, v}});
  }
  std::stable_sort(cap.begin(), cap.end(), [](const auto& x, const auto& y) { return x.first < y.first; });
  std::vector<uint32_t> closed;
  for (size_t i = 0; i < cap.size();) {
    const uint32_t r = cap[i].first;
    double a = 0, v = 0;
    for (; i < cap.size() && cap[i].first == r; ++i) a += cap[i].second.first, v += cap[i].second.second;
    const double closed6 = vol[r] + v;
    if (!open[r] || !(area[r] > 0) || a > kMaxCapShare * area[r] ||
        std::abs(closed6) < 6 * kMinCappedVolume * area[r] * std::sqrt(area[r]))
      continue;
    vol[r] = closed6;
    open[r] = 0;
    closed.push_back(r);
  }
  return closed;
}

}  // namespace

size_t orient_closed_components_outward(const std::vector<Vec3>& P, std::vector<Triangle>& T,
                                        const std::vector<uint64_t>& boundary, std::vector<Vec3>* vertex_normals,
                                        bool turn, FlatPieces* flat, NearlyClosed* nearly) {
  // Components by shared vertices (the same as by shared edges on a manifold without
  // pinches); a component is open if it holds a boundary half-edge. Joined concurrently (a
  // serial pass is a visible cost at millions of triangles): each component's root is its
  // lowest point whatever the threads did.
  const size_t n = P.size();
  ConcurrentDisjointSets sets(n);
  parallel_blocks(T.size(), 8192, [&](size_t b, size_t e) {
    for (size_t i = b; i < e; ++i) {
      sets.unite(T[i][0], T[i][1]);
      sets.unite(T[i][0], T[i][2]);
    }
  });
  std::vector<uint32_t> root(n);
  parallel_blocks(n, 8192, [&](size_t b, size_t e) {
    for (size_t v = b; v < e; ++v) root[v] = sets.find(uint32_t(v));
  });
  std::vector<uint8_t> open(n, 0);
  for (uint64_t e : boundary) open[root[uint32_t(e >> 32)]] = 1;
  // Signed volumes (and areas, for the flat pieces): partial sums per fixed chunk of
  // triangles (in space order, so a chunk meets few components), added up in chunk order:
  // the same sums for any thread count.
  struct Sums {
    uint32_t root;
    double volume6, area;
  };
  const bool capping = nearly && nearly->loops && !nearly->loops->empty() && turn;
  const bool areas = flat || capping;
  const size_t chunk = 16384, chunks = (T.size() + chunk - 1) / chunk;
  std::vector<std::vector<Sums>> part(chunks);
  parallel_blocks(chunks, 1, [&](size_t hb, size_t he) {
    for (size_t h = hb; h < he; ++h)
      for (size_t i = h * chunk; i < std::min(T.size(), (h + 1) * chunk); ++i) {
        const Triangle& t = T[i];
        const uint32_t r = root[t[0]];
        const Vec3 o = P[r];
        const double v = signed_volume6(o, P[t[0]], P[t[1]], P[t[2]]);
        const double a = areas ? 0.5 * norm(cross(P[t[1]] - P[t[0]], P[t[2]] - P[t[0]])) : 0.0;
        auto& pt = part[h];
        auto it = std::find_if(pt.rbegin(), pt.rend(), [r](const Sums& x) { return x.root == r; });
        if (it != pt.rend()) {
          it->volume6 += v;
          it->area += a;
        } else {
          pt.push_back({r, v, a});
        }
      }
  });
  std::vector<double> vol(n, 0.0), area(areas ? n : 0, 0.0);
  for (const auto& pt : part)
    for (const Sums& x : pt) {
      vol[x.root] += x.volume6;
      if (areas) area[x.root] += x.area;
    }
  if (flat) open_flat_pieces(P, T, root, vol, area, open, *flat);
  if (!turn) return 0;
  std::vector<uint32_t> capped;
  if (capping) {
    capped = close_nearly_closed_pieces(P, *nearly->loops, root, area, vol, open);
    nearly->pieces = capped.size();
  }
  // A closed component inside another faces into the cavity it bounds, one inside that
  // outward again (nesting.h): its depth decides. Pieces (the roots of triangles) numbered in
  // root order.
  std::vector<uint8_t> has_triangle(n, 0);
  for (const Triangle& t : T) has_triangle[root[t[0]]] = 1;
  std::vector<uint32_t> piece(n, UINT32_MAX);
  std::vector<uint8_t> closed;
  for (size_t v = 0; v < n; ++v)
    if (has_triangle[v]) {
      piece[v] = uint32_t(closed.size());
      closed.push_back(!open[v] && !std::binary_search(capped.begin(), capped.end(), uint32_t(v)));
    }
  const size_t pieces = closed.size();
  std::vector<uint32_t> piece_of(T.size());
  parallel_blocks(T.size(), 8192, [&](size_t b, size_t e) {
    for (size_t i = b; i < e; ++i) piece_of[i] = piece[root[T[i][0]]];
  });
  // Pieces judged with their openings capped are neither nested nor nesting: they face away
  // from the solid they nearly close (depth 0). Capped, a model's head would hold the small
  // closed pieces on its surface (a thin lip's two sides) and turn them into a cavity.
  const std::vector<uint32_t> depth = nesting_depths(P, T, piece_of.data(), pieces, closed);
  // Closed, enclosing some volume, and facing into its solid: turned (0 volume: left as it is).
  auto turned = [&](uint32_t r) {
    return !open[r] && vol[r] != 0 && !faces_away_from_its_solid(vol[r], depth[piece[r]]);
  };
  parallel_blocks(T.size(), 8192, [&](size_t b, size_t e) {
    for (size_t i = b; i < e; ++i)
      if (turned(root[T[i][0]])) std::swap(T[i][1], T[i][2]);
  });
  std::atomic<size_t> flipped{0};
  parallel_blocks(n, 8192, [&](size_t b, size_t e) {
    size_t count = 0;
    for (size_t v = b; v < e; ++v) {
      const uint32_t r = root[v];
      if (!turned(r)) continue;
      count += r == v;
      // Reversing a triangle negates its normal exactly (the cross product's terms swap), so
      // the vertex normals of a turned component are the negated ones, to the bit (0 - x, as
      // a sum of negated terms gives +0 where they cancel).
      if (vertex_normals) (*vertex_normals)[v] = Vec3{} - (*vertex_normals)[v];
    }
    flipped.fetch_add(count, std::memory_order_relaxed);
  });
  for (const uint32_t r : capped) nearly->turned += turned(r);
  return flipped.load();
}

}  // namespace particlemesh::detail
