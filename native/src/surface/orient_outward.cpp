#include "surface/orient_outward.h"

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <numeric>
#include <utility>

#include "core/disjoint_sets.h"
#include "core/parallel.h"
#include "mesh/nesting.h"
#include "mesh/orientation.h"
#include "mesh/ray_crossings_impl.h"

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

/// A loop's cap (v_i -> v_{i+1} boundary half-edges): the fan from its centroid, triangles
/// (v_{i+1}, v_i, centroid), and its area. A loop of fewer than three points caps nothing.
struct Cap {
  Vec3 centroid;
  double area = 0;
};
std::vector<Cap> caps_of(const std::vector<Vec3>& P, const std::vector<std::vector<uint32_t>>& loops) {
  std::vector<Cap> caps(loops.size());
  for (size_t k = 0; k < loops.size(); ++k) {
    const std::vector<uint32_t>& loop = loops[k];
    if (loop.size() < 3) continue;
    Vec3 centroid{};
    for (const uint32_t v : loop) centroid = centroid + P[v];
    caps[k].centroid = centroid / double(loop.size());
    for (size_t i = 0; i < loop.size(); ++i)
      caps[k].area += 0.5 * norm(cross(P[loop[i]] - caps[k].centroid, P[loop[(i + 1) % loop.size()]] - caps[k].centroid));
  }
  return caps;
}

