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
  // Signed volumes: partial sums per fixed chunk of triangles (in space order, so a chunk
  // meets few components), added up in chunk order: the same sums for any thread count.
  const size_t chunk = 16384, chunks = (T.size() + chunk - 1) / chunk;
  std::vector<std::vector<std::pair<uint32_t, double>>> part(chunks);
  parallel_blocks(chunks, 1, [&](size_t hb, size_t he) {
    for (size_t h = hb; h < he; ++h)
      for (size_t i = h * chunk; i < std::min(T.size(), (h + 1) * chunk); ++i) {
        const Triangle& t = T[i];
        const uint32_t r = root[t[0]];
        const Vec3 o = P[r];
        const double v = signed_volume6(o, P[t[0]], P[t[1]], P[t[2]]);
        auto& pt = part[h];
        auto it = std::find_if(pt.rbegin(), pt.rend(), [r](const auto& x) { return x.first == r; });
        if (it != pt.rend()) it->second += v;
        else pt.push_back({r, v});
      }
  });
  std::vector<double> vol(n, 0.0);
  for (const auto& pt : part)
    for (const auto& [r, v] : pt) vol[r] += v;
  if (flat) {
    // No volume: |6 V| within 1e-9 of (its area)^(3/2), the volume a closed piece of that
    // area has when it is not flat (a regular tetrahedron: 0.0517 A^(3/2) x 6); within
    // rounding of 0 where the plane is tilted, exactly 0 where it is a plane of coordinates.
    std::vector<double> area(n, 0.0);
    for (const Triangle& t : T) area[root[t[0]]] += 0.5 * norm(cross(P[t[1]] - P[t[0]], P[t[2]] - P[t[0]]));
    std::vector<uint8_t> gone(n, 0);
    for (size_t v = 0; v < n; ++v)
      if (root[v] == v && area[v] > 0 && !open[v] && std::abs(vol[v]) <= 1e-9 * area[v] * std::sqrt(area[v])) {
        gone[v] = 1;
        ++flat->pieces;
      }
    if (flat->pieces > 0) {
      for (size_t v = 0; v < n; ++v) flat->points += gone[root[v]];
      const size_t before = T.size();
      T.erase(std::remove_if(T.begin(), T.end(), [&](const Triangle& t) { return gone[root[t[0]]] != 0; }), T.end());
      flat->triangles = before - T.size();
    }
  }
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
