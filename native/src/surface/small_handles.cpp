#include "surface/small_handles.h"

#include <algorithm>
#include <cstdint>
#include <vector>

#include "core/parallel.h"
#include "surface/triangle_angles.h"

namespace PM_NAMESPACE::detail {

namespace {

constexpr uint32_t kNone = EditableSurface::kNoTriangle;

/// Twice the Euler characteristic V - E + F of a surface of V vertices, F triangles and B
/// boundary half-edges (E = (3 F + B) / 2).
int64_t twice_euler(int64_t vertices, int64_t triangles, int64_t boundary) {
  return 2 * vertices - triangles - boundary;
}

/// The genus of a connected orientable surface, (2 - (V - E + F) - loops) / 2; -1 where that
/// is not a whole number >= 0 (not a 2-manifold: two parts sharing one vertex).
int64_t genus_of(int64_t twice_chi, int64_t loops) {
  const int64_t four = 4 - twice_chi - 2 * loops;
  return four >= 0 && four % 4 == 0 ? four / 4 : -1;
}

/// Which pieces of the surface (EditableSurface::surface_pieces) have a handle: per root, 1
/// where the genus is above zero (genus_of); whether any has. `traced` receives the surface's
/// loops when they had to be traced.
bool pieces_with_handles(const EditableSurface& s, const EditableSurface::Pieces& pieces, std::vector<uint8_t>& handled,
                         std::vector<std::vector<uint32_t>>& traced) {
  const std::vector<uint32_t>& piece = pieces.piece;
  const std::vector<uint32_t>& triangles = pieces.triangles;
  const size_t n = piece.size();
  handled.assign(n, 0);
  // Per piece, in the order of their roots: vertices, boundary half-edges, loops.
  std::vector<uint32_t> slot(n, 0), roots;
  for (uint32_t r = 0; r < n; ++r)
    if (piece[r] == r && triangles[r] > 0) slot[r] = uint32_t(roots.size()), roots.push_back(r);
  std::vector<int64_t> vertices(roots.size(), 0), boundary(roots.size(), 0), loops(roots.size(), 0);
  for (uint32_t v = 0; v < n; ++v)
    if (triangles[piece[v]] > 0) ++vertices[slot[piece[v]]];
  for (uint64_t e : s.boundary_set()) ++boundary[slot[piece[uint32_t(e >> 32)]]];
  auto chi2 = [&](size_t i) { return twice_euler(vertices[i], triangles[roots[i]], boundary[i]); };
  // Loops are traced only if some open piece could have a handle: genus >= 1 with b >= 1
  // loops needs V - E + F <= 2 - 2 - b < 0.
  bool trace = false;
  for (size_t i = 0; i < roots.size(); ++i) trace |= boundary[i] > 0 && chi2(i) < 0;
  if (trace) {
    traced = s.trace_loops();
    for (const auto& loop : traced) ++loops[slot[piece[loop[0]]]];
  }
  bool any = false;
  for (size_t i = 0; i < roots.size(); ++i) {
    handled[roots[i]] = genus_of(chi2(i), loops[i]) >= 1;
    any |= handled[roots[i]] != 0;
  }
  return any;
}

/// The triangles around a vertex within a ball, as a patch of the surface, and its topology.
class Patch {
 public:
  explicit Patch(const EditableSurface& s) : s_(s), in_(s.triangle_slots(), 0), seen_(s.point_count(), 0) {}

  /// The triangles joined to `centre`'s through edges, every corner within `reach` of it.
  void grow(uint32_t centre, double reach) {
    if (in_.size() < s_.triangle_slots()) in_.resize(s_.triangle_slots(), 0);
    ++epoch_;
    tris_.clear();
    const auto& P = s_.positions();
    const double r2 = reach * reach;
    auto inside = [&](uint32_t t) {
      for (uint32_t v : s_.triangle(t))
        if (squared_distance(P[v], P[centre]) > r2) return false;
      return true;
    };
    s_.for_each_tri(centre, [&](uint32_t t) {
      if (in_[t] != epoch_ && inside(t)) in_[t] = epoch_, tris_.push_back(t);
    });
    for (size_t i = 0; i < tris_.size(); ++i) {
      const Triangle T = s_.triangle(tris_[i]);
      for (int k = 0; k < 3; ++k) {
        const uint32_t u = s_.triangle_with(T[(k + 1) % 3], T[k]);
        if (u != kNone && in_[u] != epoch_ && inside(u)) in_[u] = epoch_, tris_.push_back(u);
      }
    }
  }