/// NearlyClosed (orient_outward.h): the open pieces closed but for small openings, each of
/// their loops capped (`caps`); each such piece's cap volume (six times, about the piece's
/// root) added to vol[r] and the piece marked closed. Returns those pieces' roots, ascending.
std::vector<uint32_t> close_nearly_closed_pieces(const std::vector<Vec3>& P,
                                                 const std::vector<std::vector<uint32_t>>& loops,
                                                 const std::vector<Cap>& caps, const std::vector<uint32_t>& root,
                                                 const std::vector<double>& area, std::vector<double>& vol,
                                                 std::vector<uint8_t>& open) {
  std::vector<std::pair<uint32_t, std::pair<double, double>>> cap;  // per loop: (root, (area, volume6))
  for (size_t k = 0; k < loops.size(); ++k) {
    const std::vector<uint32_t>& loop = loops[k];
    if (loop.size() < 3) continue;
    const uint32_t r = root[loop[0]];
    double v = 0;
    for (size_t i = 0; i < loop.size(); ++i)
      v += signed_volume6(P[r], P[loop[(i + 1) % loop.size()]], P[loop[i]], caps[k].centroid);
    cap.push_back({r, {caps[k].area, v}});
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

/// Folds (orient_outward.h): which triangles face into the solid their piece bounds, for the
/// pieces `judge` marks (numbered: piece[root[v]] for a vertex v, piece_of[i] for triangle i).
/// Each piece's own triangles and its loops' caps are the closed surface its rays cross:
/// other pieces (one inside another, or side by side) do not count.
void judge_folds(const std::vector<Vec3>& P, const std::vector<Triangle>& T, const std::vector<uint32_t>& root,
                 const std::vector<uint32_t>& piece, const std::vector<uint32_t>& piece_of,
                 const std::vector<uint8_t>& judge, const std::vector<std::vector<uint32_t>>& loops,
                 const std::vector<Cap>& caps, Folds& folds) {
  // The caps' fans as triangles over the loops' points and the centroids.
  std::vector<Vec3> cap_points;
  std::vector<Triangle> fans;
  std::vector<uint32_t> fan_piece;
  for (size_t k = 0; k < loops.size(); ++k) {
    const std::vector<uint32_t>& loop = loops[k];
    if (loop.size() < 3 || !judge[piece[root[loop[0]]]]) continue;
    const auto first = uint32_t(cap_points.size()), m = uint32_t(loop.size());
    for (const uint32_t v : loop) cap_points.push_back(P[v]);
    cap_points.push_back(caps[k].centroid);
    for (uint32_t i = 0; i < m; ++i) {
      fans.push_back({first + (i + 1) % m, first + i, first + m});
      fan_piece.push_back(piece[root[loop[0]]]);
    }
  }
  // The point just off a triangle's centre along its normal, by a thousandth of its longest
  // edge: nearer than any other sheet but a fold's (false: no area); its area.
  auto probe = [&](size_t i, Vec3& q, double& area) {
    const Triangle& t = T[i];
    const Vec3 a = P[t[0]], u = P[t[1]] - a, v = P[t[2]] - a;
    const Vec3 normal = cross(u, v);
    const double length = norm(normal);
    area = 0.5 * length;
    if (!(length > 0)) return false;
    const double reach = 1e-3 * std::sqrt(std::max({squared_norm(u), squared_norm(v), squared_norm(v - u)}));
    q = a + (u + v) / 3.0 + normal * (reach / length);
    return true;
  };
  if (folds.samples > 0) {
    // Every k-th triangle of the pieces judged first. Their few rays are crossed against
    // every triangle in one pass, each triangle meeting those in the cells of a grid over the
    // rays that its xy box covers: cheaper than bucketing every triangle for them.
    const size_t stride = std::max<size_t>(1, T.size() / folds.samples);
    std::vector<uint32_t> picked;
    std::vector<Vec3> q;
    std::vector<double> area;
    for (size_t i = 0; i < T.size(); i += stride) {
      Vec3 point;
      double a;
      if (!judge[piece_of[i]] || !probe(i, point, a)) continue;
      picked.push_back(uint32_t(i));
      q.push_back(point);
      area.push_back(a);
    }
    // The rays bucketed in a grid over their xy box, about one per cell.
    double lo[2] = {INFINITY, INFINITY}, hi[2] = {-INFINITY, -INFINITY};
    for (const Vec3& point : q)
      for (int a = 0; a < 2; ++a) lo[a] = std::min(lo[a], point[a]), hi[a] = std::max(hi[a], point[a]);
    const size_t side = std::max<size_t>(1, size_t(std::sqrt(double(q.size()))));
    double scale[2];
    for (int a = 0; a < 2; ++a) scale[a] = hi[a] > lo[a] ? double(side) / (hi[a] - lo[a]) : 0.0;
    auto cell = [&](double v, int a) {
      const double c = (v - lo[a]) * scale[a];
      return c > 0 ? size_t(std::min(c, double(side - 1))) : size_t(0);
    };
    std::vector<uint32_t> start(side * side + 1, 0), rays(q.size());
    for (const Vec3& point : q) ++start[cell(point.y, 1) * side + cell(point.x, 0) + 1];
    for (size_t c = 0; c < side * side; ++c) start[c + 1] += start[c];
    {
      std::vector<uint32_t> at(start.begin(), start.end() - 1);
      for (size_t k = 0; k < q.size(); ++k) rays[at[cell(q[k].y, 1) * side + cell(q[k].x, 0)]++] = uint32_t(k);
    }
    // Crossings' parities per block of triangles, combined by exclusive or: any thread count.
    auto cross_all = [&](const std::vector<Vec3>& points, const std::vector<Triangle>& tris,
                         auto&& piece_of_triangle, std::vector<uint8_t>& parity, size_t b, size_t e) {
      if (q.empty()) return;
      for (size_t i = b; i < e; ++i) {
        const Triangle& t = tris[i];
        const double x0 = std::min({points[t[0]].x, points[t[1]].x, points[t[2]].x});
        const double x1 = std::max({points[t[0]].x, points[t[1]].x, points[t[2]].x});
        const double y0 = std::min({points[t[0]].y, points[t[1]].y, points[t[2]].y});
        const double y1 = std::max({points[t[0]].y, points[t[1]].y, points[t[2]].y});
        if (x1 < lo[0] || x0 > hi[0] || y1 < lo[1] || y0 > hi[1]) continue;
        const uint32_t r = piece_of_triangle(i);
        for (size_t cy = cell(y0, 1), cy1 = cell(y1, 1); cy <= cy1; ++cy)
          for (size_t c = cy * side + cell(x0, 0), c1 = cy * side + cell(x1, 0); c <= c1; ++c)
            for (uint32_t j = start[c]; j < start[c + 1]; ++j) {
              const uint32_t k = rays[j];
              if (q[k].x < x0 || q[k].x > x1 || q[k].y < y0 || q[k].y > y1 || piece_of[picked[k]] != r) continue;
              parity[k] ^= uint8_t(ray_crosses(points, t, q[k]));
            }
      }
    };
    constexpr size_t kBlock = 16384;
    const size_t blocks = (T.size() + kBlock - 1) / kBlock;
    std::vector<std::vector<uint8_t>> parities(blocks);
    parallel_blocks(blocks, 1, [&](size_t hb, size_t he) {
      for (size_t h = hb; h < he; ++h) {
        parities[h].assign(picked.size(), 0);
        cross_all(P, T, [&](size_t i) { return piece_of[i]; }, parities[h], h * kBlock,
                  std::min(T.size(), (h + 1) * kBlock));
      }
    });
    std::vector<uint8_t> parity(picked.size(), 0);
    cross_all(cap_points, fans, [&](size_t i) { return fan_piece[i]; }, parity, 0, fans.size());
    for (const auto& p : parities)
      for (size_t k = 0; k < p.size(); ++k) parity[k] ^= p[k];
    for (size_t k = 0; k < picked.size(); ++k) {
      folds.sampled_area += area[k];
      if (parity[k]) folds.sampled_inward_area += area[k];
    }
    if (!(folds.sampled_inward_area > folds.share * folds.sampled_area)) return;
  }
  // Every triangle judged: the triangles bucketed for their rays (RayCrossings).
  std::vector<uint32_t> all(T.size()), all_fans(fans.size());
  std::iota(all.begin(), all.end(), uint32_t(0));
  std::iota(all_fans.begin(), all_fans.end(), uint32_t(0));
  const RayCrossings crossings(P, T, all.data(), all.size());
  const RayCrossings cap_crossings(cap_points, fans, all_fans.data(), all_fans.size());
  folds.inward.assign(T.size(), 0);
  // In fixed chunks, the areas summed in chunk order: the same for any thread count.
  const size_t chunk = 4096, chunks = (T.size() + chunk - 1) / chunk;
  std::vector<std::array<double, 2>> sums(chunks, {0.0, 0.0});
  parallel_blocks(chunks, 1, [&](size_t hb, size_t he) {
    for (size_t h = hb; h < he; ++h)
      for (size_t i = h * chunk; i < std::min(T.size(), (h + 1) * chunk); ++i) {
        const uint32_t r = piece_of[i];
        Vec3 point;
        double area;
        if (!judge[r] || !probe(i, point, area)) continue;
        const size_t count = crossings.count_if(point, [&](uint32_t k) { return piece_of[k] == r; }) +
                             cap_crossings.count_if(point, [&](uint32_t k) { return fan_piece[k] == r; });
        folds.inward[i] = uint8_t(count & 1);
        sums[h][0] += area;
        sums[h][1] += folds.inward[i] ? area : 0.0;
      }
  });
  for (const auto& sum : sums) folds.judged_area += sum[0], folds.inward_area += sum[1];
}
}  // namespace

size_t orient_closed_components_outward(const std::vector<Vec3>& P, std::vector<Triangle>& T,
                                        const std::vector<uint64_t>& boundary, std::vector<Vec3>* vertex_normals,
                                        bool turn, FlatPieces* flat, NearlyClosed* nearly, Folds* folds) {
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
  const bool areas = flat || capping || folds;
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
  const std::vector<std::vector<uint32_t>> none;
  const auto& loops = nearly && nearly->loops ? *nearly->loops : none;
  const std::vector<Cap> caps = caps_of(P, loops);
  std::vector<uint32_t> capped;
  if (capping) {
    capped = close_nearly_closed_pieces(P, loops, caps, root, area, vol, open);
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
  if (folds) {
    folds->pieces = pieces;
    // The pieces to look for folds in: closed and inside no other (one inside another faces
    // into its cavity, rightly), or closed but for small openings (by their caps' area alone).
    // Not where flat pieces were opened (their outlines are in no loop), nor in pieces of
    // fewer than kMinFoldTriangles triangles.
    if (!flat || flat->pieces == 0) {
      std::vector<double> cap_area(pieces, 0.0);
      for (size_t k = 0; k < loops.size(); ++k)
        if (!loops[k].empty()) cap_area[piece[root[loops[k][0]]]] += caps[k].area;
      std::vector<uint32_t> triangles(pieces, 0);
      for (const uint32_t k : piece_of) ++triangles[k];
      std::vector<uint8_t> judge(pieces, 0);
      for (size_t v = 0; v < n; ++v) {
        const uint32_t k = piece[v];
        if (k != UINT32_MAX)
          judge[k] = area[v] > 0 && depth[k] == 0 && triangles[k] >= kMinFoldTriangles &&
                     (!open[v] || cap_area[k] <= kMaxCapShare * area[v]);
      }
      judge_folds(P, T, root, piece, piece_of, judge, loops, caps, *folds);
    }
  }
  return flipped.load();
}

}  // namespace particlemesh::detail
