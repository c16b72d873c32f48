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

}  // namespace

size_t orient_closed_components_outward(const std::vector<Vec3>& P, std::vector<Triangle>& T,
                                        const std::vector<uint64_t>& boundary, std::vector<Vec3>* vertex_normals,
                                        bool turn, FlatPieces* flat) {
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
  const size_t chunk = 16384, chunks = (T.size() + chunk - 1) / chunk;
  std::vector<std::vector<Sums>> part(chunks);
  parallel_blocks(chunks, 1, [&](size_t hb, size_t he) {
    for (size_t h = hb; h < he; ++h)
      for (size_t i = h * chunk; i < std::min(T.size(), (h + 1) * chunk); ++i) {
        const Triangle& t = T[i];
        const uint32_t r = root[t[0]];
        const Vec3 o = P[r];
        const double v = signed_volume6(o, P[t[0]], P[t[1]], P[t[2]]);
        const double a = flat ? 0.5 * norm(cross(P[t[1]] - P[t[0]], P[t[2]] - P[t[0]])) : 0.0;
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
  std::vector<double> vol(n, 0.0), area(flat ? n : 0, 0.0);
  for (const auto& pt : part)
    for (const Sums& x : pt) {
      vol[x.root] += x.volume6;
      if (flat) area[x.root] += x.area;
    }
  if (flat) open_flat_pieces(P, T, root, vol, area, open, *flat);
  if (!turn) return 0;
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
      closed.push_back(!open[v]);
    }
  const size_t pieces = closed.size();
  std::vector<uint32_t> piece_of(T.size());
  parallel_blocks(T.size(), 8192, [&](size_t b, size_t e) {
    for (size_t i = b; i < e; ++i) piece_of[i] = piece[root[T[i][0]]];
  });
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
  return flipped.load();
}

}  // namespace particlemesh::detail