  const std::vector<uint32_t>& triangles() const { return tris_; }
  bool holds(uint32_t t) const { return t < in_.size() && in_[t] == epoch_; }

  /// The patch's genus and its outline (the half-edges whose other side is not in the
  /// patch), traced into loops keeping the patch on their left. `interior`: every outline
  /// half-edge has a triangle of the surface on its other side.
  struct Shape {
    int64_t genus = 0;
    std::vector<std::vector<uint32_t>> loops;
    bool interior = true;
    std::vector<uint32_t> vertices;
  };
  Shape shape() {
    Shape out;
    size_t boundary = 0;
    for (uint32_t t : tris_)
      for (uint32_t v : s_.triangle(t))
        if (seen_[v] != epoch_) seen_[v] = epoch_, out.vertices.push_back(v);
    // Outline half-edges, each with the triangle that holds it.
    std::vector<std::pair<uint64_t, uint32_t>> outline;
    for (uint32_t t : tris_) {
      const Triangle& T = s_.triangle(t);
      for (int k = 0; k < 3; ++k) {
        const uint32_t a = T[k], b = T[(k + 1) % 3];
        const uint32_t other = s_.triangle_with(b, a);
        if (holds(other)) continue;
        ++boundary;
        if (other == kNone) out.interior = false;
        outline.push_back({EditableSurface::half_key(a, b), t});
      }
    }
    std::sort(outline.begin(), outline.end());
    std::vector<uint8_t> used(outline.size(), 0);
    auto find = [&](uint32_t a, uint32_t b) {
      const auto it = std::lower_bound(outline.begin(), outline.end(), std::make_pair(EditableSurface::half_key(a, b), 0u));
      return it != outline.end() && it->first == EditableSurface::half_key(a, b) ? size_t(it - outline.begin())
                                                                                 : outline.size();
    };
    for (size_t start = 0; start < outline.size(); ++start) {
      if (used[start]) continue;
      std::vector<uint32_t> loop;
      size_t e = start;
      while (!used[e]) {
        used[e] = 1;
        uint32_t a = uint32_t(outline[e].first >> 32), b = uint32_t(outline[e].first);
        loop.push_back(a);
        // The next outline half-edge leaves b: turn about b through the patch's triangles,
        // from a -> b's, until a half-edge out of b has no patch triangle on its other side.
        uint32_t t = outline[e].second;
        for (size_t turns = 0;; ++turns) {
          const Triangle& T = s_.triangle(t);
          const uint32_t c = T[(corner_of(T, b) + 1) % 3];
          const uint32_t u = s_.triangle_with(c, b);
          if (!holds(u) || turns > tris_.size()) {
            e = find(b, c);
            break;
          }
          t = u;
        }
        if (e == outline.size()) {  // the outline does not go on (not a 2-manifold here)
          out.genus = 0;
          return out;
        }
      }
      if (e != start) {  // the walk closed elsewhere than where it began: the same
        out.genus = 0;
        return out;
      }
      out.loops.push_back(std::move(loop));
    }
    out.genus = std::max<int64_t>(
        0, genus_of(twice_euler(int64_t(out.vertices.size()), int64_t(tris_.size()), int64_t(boundary)),
                    int64_t(out.loops.size())));
    return out;
  }

