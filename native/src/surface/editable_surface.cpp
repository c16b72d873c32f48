#include "surface/editable_surface.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <numeric>

#include "core/first_touch.h"
#include "core/parallel.h"
#include "surface/triangle_angles.h"

namespace PM_NAMESPACE::detail {

EditableSurface::EditableSurface(const std::vector<Vec3>& P, const std::vector<Frame>& frames, GrownSurface&& g,
                                 ProgressTracker& tracker)
    : P_(P), frame_(frames), tris_(std::move(g.triangles)) {
  const size_t n = P_.size();
  const auto& vc = g.corners;
  const auto& vc_off = g.corner_offset;
  const auto& acc_count = g.accepted_count;
  alive_.assign(tris_.size(), 1);
  extra_of_.assign(n, kNoList);
  changed_.assign(n, 0);
  vt_off_.assign(n + 1, 0);
  parallel_blocks(n, 8192, [&](size_t b, size_t e) {
    for (size_t v = b; v < e; ++v) vt_off_[v + 1] = acc_count[v];
  });
  std::partial_sum(vt_off_.begin(), vt_off_.end(), vt_off_.begin());
  vt_.resize(vt_off_[n]);
  {
    std::vector<uint32_t> fill(vt_off_.begin(), vt_off_.end() - 1);
    for (uint32_t t = 0; t < tris_.size(); ++t)
      for (uint32_t v : tris_[t]) vt_[fill[v]++] = t;
  }
  tracker.check();
  // Per vertex: its boundary half-edges v -> s (no accepted triangle holds s -> v, i.e. no
  // corner at v has s as its predecessor). Found in parallel and joined in block order.
  const size_t block = 8192, blocks = (n + block - 1) / block;
  std::vector<std::vector<uint64_t>> found(blocks);
  parallel_blocks(blocks, 1, [&](size_t bb, size_t be) {
    for (size_t b = bb; b < be; ++b) {
      if (tracker.cancelled()) return;
      tracker.tick(0);  // on the calling thread: lets a cancel request in
      for (size_t v = b * block; v < std::min(n, (b + 1) * block); ++v) {
        const Corner* x = vc.data() + vc_off[v];
        const uint32_t m = acc_count[v];
        for (uint32_t i = 0; i < m; ++i) {
          bool closed = false;
          for (uint32_t j = 0; j < m && !closed; ++j) closed = x[j].pred == x[i].succ;
          if (!closed) found[b].push_back(half_key(uint32_t(v), x[i].succ));
        }
      }
    }
  });
  tracker.check();
  for (const auto& f : found)
    for (const uint64_t e : f) boundary_.insert(e);
  // Growth is over: free its structures.
  decltype(g.corners)().swap(g.corners);
  std::vector<uint32_t>().swap(g.corner_offset);
}

EditableSurface::EditableSurface(const std::vector<Vec3>& P, const std::vector<Frame>& frames,
                                 const std::vector<Triangle>& triangles)
    : P_(P), frame_(frames), tris_(triangles) {
  const size_t n = P_.size();
  alive_.assign(tris_.size(), 1);
  extra_of_.assign(n, kNoList);
  changed_.assign(n, 0);
  vt_off_.assign(n + 1, 0);
  for (const Triangle& t : tris_)
    for (uint32_t v : t) ++vt_off_[v + 1];
  std::partial_sum(vt_off_.begin(), vt_off_.end(), vt_off_.begin());
  vt_.resize(vt_off_[n]);
  std::vector<uint32_t> fill(vt_off_.begin(), vt_off_.end() - 1);
  for (uint32_t t = 0; t < tris_.size(); ++t)
    for (uint32_t v : tris_[t]) vt_[fill[v]++] = t;
  for (const Triangle& T : tris_) toggle_boundary(T, true);
}

uint32_t EditableSurface::triangle_with(uint32_t a, uint32_t b) const {
  uint32_t found = kNoTriangle;
  for_each_tri(a, [&](uint32_t t) {
    const Triangle& T = tris_[t];
    if (T[(corner_of(T, a) + 1) % 3] == b) found = t;
  });
  return found;
}

bool EditableSurface::triangle_exists(uint32_t a, uint32_t b, uint32_t c) const {
  bool found = false;
  for_each_tri(a, [&](uint32_t t) {
    const Triangle& T = tris_[t];
    if ((T[0] == b || T[1] == b || T[2] == b) && (T[0] == c || T[1] == c || T[2] == c)) found = true;
  });
  return found;
}

bool EditableSurface::starts_boundary(uint32_t v) const {
  bool found = false;
  for_each_tri(v, [&](uint32_t t) {
    const Triangle& T = tris_[t];
    const uint32_t w = T[(corner_of(T, v) + 1) % 3];
    bool twin = false;
    for_each_tri(v, [&](uint32_t u) {
      const Triangle& U = tris_[u];
      twin = twin || U[(corner_of(U, v) + 2) % 3] == w;
    });
    found = found || !twin;
  });
  return found;
}

void EditableSurface::add_triangle(const Triangle& T) {
  const uint32_t id = uint32_t(tris_.size());
  tris_.push_back(T);
  alive_.push_back(1);
  for (uint32_t v : T) {
    if (extra_of_[v] == kNoList) {
      extra_of_[v] = uint32_t(extra_.size());
      extra_.emplace_back();
    }
    extra_[extra_of_[v]].push_back(id);
  }
  mark_changed(T);
  toggle_boundary(T, true);
}

void EditableSurface::kill_triangle(uint32_t t) {
  alive_[t] = 0;
  mark_changed(tris_[t]);
  toggle_boundary(tris_[t], false);
}

void EditableSurface::revive_triangle(uint32_t t) {
  alive_[t] = 1;
  mark_changed(tris_[t]);
  toggle_boundary(tris_[t], true);
}

void EditableSurface::mark_changed(const Triangle& T) {
  for (uint32_t v : T)
    if (!changed_[v]) {
      changed_[v] = 1;
      changed_list_.push_back(v);
    }
}

std::vector<uint32_t> EditableSurface::take_changed_vertices() {
  for (uint32_t v : changed_list_) changed_[v] = 0;
  std::vector<uint32_t> out;
  out.swap(changed_list_);
  return out;
}

void EditableSurface::toggle_boundary(const Triangle& T, bool entering) {
  for (int k = 0; k < 3; ++k) {
    uint32_t a = T[k], b = T[(k + 1) % 3];
    if (!entering) std::swap(a, b);  // leaving: a -> b goes, b -> a is left open
    if (!boundary_.erase(half_key(b, a))) boundary_.insert(half_key(a, b));
  }
}


std::vector<std::vector<uint32_t>> EditableSurface::trace_loops() const {
  const std::vector<uint64_t> bnd = boundary();
  std::vector<uint8_t> used(bnd.size(), 0);
  auto find_edge = [&](uint32_t a, uint32_t b) -> int64_t {
    auto it = std::lower_bound(bnd.begin(), bnd.end(), half_key(a, b));
    return it != bnd.end() && *it == half_key(a, b) ? it - bnd.begin() : -1;
  };
  // Next boundary edge after a -> b: leave b along the wedge that follows, counter-clockwise,
  // the gap where a -> b's triangle ends.
  auto next_edge = [&](uint32_t a, uint32_t b) -> int64_t {
    // b's boundary edges are a run of bnd (sorted by their first vertex): nearly always one
    // is left, and it is the next; only where the boundary passes b more than once do the
    // angles choose.
    size_t unused = 0, last = 0;
    for (auto i = size_t(std::lower_bound(bnd.begin(), bnd.end(), half_key(b, 0)) - bnd.begin());
         i < bnd.size() && uint32_t(bnd[i] >> 32) == b; ++i)
      if (!used[i]) ++unused, last = i;
    if (unused < 2) return unused == 0 ? -1 : int64_t(last);
    const double gap = angle_of(frame_[b], P_[a] - P_[b]);
    double best = INFINITY;
    int64_t best_e = -1;
    for_each_tri(b, [&](uint32_t t) {
      const Triangle& T = tris_[t];
      const uint32_t s = T[(corner_of(T, b) + 1) % 3];
      const int64_t e = find_edge(b, s);
      if (e < 0 || used[size_t(e)]) return;
      double d = angle_of(frame_[b], P_[s] - P_[b]) - gap;
      while (d < 0) d += kTwoPi;
      while (d >= kTwoPi) d -= kTwoPi;
      if (d < best) {
        best = d;
        best_e = e;
      }
    });
    return best_e;
  };
  std::vector<std::vector<uint32_t>> loops;
  // Where each vertex stands in the path being traced (a vertex is there at most once: a
  // repeat is cut off at once), so that a repeat is found without searching the path: a
  // depth camera's frame has loops of tens of thousands of edges.
  constexpr uint32_t kAbsent = 0xffffffffu;
  std::vector<uint32_t> at(P_.size(), kAbsent);
  for (size_t start = 0; start < bnd.size(); ++start) {
    if (used[start]) continue;
    std::vector<uint32_t> path;
    int64_t e = int64_t(start);
    while (e >= 0 && !used[size_t(e)]) {
      used[size_t(e)] = 1;
      const uint32_t a = uint32_t(bnd[size_t(e)] >> 32), b = uint32_t(bnd[size_t(e)]);
      // Split at a repeated vertex: the part since its last visit is a loop of its own.
      if (at[a] != kAbsent) {
        const auto it = path.begin() + ptrdiff_t(at[a]);
        for (auto v = it; v != path.end(); ++v) at[*v] = kAbsent;
        loops.emplace_back(it, path.end());
        path.erase(it, path.end());
      }
      at[a] = uint32_t(path.size());
      path.push_back(a);
      if (b == path.front()) break;
      e = next_edge(a, b);
    }
    for (uint32_t v : path) at[v] = kAbsent;
    if (path.size() >= 3) loops.push_back(std::move(path));
  }
  for (auto& l : loops) std::rotate(l.begin(), std::min_element(l.begin(), l.end()), l.end());
  std::sort(loops.begin(), loops.end());
  return loops;
}

void EditableSurface::surface_pieces(std::vector<uint32_t>& piece, std::vector<uint32_t>& triangles) const {
  const size_t n = P_.size();
  piece.resize(n);
  std::iota(piece.begin(), piece.end(), 0u);
  // Union-find over the triangles in parallel (a serial pass was ~30 ms of a 1M-point run on
  // one core, called by the repair and the hole filling): a root is linked under the other,
  // smaller root by a compare-and-swap that fails if it stopped being a root meanwhile, and
  // finds halve their paths (each slot only ever moves to an ancestor, which is smaller). So
  // every set's root is its lowest vertex, whatever order the links came in: the same pieces,
  // named the same, for any thread count.
  const auto at = [&](uint32_t x) { return std::atomic_ref<uint32_t>(piece[x]); };
  const auto find = [&](uint32_t x) {
    for (;;) {
      const uint32_t p = at(x).load(std::memory_order_relaxed);
      if (p == x) return x;
      const uint32_t g = at(p).load(std::memory_order_relaxed);
      if (g != p) at(x).store(g, std::memory_order_relaxed);
      x = g;
    }
  };
  parallel_blocks(tris_.size(), 8192, [&](size_t b, size_t e) {
    for (size_t t = b; t < e; ++t) {
      if (!alive_[t]) continue;
      for (int k = 1; k < 3; ++k) {
        uint32_t a = tris_[t][0], c = tris_[t][k];
        for (;;) {
          a = find(a), c = find(c);
          if (a == c) break;
          if (a < c) std::swap(a, c);  // link the larger root a under c
          uint32_t expected = a;
          if (at(a).compare_exchange_strong(expected, c, std::memory_order_relaxed)) break;
        }
      }
    }
  });
  parallel_blocks(n, 8192, [&](size_t b, size_t e) {
    for (size_t v = b; v < e; ++v) at(uint32_t(v)).store(find(uint32_t(v)), std::memory_order_relaxed);
  });
  triangles.assign(n, 0);
  for (uint32_t t = 0; t < tris_.size(); ++t)
    if (alive_[t]) ++triangles[piece[tris_[t][0]]];
}

std::vector<Triangle> EditableSurface::take() const {
  // The live triangles in order: counted per fixed block, then each block's written at its
  // offset, in parallel (two million triangles copied on one core were a visible serial step).
  constexpr size_t kBlock = 65536;
  const size_t m = tris_.size(), blocks = (m + kBlock - 1) / kBlock;
  std::vector<size_t> at(blocks + 1, 0);
  parallel_blocks(blocks, 1, [&](size_t bb, size_t be) {
    for (size_t b = bb; b < be; ++b)
      for (size_t t = b * kBlock; t < std::min(m, (b + 1) * kBlock); ++t) at[b + 1] += alive_[t] != 0;
  });
  std::partial_sum(at.begin(), at.end(), at.begin());
  std::vector<Triangle> out;
  resize_touched(out, at[blocks]);
  parallel_blocks(blocks, 1, [&](size_t bb, size_t be) {
    for (size_t b = bb; b < be; ++b) {
      size_t k = at[b];
      for (size_t t = b * kBlock; t < std::min(m, (b + 1) * kBlock); ++t)
        if (alive_[t]) out[k++] = tris_[t];
    }
  });
  return out;
}

std::vector<uint64_t> EditableSurface::boundary() const {
  std::vector<uint64_t> b;
  b.reserve(boundary_.size());
  for (const uint64_t e : boundary_) b.push_back(e);
  std::sort(b.begin(), b.end());
  return b;
}

}  // namespace particlemesh::detail
