#include "surface/repair.h"

#include <algorithm>
#include <cmath>
#include <memory>
#include <numeric>

#include "particlemesh/spatial/neighbor_grid.h"
#include "surface/small_handles.h"
#include "surface/tangent_arcs.h"
#include "surface/triangle_angles.h"

namespace PM_NAMESPACE::detail {

size_t unpinch(EditableSurface& s) {
  std::vector<uint32_t> starts;
  for (uint64_t e : s.boundary_set()) starts.push_back(uint32_t(e >> 32));
  std::sort(starts.begin(), starts.end());
  std::vector<uint32_t> suspects;
  for (size_t i = 1; i < starts.size(); ++i)
    if (starts[i] == starts[i - 1]) suspects.push_back(starts[i]);
  // Fills and insertions are not held to the wedge rule: check their corners too, those whose
  // triangles changed since the last unpinch (any other was looked at then, and is as it was:
  // its fans then, fixed or one, are its fans now). On a random sampling the fills touch 40 %
  // of the vertices, and every pass looked at all of them again.
  for (uint32_t v : s.take_changed_vertices())
    if (s.has_added_triangles(v)) suspects.push_back(v);
  std::sort(suspects.begin(), suspects.end());
  suspects.erase(std::unique(suspects.begin(), suspects.end()), suspects.end());
  size_t removed_fans = 0;
  std::vector<uint32_t> ts, parent, size;
  for (uint32_t v : suspects) {
    ts.clear();
    s.for_each_tri(v, [&](uint32_t t) { ts.push_back(t); });
    if (ts.size() < 2) continue;
    parent.resize(ts.size());
    std::iota(parent.begin(), parent.end(), 0u);
    auto find = [&](uint32_t x) {
      while (parent[x] != x) x = parent[x] = parent[parent[x]];
      return x;
    };
    for (size_t i = 0; i < ts.size(); ++i)
      for (size_t j = i + 1; j < ts.size(); ++j) {
        const Triangle &A = s.triangle(ts[i]), &B = s.triangle(ts[j]);
        const int ka = corner_of(A, v), kb = corner_of(B, v);
        if (A[(ka + 1) % 3] == B[(kb + 2) % 3] || A[(ka + 2) % 3] == B[(kb + 1) % 3])
          parent[find(uint32_t(i))] = find(uint32_t(j));
      }
    size.assign(ts.size(), 0);
    for (size_t i = 0; i < ts.size(); ++i) ++size[find(uint32_t(i))];
    uint32_t best = find(0);
    size_t fans = 0;
    for (size_t i = 0; i < ts.size(); ++i)
      if (find(uint32_t(i)) == i) {
        ++fans;
        if (size[i] > size[best]) best = uint32_t(i);
      }
    if (fans < 2) continue;
    for (size_t i = 0; i < ts.size(); ++i)
      if (find(uint32_t(i)) != best) s.kill_triangle(ts[i]);
    removed_fans += fans - 1;
  }
  return removed_fans;
}

namespace {

/// New triangles fold at most kMaxFillDihedral against the triangle they replace or adjoin,
/// as fills do.
const double kMinFoldCos = std::cos(kMaxFillDihedral);

/// Does the corner (v; succ, pred) of a new triangle fit in the gap of v's fan: its arc overlaps
/// none of the arcs of v's triangles (the growth's wedge rule)? Arcs are taken about the fan's
/// own normal (its triangles' and the new one's, angle-weighted): the particle's estimated
/// normal may lean off a noisy fan, which makes arcs that do not overlap seem to.
bool fits_fan(const EditableSurface& s, uint32_t v, uint32_t succ, uint32_t pred) {
  const std::vector<Vec3>& P = s.positions();
  auto weighted = [&](const Vec3& a, const Vec3& b) {
    const Vec3 f = normalized(cross(a - P[v], b - P[v]));
    return f * fast_acos(std::clamp(corner_cosine(P[v], a, b), -1.0, 1.0));
  };
  Vec3 n = weighted(P[succ], P[pred]);
  s.for_each_tri(v, [&](uint32_t t) {
    const Triangle& T = s.triangle(t);
    const int k = corner_of(T, v);
    n += weighted(P[T[(k + 1) % 3]], P[T[(k + 2) % 3]]);
  });
  if (!(squared_norm(n) > 0)) return false;
  const Frame f = tangent_frame(normalized(n));
  const Arc mine = make_arc(f, P[v], P[succ], P[pred]);
  bool fits = true;
  s.for_each_tri(v, [&](uint32_t t) {
    const Triangle& T = s.triangle(t);
    const int k = corner_of(T, v);
    const Arc other = make_arc(f, P[v], P[T[(k + 1) % 3]], P[T[(k + 2) % 3]]);
    fits = fits && !arcs_overlap(other, mine) && !arcs_overlap(mine, other);
  });
  return fits;
}

/// A triangle with no corner of sine below about 1e-10 relative to its edges.
bool proper(const std::vector<Vec3>& P, uint32_t a, uint32_t b, uint32_t c) {
  const Vec3 u = P[b] - P[a], v = P[c] - P[a], w = P[c] - P[b];
  const double n2 = squared_norm(cross(u, v));
  const double l1 = squared_norm(u), l2 = squared_norm(v), l3 = squared_norm(w);
  const double lmax = std::max({l1, l2, l3}), lmid = l1 + l2 + l3 - lmax - std::min({l1, l2, l3});
  return n2 > 1e-20 * lmax * lmid;
}

}  // namespace

size_t insert_unused(EditableSurface& s, const std::vector<uint8_t>& active, const std::vector<Triangle>& raw,
                     const FillOptions& o, std::unique_ptr<NeighborGrid>& near) {
  const std::vector<Vec3>& P = s.positions();
  const std::vector<double>& Lp = *o.max_edge;
  std::vector<uint32_t> unused;
  for (uint32_t p = 0; p < P.size(); ++p) {
    if (!active[p]) continue;
    bool used = false;
    s.for_each_tri(p, [&](uint32_t) { used = true; });
    if (!used) unused.push_back(p);
  }
  if (unused.empty()) return 0;
  // The raw triangles at each unused particle tell which surface is around it.
  constexpr uint32_t kUsed = 0xffffffffu;
  std::vector<uint32_t> slot(P.size(), kUsed);  // each particle's place in `unused`
  for (size_t u = 0; u < unused.size(); ++u) slot[unused[u]] = uint32_t(u);
  std::vector<std::vector<uint32_t>> around(unused.size());
  for (const Triangle& t : raw)
    for (int k = 0; k < 3; ++k)
      if (slot[t[k]] != kUsed)
        for (int q = 1; q < 3; ++q) around[slot[t[k]]].push_back(t[(k + q) % 3]);
  // A new edge from p to the surface's vertex v is held to the fill limit at the surface's
  // scale or p's, whichever is larger: p is a sample of the surface around v (a stray one: its
  // own spacing, from the few particles around it, says little).
  auto short_enough = [&](uint32_t p, uint32_t v) {
    return distance(P[p], P[v]) <= std::min(o.fill_edge_factor * std::max(Lp[p], Lp[v]), o.edge_cap) &&
           !o.view.along_ray(P[p], P[v]);
  };
  // The largest limit among the surface's vertices: the farthest any of them may reach out.
  double surface_scale = 0;
  for (size_t v = 0; v < P.size(); ++v)
    if (active[v]) surface_scale = std::max(surface_scale, Lp[v]);
  size_t inserted = 0;
  std::vector<uint32_t> near_nb;  // of nb, those within p's reach
  for (size_t u = 0; u < unused.size(); ++u) {
    const uint32_t p = unused[u];
    // How far p may reach: a repair edge may be as long as the fill limit (at the larger
    // scale of p's and the surface's; see short_enough).
    const double max_edge = std::min(o.fill_edge_factor * std::max(Lp[p], surface_scale), o.edge_cap);
    auto& nb = around[u];
    std::sort(nb.begin(), nb.end());
    nb.erase(std::unique(nb.begin(), nb.end()), nb.end());
    // The raw triangles' other corners that are on the surface.
    nb.erase(std::remove_if(nb.begin(), nb.end(), [&](uint32_t w) {
               bool on = false;
               s.for_each_tri(w, [&](uint32_t) { on = true; });
               return !on;
             }),
             nb.end());
    if (nb.empty()) {
      // In no raw triangle with the surface (fewer than two neighbours within L, e.g. at the
      // rim of a real opening, or only particles the surface passed by too): take the surface's
      // vertices within p's reach as its neighbours.
      // A grid over the particles, built at the first such particle (and kept for the next
      // rounds: the particles do not move): scanning the whole surface per particle is
      // quadratic on scans with many openings.
      if (!near) {
        std::vector<double> l(Lp);
        std::nth_element(l.begin(), l.begin() + ptrdiff_t(l.size() / 2), l.end());
        near = std::make_unique<NeighborGrid>(P.data(), P.size(), l[l.size() / 2]);
      }
      near->for_each_within(P[p], max_edge, [&](uint32_t g, double) {
        const uint32_t a = near->original_index(g);
        if (a == p || !active[a]) return;
        bool on = false;
        s.for_each_tri(a, [&](uint32_t) { on = true; });
        if (on) nb.push_back(a);
      });
      std::sort(nb.begin(), nb.end());
    }
    // 1. Over a triangle: split it in three. (Only a triangle whose corners are all within
    // reach is taken: it is met through those of nb that are, in the same order.)
    double best = INFINITY;
    int64_t best_t = -1;
    near_nb.clear();
    for (uint32_t w : nb)
      if (short_enough(p, w)) near_nb.push_back(w);
    for (uint32_t w : near_nb)
      s.for_each_tri(w, [&](uint32_t t) {
        const Triangle& T = s.triangle(t);
        const Vec3 a = P[T[0]], b = P[T[1]], c = P[T[2]];
        const Vec3 n = cross(b - a, c - a);
        const double n2 = squared_norm(n);
        if (!(n2 > 0)) return;
        const Vec3 q = P[p];
        const double la = dot(cross(c - b, q - b), n) / n2, lb = dot(cross(a - c, q - c), n) / n2;
        // Strictly inside: a particle on an edge goes to the edge split below, which keeps
        // every triangle non-degenerate.
        if (la < 1e-6 || lb < 1e-6 || 1 - la - lb < 1e-6) return;
        const double h = std::abs(dot(q - a, n)) / std::sqrt(n2);
        if (h < best && short_enough(p, T[0]) && short_enough(p, T[1]) && short_enough(p, T[2])) {
          best = h;
          best_t = t;
        }
      });
    if (best_t >= 0 && best <= max_edge) {
      const Triangle T = s.triangle(uint32_t(best_t));
      s.kill_triangle(uint32_t(best_t));
      s.add_triangle({T[0], T[1], p});
      s.add_triangle({T[1], T[2], p});
      s.add_triangle({T[2], T[0], p});
      ++inserted;
      continue;
    }
    // 2. Beside an edge within its reach, nearest first: beyond a boundary edge x -> y (on the
    // side away from its triangle) p becomes a new triangle (y, x, p) on it, if that fits the
    // fans at x and y and does not fold back over the surface; otherwise the edge is split at
    // p: each triangle (x, y, c) on it becomes (x, p, c) and (p, y, c). The fans stay disks
    // and the windings agree. Splits that would give a degenerate or turned triangle (p in
    // line with a corner: rows of a depth scan) are passed over for the next nearest edge.
    std::vector<std::pair<double, std::pair<uint32_t, uint32_t>>> edges;
    for (uint32_t w : nb)
      s.for_each_tri(w, [&](uint32_t t) {
        for (int k = 0; k < 3; ++k) {
          const uint32_t a = s.triangle(t)[k], b = s.triangle(t)[(k + 1) % 3];
          const Vec3 ab = P[b] - P[a];
          const double along = std::clamp(dot(P[p] - P[a], ab) / squared_norm(ab), 0.0, 1.0);
          const double d = squared_distance(P[p], P[a] + ab * along);
          // (An edge with an end out of reach is passed over below: not sorted in.)
          if (d <= max_edge * max_edge && short_enough(p, a) && short_enough(p, b))
            edges.push_back({d, {std::min(a, b), std::max(a, b)}});
        }
      });
    std::sort(edges.begin(), edges.end());
    edges.erase(std::unique(edges.begin(), edges.end()), edges.end());
    for (const auto& [d, e] : edges) {
      // Plain variables, not a structured binding: the lambdas below capture them, which
      // clang before 16 (the sanitizer build's clang 14) does not allow.
      const uint32_t a = e.first, b = e.second;
      std::vector<uint32_t> on_edge;
      s.for_each_tri(a, [&](uint32_t t) {
        const Triangle& T = s.triangle(t);
        const int k = corner_of(T, a);
        if (T[(k + 1) % 3] == b || T[(k + 2) % 3] == b) on_edge.push_back(t);
      });
      if (on_edge.empty() || !short_enough(p, a) || !short_enough(p, b)) continue;
      if (on_edge.size() == 1) {
        const Triangle& T = s.triangle(on_edge[0]);
        const int k = corner_of(T, a);
        const bool forward = T[(k + 1) % 3] == b;
        const uint32_t x = forward ? a : b, y = forward ? b : a;
        const Vec3 nt = s.face_normal(T);
        // Beyond the edge: p on the side of it away from T, in T's plane.
        const Vec3 side = cross(nt, P[y] - P[x]);  // points into T
        if (dot(P[p] - P[x], side) < 0 && proper(P, y, x, p)) {
          const Vec3 ne = s.face_normal({y, x, p});
          if (dot(ne, nt) > kMinFoldCos && fits_fan(s, x, p, y) && fits_fan(s, y, x, p)) {
            s.add_triangle({y, x, p});
            ++inserted;
            break;
          }
        }
      }
      bool ok = true;
      for (uint32_t t : on_edge) {
        const Triangle& T = s.triangle(t);
        const int k = corner_of(T, a);
        const bool forward = T[(k + 1) % 3] == b;
        const uint32_t x = forward ? a : b, y = forward ? b : a, c = T[(corner_of(T, x) + 2) % 3];
        const Vec3 nt = s.face_normal(T);
        ok = ok && short_enough(p, c) && proper(P, x, p, c) && proper(P, p, y, c) &&
             dot(s.face_normal({x, p, c}), nt) > kMinFoldCos && dot(s.face_normal({p, y, c}), nt) > kMinFoldCos;
      }
      if (!ok) continue;
      for (uint32_t t : on_edge) {
        const Triangle T = s.triangle(t);
        const int k = corner_of(T, a);
        // Name the corners so the edge runs x -> y in T = (x, y, c).
        const bool forward = T[(k + 1) % 3] == b;
        const uint32_t x = forward ? a : b, y = forward ? b : a;
        const uint32_t c = T[(corner_of(T, x) + 2) % 3];
        s.kill_triangle(t);
        s.add_triangle({x, p, c});
        s.add_triangle({p, y, c});
      }
      ++inserted;
      break;
    }
  }
  return inserted;
}

size_t drop_fragments(EditableSurface& s, const std::vector<Triangle>& raw) {
  const std::vector<Vec3>& P = s.positions();
  const size_t n = P.size();
  std::vector<uint32_t> piece, count;
  s.surface_pieces(piece, count);
  std::vector<uint8_t> small(n, 0), touching(n, 0);
  bool any = false;
  for (uint32_t v = 0; v < n; ++v)
    if (piece[v] == v && count[v] > 0 && count[v] <= kMaxFragment) small[v] = any = true;
  if (!any) return 0;
  // A raw triangle with corners in a small piece and in a larger one joins them (of small
  // pieces joined only to each other the largest stays: a sparse patch keeps a surface).
  for (const Triangle& t : raw) {
    const uint32_t r0 = piece[t[0]], r1 = piece[t[1]], r2 = piece[t[2]];
    for (uint32_t a : {r0, r1, r2})
      if (small[a])
        for (uint32_t b : {r0, r1, r2})
          if (b != a && count[b] > count[a]) touching[a] = 1;
  }
  size_t dropped = 0;
  for (uint32_t t = 0; t < s.triangle_slots(); ++t) {
    if (!s.alive(t)) continue;
    const uint32_t r = piece[s.triangle(t)[0]];
    if (small[r] && touching[r]) {
      s.kill_triangle(t);
      ++dropped;
    }
  }
  return dropped;
}

void sort_out_pieces(EditableSurface& s, size_t min_triangles, PieceStats& out, const EditableSurface::Pieces* known) {
  out = {};
  const bool removing = min_triangles > 1;
  if (!removing && s.closed()) return;
  const EditableSurface::Pieces found = known ? EditableSurface::Pieces{} : s.pieces();
  const std::vector<uint32_t>& piece = known ? known->piece : found.piece;
  const std::vector<uint32_t>& count = known ? known->triangles : found.triangles;  // at each root
  if (removing) {
    for (uint32_t t = 0; t < s.triangle_slots(); ++t)
      if (s.alive(t) && count[piece[s.triangle(t)[0]]] < min_triangles) {
        s.kill_triangle(t);
        ++out.removed_triangles;
      }
  }
  const bool open = !s.closed();
  for (uint32_t v = 0; v < piece.size(); ++v) {
    if (piece[v] != v || count[v] == 0) continue;
    if (count[v] < min_triangles) {
      ++out.removed;
    } else if (open && count[v] < kStrayPieceTriangles) {
      ++out.strays.count;
      out.strays.triangles += count[v];
      out.strays.largest = std::max<size_t>(out.strays.largest, count[v]);
    }
  }
}

void repair_surface(EditableSurface& s, const std::vector<uint8_t>& active, const std::vector<Triangle>& raw,
                    const RepairOptions& o, RepairStats& stats, ProgressTracker& tracker) {
  tracker.stage("repairing", 0.85, 0.97);
  // Every pass before the last fills with edges of at most kFirstFillFactor x L (or the
  // caller's factor, if smaller): particles put back later close many of the loops left
  // with shorter edges than a wide fill would use.
  FillOptions f = o.fill;
  f.fill_edge_factor = std::min(f.fill_edge_factor, kFirstFillFactor);
  // Small loops first (wrong diagonals, sampling gaps), then pinches, then larger loops.
  // A check between the steps: each is a pass over the whole mesh (up to a second at 1M
  // points), and a host's cancel request is only seen in a check.
  fill_loops(s, f.small_hole, f, stats);
  tracker.check();
  stats.pinches_resolved += unpinch(s);
  tracker.check();
  fill_loops(s, f.small_hole, f, stats);
  tracker.check();
  if (o.max_hole > f.small_hole) fill_loops(s, o.max_hole, f, stats);
  tracker.check();
  stats.pinches_resolved += unpinch(s);
  tracker.check();
  drop_fragments(s, raw);
  tracker.check();
  // Particles inserted next to the surface give the ones beyond them something to attach to:
  // a few rounds, until none is left that fits.
  size_t inserted = 0;
  std::unique_ptr<NeighborGrid> near;  // built by the first round that needs it
  for (int round = 0; round < kInsertRounds; ++round) {
    const size_t now = insert_unused(s, active, raw, f, near);
    tracker.check();
    if (now == 0) break;
    inserted += now;
  }
  if (inserted > 0) {
    fill_loops(s, f.small_hole, f, stats);
    stats.pinches_resolved += unpinch(s);
  }
  tracker.check();
  if (o.max_hole > 0 && fill_folded_loops(s, o.max_hole, f, stats) > 0) {
    tracker.check();
    stats.pinches_resolved += unpinch(s);
  }
  tracker.check();
  // The loops still open once every particle that fits is in, filled up to the caller's
  // factor: gaps in the sampling wider than the first passes' limit.
  if (o.max_hole > 0 && o.fill.fill_edge_factor > f.fill_edge_factor && !s.closed()) {
    size_t wide = fill_loops(s, o.max_hole, o.fill, stats);
    wide += fill_folded_loops(s, o.max_hole, o.fill, stats);
    if (wide > 0) stats.pinches_resolved += unpinch(s);
    tracker.check();
  }
  // Handles smaller than the sampling, where a part thinner than the spacing was joined
  // across: each replaced by a fill of its outline, its particles put back.
  HandleSearch seen;  // the surface's pieces (and loops, if traced), while it is unchanged
  stats.small_handles_removed = remove_small_handles(s, o.fill, o.max_hole, &seen);
  if (stats.small_handles_removed > 0) {
    for (int round = 0; round < kInsertRounds; ++round)
      if (insert_unused(s, active, raw, o.fill, near) == 0) break;
    fill_loops(s, f.small_hole, f, stats);
    stats.pinches_resolved += unpinch(s);
  }
  tracker.check();
  sort_out_pieces(s, o.min_component_triangles, stats.pieces, seen.pieces.piece.empty() ? nullptr : &seen.pieces);
  tracker.check();
  if (!s.closed()) {
    // The loops traced above are still the surface's unless a piece was removed since.
    const auto left = seen.loops.empty() || stats.pieces.removed > 0 ? s.trace_loops() : std::move(seen.loops);
    stats.holes_left = left.size();
    for (const auto& l : left) {
      stats.largest_hole_left = std::max(stats.largest_hole_left, l.size());
      stats.holes_left_edges.push_back(l.size());
      if (stats.open_loops.size() < 1000)
        stats.open_loops.push_back({l.size(), l.size() <= kMaxWidthLoop ? loop_width(s.positions(), l, f) : INFINITY});
    }
    std::sort(stats.holes_left_edges.begin(), stats.holes_left_edges.end());
  }
}

}  // namespace particlemesh::detail