 private:
  const EditableSurface& s_;
  std::vector<uint32_t> in_, seen_;
  uint32_t epoch_ = 0;
  std::vector<uint32_t> tris_;
};

/// Does the surface fold sharply at v: two of its triangles on an edge at v with normals
/// more than 90 degrees apart (a negative dot product of their unnormalised normals)? Both
/// triangles of an edge v -> w are at v: the other holds w -> v, its corner at v has w before
/// it. `work`: scratch space.
bool folds_sharply(const EditableSurface& s, uint32_t v, std::vector<std::pair<Vec3, uint64_t>>& work) {
  const auto& P = s.positions();
  work.clear();
  s.for_each_tri(v, [&](uint32_t t) {
    const Triangle& T = s.triangle(t);
    const int k = corner_of(T, v);
    const uint64_t succ = T[(k + 1) % 3], pred = T[(k + 2) % 3];
    work.push_back({cross(P[T[1]] - P[T[0]], P[T[2]] - P[T[0]]), succ << 32 | pred});
  });
  for (const auto& [n, a] : work)
    for (const auto& [m, b] : work)
      if (uint32_t(b) == uint32_t(a >> 32) && dot(n, m) < 0) return true;  // b's pred is a's succ
  return false;
}

/// remove_small_handles, with what the search found on the surface in `found`.
size_t take_out_small_handles(EditableSurface& s, const FillOptions& o, size_t max_loop, HandleSearch& found) {
  if (s.triangle_slots() == 0) return 0;
  found.pieces = s.pieces();
  const std::vector<uint32_t>& piece = found.pieces.piece;
  std::vector<uint8_t> handled;
  if (!pieces_with_handles(s, found.pieces, handled, found.loops)) return 0;
  const size_t n = piece.size();
  std::vector<uint8_t> sharp(n, 0);
  parallel_blocks(n, 8192, [&](size_t b, size_t e) {
    std::vector<std::pair<Vec3, uint64_t>> work;
    for (size_t v = b; v < e; ++v) sharp[v] = handled[piece[v]] && folds_sharply(s, uint32_t(v), work);
  });
  std::vector<uint32_t> seeds;
  for (uint32_t v = 0; v < n; ++v)
    if (sharp[v]) seeds.push_back(v);
  if (seeds.empty()) return 0;
  const auto& P = s.positions();
  const std::vector<double>& L = *o.max_edge;
  std::vector<uint8_t> covered(n, 0);
  Patch patch(s);
  size_t removed = 0;
  for (uint32_t v : seeds) {
    if (covered[v]) continue;
    const double reach = kHandleReach * L[v];
    patch.grow(v, reach);
    if (patch.triangles().empty()) continue;
    Patch::Shape shape = patch.shape();
    // The patch's vertices near the centre need no patch of their own: one around them
    // would hold nearly the same triangles.
    for (uint32_t w : shape.vertices)
      if (distance(P[w], P[v]) <= 0.5 * reach) covered[w] = 1;
    if (shape.genus < 1 || shape.loops.size() != 1 || !shape.interior || shape.loops[0].size() > max_loop) continue;
    // The outline, as the surface's boundary once the patch is gone: its half-edges reversed.
    std::vector<uint32_t> loop(shape.loops[0].rbegin(), shape.loops[0].rend());
    std::vector<uint32_t> sorted(loop);
    std::sort(sorted.begin(), sorted.end());
    if (std::adjacent_find(sorted.begin(), sorted.end()) != sorted.end()) continue;  // through a vertex twice
    for (uint32_t t : patch.triangles()) s.kill_triangle(t);
    // The outline is now a loop of the surface's boundary, each half-edge held on its far side.
    bool boundary = true;
    for (size_t i = 0; i < loop.size(); ++i) {
      const uint32_t a = loop[i], b = loop[(i + 1) % loop.size()];
      boundary = boundary && s.directed_used(a, b) && !s.directed_used(b, a);
    }
    FillStats fill;  // not a hole of the surface: not counted as one
    if (boundary && (fill_loop(s, loop, o, fill) || fill_loop(s, loop, o, fill, kMaxCreaseDihedral))) {
      removed += size_t(shape.genus);
      for (uint32_t w : shape.vertices) covered[w] = 1;
    } else {
      for (uint32_t t : patch.triangles()) s.revive_triangle(t);  // as it was, slot for slot
    }
  }
  return removed;
}

}  // namespace

size_t remove_small_handles(EditableSurface& s, const FillOptions& o, size_t max_loop, HandleSearch* unchanged) {
  HandleSearch found;
  const size_t removed = take_out_small_handles(s, o, max_loop, found);
  if (unchanged) *unchanged = removed == 0 ? std::move(found) : HandleSearch{};
  return removed;
}

}  // namespace particlemesh::detail
