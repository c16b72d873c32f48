#include "surface/surface_builder.h"

#include <algorithm>
#include <atomic>
#include <bit>
#include <chrono>
#include <cmath>
#include <cstring>
#include <functional>
#include <limits>
#include <memory>
#include <numbers>
#include <numeric>
#include <unordered_map>
#include <unordered_set>


#include "core/counting_sort.h"
#include "core/parallel.h"
#include "particlemesh/core/error.h"
#include "particlemesh/spatial/neighbor_grid.h"

namespace particlemesh::detail {

namespace {

constexpr double kTwoPi = 4.0;     // the period of angle_of's pseudo-angles
constexpr float kArcEps = 1e-5f;  // in pseudo-angle units (about 1.5e-5 rad); arcs are floats

struct Frame {
  Vec3 u, w;
};

Frame tangent_frame(const Vec3& n) {
  const Vec3 axis = std::abs(n.x) < 0.57 ? Vec3{1, 0, 0} : (std::abs(n.y) < 0.57 ? Vec3{0, 1, 0} : Vec3{0, 0, 1});
  const Vec3 u = normalized(cross(n, axis));
  return {u, cross(n, u)};
}

/// The direction of d around the normal as a pseudo-angle in [0, 4): monotonic in the true
/// angle (counter-clockwise from u) but with no trigonometry; the wedge tests only compare
/// and order angles, so any order-preserving measure with a fixed period serves.
double angle_of(const Frame& f, const Vec3& d) {
  const double x = dot(d, f.u), y = dot(d, f.w);
  const double s = std::abs(x) + std::abs(y);
  if (!(s > 0)) return 0;
  const double r = y / s;
  return x >= 0 ? (r >= 0 ? r : 4 + r) : 2 - r;
}

/// A counter-clockwise arc (about the vertex normal) of a triangle's corner.
struct Arc {
  float start, length;
};

/// An allocator whose resize leaves trivial elements uninitialised: the corner lists (150 MB
/// at 1M points) are then first touched by the parallel pass that fills them, not zeroed
/// by a serial one before.
template <class T>
struct UninitAllocator : std::allocator<T> {
  template <class U>
  struct rebind {
    using other = UninitAllocator<U>;
  };
  template <class U, class... Args>
  void construct(U* p, Args&&... args) {
    if constexpr (sizeof...(Args) == 0) ::new (static_cast<void*>(p)) U;
    else ::new (static_cast<void*>(p)) U(std::forward<Args>(args)...);
  }
};

Arc make_arc(const Frame& f, const Vec3& v, const Vec3& succ, const Vec3& pred) {
  const double a = angle_of(f, succ - v), b = angle_of(f, pred - v);
  double len = b - a;
  if (len < 0) len += kTwoPi;
  return {float(a), float(len)};
}

bool arcs_overlap(const Arc& a, const Arc& b) {
  float d = b.start - a.start;
  if (d < 0) d += float(kTwoPi);
  if (d >= float(kTwoPi)) d -= float(kTwoPi);
  return d < a.length - kArcEps || d + b.length > float(kTwoPi) + kArcEps;
}

/// The cosine of a triangle's largest angle (the smallest of its corners' cosines): the same
/// order as the largest angle, without the arc-cosines.
/// The cosine of the triangle (p, q, r)'s angle at p.
double corner_cosine(const Vec3& p, const Vec3& q, const Vec3& r) {
  const Vec3 u = q - p, v = r - p;
  return dot(u, v) / std::sqrt(squared_norm(u) * squared_norm(v));
}

double min_corner_cosine(const Vec3& a, const Vec3& b, const Vec3& c) {
  return std::min({corner_cosine(a, b, c), corner_cosine(b, c, a), corner_cosine(c, a, b)});
}

double max_angle(const Vec3& a, const Vec3& b, const Vec3& c) {
  auto ang = [](const Vec3& p, const Vec3& q, const Vec3& r) { return std::acos(std::clamp(corner_cosine(p, q, r), -1.0, 1.0)); };
  return std::max({ang(a, b, c), ang(b, c, a), ang(c, a, b)});
}

/// A set of ranks in [0, n), taken smallest first: a 64-ary tree of bit words, so that adding
/// and taking touch one word per level (4 levels for 16M ranks). Written here because the
/// growth's binary heap held up to a fifth of all candidates (the poor ones wait until the end)
/// and its sifts were the growth's largest cost; no standard container does this.
class RankQueue {
 public:
  explicit RankQueue(size_t n) {
    size_t m = n;
    do {
      m = std::max<size_t>(1, (m + 63) / 64);
      levels_.emplace_back(m, 0);
    } while (m > 1);
  }
  bool empty() const { return levels_.back()[0] == 0; }
  void push(uint32_t r) {
    for (auto& level : levels_) {
      uint64_t& w = level[r >> 6];
      const bool had = w != 0;  // then the levels above already know of this word
      w |= uint64_t(1) << (r & 63);
      if (had) return;
      r >>= 6;
    }
  }
  /// The smallest rank, left in place. Not empty.
  uint32_t top() const {
    uint64_t r = 0;
    for (size_t l = levels_.size(); l-- > 0;) r = (r << 6) | uint64_t(std::countr_zero(levels_[l][r]));
    return uint32_t(r);
  }
  /// The smallest rank, removed. Not empty.
  uint32_t pop() {
    const uint32_t r = top();
    for (uint32_t x = r; auto& level : levels_) {
      uint64_t& w = level[x >> 6];
      w &= ~(uint64_t(1) << (x & 63));
      if (w != 0) break;
      x >>= 6;
    }
    return r;
  }

 private:
  std::vector<std::vector<uint64_t>> levels_;  // [0] holds one bit per rank
};

/// Sorts keys whose low words already ascend by their high words, stably: three counting
/// passes of 11 bits (a pass where every key has the same digit is skipped). Linear, where a
/// comparison sort of the 2.5M candidates of 1M points took 80-120 ms; TBB and the standard
/// library have no radix sort.
void sort_by_high_word(std::vector<uint64_t>& key) {
  std::vector<uint64_t> tmp(key.size());
  for (int shift = 32; shift < 64; shift += 11) {
    const std::vector<size_t> start = counting_place(
        key.size(), 2048, [&](size_t i) { return (key[i] >> shift) & 2047; },
        [&](size_t i, size_t pos) { tmp[pos] = key[i]; }, true);
    if (!one_bucket(start, key.size())) key.swap(tmp);  // else nothing was placed, and the order stands
  }
}

/// acos(x) for x in [-1, 1] within 2e-8 rad (Abramowitz and Stegun 4.4.46): the corner
/// angles that weight the vertex normals, where std::acos took half the time of that stage.
double fast_acos(double x) {
  const double a = std::min(std::abs(x), 1.0);
  const double r = std::sqrt(1.0 - a) *
                   (1.5707963050 + a * (-0.2145988016 + a * (0.0889789874 + a * (-0.0501743046 + a * (0.0308918810 +
                    a * (-0.0170881256 + a * (0.0066700901 + a * -0.0012624911)))))));
  return x >= 0 ? r : std::numbers::pi - r;
}

/// A float's bits, turned so that they order as the float does (-0 taken as +0, so that equal
/// qualities tie on what follows them in a key).
uint32_t sortable_bits(float f) {
  f += 0.0f;
  uint32_t bits;
  std::memcpy(&bits, &f, sizeof bits);
  return (bits & 0x80000000u) ? ~bits : (bits | 0x80000000u);
}

int corner_of(const Triangle& t, uint32_t v) { return t[0] == v ? 0 : (t[1] == v ? 1 : 2); }

class Builder {
 public:
  Builder(const std::vector<Vec3>& P, const std::vector<Vec3>& N, const std::vector<uint8_t>& active,
          const BuilderOptions& o, BuilderStats& stats, ProgressTracker& tracker)
      : P_(P), N_(N), active_(active), o_(o), stats_(stats), tracker_(tracker), frame_(P.size()) {
    detail::parallel_blocks(P.size(), 4096, [&](size_t b, size_t e) {
      for (size_t i = b; i < e; ++i)
        if (squared_norm(N_[i]) > 0) frame_[i] = tangent_frame(N_[i]);
    });
  }

  // ---- candidates ------------------------------------------------------------------------

  void add_candidates(const std::vector<Triangle>& raw) {
    // Per raw triangle: kept or not, turned or not (to face along its normals), its quality.
    // Eight bytes, not a copy of the triangle: the list is as long as the raw test's output.
    struct Oriented {
      float quality;
      uint8_t ok, turned;
    };
    std::vector<Oriented> o(raw.size());
    auto oriented = [&](size_t i) {
      Triangle t = raw[i];
      if (o[i].turned) std::swap(t[1], t[2]);
      return t;
    };
    // Corners agree with each other within the co-normality angle (above 90 degrees: a sharp
    // crease's sides, up to 180 - angle of dihedral); the face agrees with every corner within
    // that angle and never beyond 90 degrees (a face turned away from a corner's normal is
    // not the surface there).
    const double cosa = o_.cos_normal_angle, cosf = std::max(cosa, 0.0);
    const size_t n = P_.size();
    vc_off_.assign(n + 1, 0);  // each vertex's corners, counted here
    std::atomic<size_t> kept_sum{0};
    detail::parallel_blocks(raw.size(), 4096, [&](size_t b, size_t e) {
      size_t block_kept = 0;
      for (size_t i = b; i < e; ++i) {
        Triangle t = raw[i];
        o[i].ok = o[i].turned = 0;
        if (!active_[t[0]] || !active_[t[1]] || !active_[t[2]]) continue;
        const Vec3 &na = N_[t[0]], &nb = N_[t[1]], &nc = N_[t[2]];
        if (!(squared_norm(na) > 0 && squared_norm(nb) > 0 && squared_norm(nc) > 0)) continue;
        Vec3 f = cross(P_[t[1]] - P_[t[0]], P_[t[2]] - P_[t[0]]);
        const bool turned = dot(f, na + nb + nc) < 0;
        if (turned) {
          std::swap(t[1], t[2]);
          f = -f;
        }
        const Vec3 fu = normalized(f);
        // Co-normality (seed 5.2.4): corners agree with each other and with the face.
        if (dot(na, nb) < cosa || dot(nb, nc) < cosa || dot(na, nc) < cosa) continue;
        if (dot(fu, na) < cosf || dot(fu, nb) < cosf || dot(fu, nc) < cosf) continue;
        o[i].quality = float(-min_corner_cosine(P_[t[0]], P_[t[1]], P_[t[2]]));  // ~ the largest angle
        o[i].ok = 1;
        o[i].turned = turned;
        ++block_kept;
        for (uint32_t v : t) std::atomic_ref<uint32_t>(vc_off_[v + 1]).fetch_add(1, std::memory_order_relaxed);
      }
      kept_sum.fetch_add(block_kept, std::memory_order_relaxed);
    });
    tracker_.check();
    const size_t kept = kept_sum.load();
    stats_.rejected_conormal = raw.size() - kept;
    stats_.candidates = kept;
    // Best first: the smallest largest angle (the Delaunay diagonal of a quad beats the
    // overlapping obtuse triangle), then the raw order (sorted indices) - deterministic.
    // Sorted as (quality, index) keys: a float's bits, with the sign folded, order as the float.
    std::vector<uint64_t> key(kept);
    counting_place(o.size(), 2, [&](size_t i) { return o[i].ok ? 0 : 1; }, [&](size_t i, size_t pos) {
      if (o[i].ok) key[pos] = (uint64_t(sortable_bits(o[i].quality)) << 32) | i;
    });
    sort_by_high_word(key);
    // The quality order puts the flat candidates last.
    flat_from_ = uint32_t(std::partition_point(key.begin(), key.end(), [](uint64_t k) {
                            return uint32_t(k >> 32) <= sortable_bits(kFlatQuality);
                          }) - key.begin());
    tracker_.check();
    cand_.resize(kept);
    state_.assign(kept, kOpen);
    detail::parallel_blocks(kept, 8192, [&](size_t b, size_t e) {
      for (size_t c = b; c < e; ++c) cand_[c] = oriented(uint32_t(key[c]));
    });
    tracker_.check();
    // Vertex -> its corners, with their arcs. Counted (above) and placed in parallel: a corner's slot comes
    // from its vertex's atomic cursor, so the order within a list depends on the threads. No
    // result does: growth reads a list as a set (check() and the edge scan answer the same in
    // any order, and the front is a set of ranks), the boundary is sorted and the triangles
    // are put in order explicitly. Placed in the raw order, not the candidate order: raw
    // triangles come vertex by vertex, so neighbouring writes land near each other (in quality
    // order they scatter over the whole list: 3x slower at 1M points).
    std::vector<uint32_t> rank(o.size());
    detail::parallel_blocks(kept, 8192, [&](size_t b, size_t e) {
      for (size_t c = b; c < e; ++c) rank[uint32_t(key[c])] = uint32_t(c);
    });
    std::vector<uint64_t>().swap(key);
    std::partial_sum(vc_off_.begin(), vc_off_.end(), vc_off_.begin());
    vc_.resize(vc_off_[n]);
    std::vector<uint32_t> fill(vc_off_.begin(), vc_off_.end() - 1);
    detail::parallel_blocks(o.size(), 8192, [&](size_t b, size_t e) {
      for (size_t i = b; i < e; ++i) {
        if (!o[i].ok) continue;
        const Triangle t = oriented(i);
        for (int k = 0; k < 3; ++k) {
          const uint32_t v = t[k], succ = t[(k + 1) % 3], pred = t[(k + 2) % 3];
          const uint32_t slot = std::atomic_ref<uint32_t>(fill[v]).fetch_add(1, std::memory_order_relaxed);
          vc_[slot] = {rank[i], succ, pred, make_arc(frame_[v], P_[v], P_[succ], P_[pred])};
        }
      }
    });
    tracker_.check();
    acc_count_.assign(n, 0);
  }

  // ---- growth ----------------------------------------------------------------------------

  enum : uint8_t { kOpen = 0, kAccepted = 1, kDead = 2 };
  enum Check { kOk = 0, kPinch = 1, kInvalid = 2 };

  /// Candidates are named by ids: their ranks, or in a block's growth their positions in the
  /// block's own list (see grow()).
  struct Region;

  Check check(uint32_t c, const Region& r) const {
    if (r.state[c] != kOpen) return kInvalid;
    const Triangle& C = r.cand[c];
    bool pinch = false;
    for (int k = 0; k < 3; ++k) {
      const uint32_t v = C[k];
      if (acc_count_[v] == 0) continue;
      const uint32_t accepted_end = vc_off_[v] + acc_count_[v];
      uint32_t own = accepted_end;
      while (vc_[own].c != c) ++own;  // c is open: after the accepted corners
      const Corner& mine = vc_[own];
      bool adjacent = false;
      for (uint32_t i = vc_off_[v]; i < accepted_end; ++i) {
        const Corner& t = vc_[i];  // accepted (they lead v's list)
        if (t.succ == mine.succ || t.pred == mine.pred) return kInvalid;  // a directed edge is taken
        if (arcs_overlap(t.arc, mine.arc)) return kInvalid;
        if (t.pred == mine.succ || t.succ == mine.pred) adjacent = true;
      }
      if (!adjacent) pinch = true;
    }
    return pinch ? kPinch : kOk;
  }

  /// f(candidate, whether it holds b -> a) for each candidate on the edge {a, b}.
  template <class F>
  void for_each_candidate_on_edge(uint32_t a, uint32_t b, F&& f) const {
    if (vc_off_[a + 1] - vc_off_[a] <= vc_off_[b + 1] - vc_off_[b]) {
      for (uint32_t i = vc_off_[a]; i < vc_off_[a + 1]; ++i) {
        const Corner& x = vc_[i];
        if (x.succ == b || x.pred == b) f(x.c, x.pred == b);
      }
    } else {
      for (uint32_t i = vc_off_[b]; i < vc_off_[b + 1]; ++i) {
        const Corner& x = vc_[i];
        if (x.succ == a || x.pred == a) f(x.c, x.succ == a);
      }
    }
  }

  /// Where growth runs (see grow()): one block, on its own candidates, or the seams pass, on
  /// all of them. Ids are [0, count) and order as ranks do.
  struct Region {
    const Triangle* cand = nullptr;   ///< by id
    uint8_t* state = nullptr;         ///< by id
    size_t count = 0;
    bool block = false;  ///< ids are the block's; corners of other candidates carry kOther
    const std::vector<uint32_t>* seed_from = nullptr;  ///< the ids that may seed it, ascending (null: all)
    size_t grown = 0, seeds = 0;
  };
  /// In a block's growth, the corners of candidates it does not take carry this bit.
  static constexpr uint32_t kOther = 0x80000000u;

  /// Blocks are equal runs of points: v * blocks / n, by a multiply and a shift.
  uint32_t block_of(uint32_t v) const { return uint32_t((uint64_t(v) * block_scale_) >> 32); }

  /// Does the growth of block `blk` take candidate c, with corners a, b, d? All three in the
  /// block; if it is flat, all three inner (see grow()).
  bool block_takes(uint32_t blk, uint32_t c, uint32_t a, uint32_t b, uint32_t d) const {
    return block_of(a) == blk && block_of(b) == blk && block_of(d) == blk &&
           (c < flat_from_ || (inner_[a] && inner_[b] && inner_[d]));
  }

  void accept(uint32_t c, RankQueue& heap, Region& r) {
    r.state[c] = kAccepted;
    const Triangle& C = r.cand[c];
    // Keep each vertex's accepted candidates at the front of its list, so that check() reads
    // only those (the result does not depend on the order it reads them in).
    for (uint32_t v : C) {
      const uint32_t front = vc_off_[v] + acc_count_[v];
      uint32_t i = front;
      while (vc_[i].c != c) ++i;
      std::swap(vc_[i], vc_[front]);
      ++acc_count_[v];
    }
    ++r.grown;
    // Candidates across each edge, wound the other way, join the front. A block leaves the
    // candidates it does not take to the seams pass (another block's thread may own them).
    for (int k = 0; k < 3; ++k) {
      const uint32_t a = C[k], b = C[(k + 1) % 3];
      for_each_candidate_on_edge(a, b, [&](uint32_t t, bool b_to_a) {
        if (r.block && (t & kOther)) return;
        if (r.state[t] != kOpen) return;
        if (!b_to_a) r.state[t] = kDead;  // T holds a -> b: can never be used
        else heap.push(t);
      });
    }
  }

  /// Best-first growth of a region from the front in `heap`: the front first, then the
  /// candidates that would pinch, then a new seed on untouched points. The seams pass takes no
  /// flat candidate when there are several blocks (see grow()), and last gives points that no
  /// region reached a triangle, even at the cost of a pinch.
  void grow_region(Region& r, RankQueue& heap, bool flat_ok) {
    RankQueue deferred(r.count);
    size_t seed_ptr = 0, touch_ptr = 0, since_tick = 0;
    const size_t seeds = r.seed_from ? r.seed_from->size() : r.count;
    std::vector<uint32_t> touch;  // the candidates at points no region reached, ascending
    bool touch_listed = false;
    while (true) {
      if (++since_tick == 4096) {
        tracker_.tick(4096);
        since_tick = 0;
        if (tracker_.cancelled()) return;
      }
      if (!heap.empty()) {
        const uint32_t c = heap.pop();
        if (!heap.empty()) {  // likely the next one: load it while this one is checked
          const uint32_t next = heap.top();
          __builtin_prefetch(&r.cand[next]);
          __builtin_prefetch(&r.state[next]);
        }
        const Check k = !flat_ok && c >= flat_from_ ? kInvalid : check(c, r);
        if (k == kOk) accept(c, heap, r);
        else if (k == kPinch) deferred.push(c);
        else if (r.state[c] == kOpen) r.state[c] = kDead;
        continue;
      }
      if (!deferred.empty()) {
        const uint32_t c = deferred.pop();
        if (check(c, r) != kInvalid) accept(c, heap, r);
        continue;
      }
      bool seeded = false;
      for (; seed_ptr < seeds; ++seed_ptr) {
        const uint32_t c = r.seed_from ? (*r.seed_from)[seed_ptr] : uint32_t(seed_ptr);
        const Triangle& C = r.cand[c];
        if (r.state[c] == kOpen && acc_count_[C[0]] == 0 && acc_count_[C[1]] == 0 && acc_count_[C[2]] == 0) {
          accept(c, heap, r);
          ++r.seeds;
          seeded = true;
          break;
        }
      }
      if (seeded) continue;
      if (r.block) break;
      if (!touch_listed) {
        touch = candidates_at_untouched_points();
        touch_listed = true;
      }
      for (; touch_ptr < touch.size(); ++touch_ptr) {
        const uint32_t c = touch[touch_ptr];
        const Triangle& C = r.cand[c];
        if (acc_count_[C[0]] && acc_count_[C[1]] && acc_count_[C[2]]) continue;
        if (check(c, r) != kInvalid) {
          accept(c, heap, r);
          seeded = true;
          break;
        }
      }
      if (!seeded) break;
    }
  }

  /// The candidates (ascending) with a corner at a point that no accepted triangle touches:
  /// the only ones the last step of growth looks at.
  std::vector<uint32_t> candidates_at_untouched_points() const {
    std::vector<uint32_t> out;
    for (uint32_t v = 0; v < P_.size(); ++v)
      if (acc_count_[v] == 0)
        for (uint32_t i = vc_off_[v]; i < vc_off_[v + 1]; ++i) out.push_back(vc_[i].c);
    std::sort(out.begin(), out.end());
    out.erase(std::unique(out.begin(), out.end()), out.end());
    return out;
  }

  /// inner_: the points with no candidate path of up to two edges into another block.
  void mark_inner_points() {
    const size_t n = P_.size();
    inner_.assign(n, 1);
    for (int ring = 0; ring < 2; ++ring) {
      std::vector<uint8_t> next(n);
      detail::parallel_blocks(n, 8192, [&](size_t b, size_t e) {
        for (size_t v = b; v < e; ++v) {
          const uint32_t blk = block_of(uint32_t(v));
          bool in = inner_[v];
          for (uint32_t i = vc_off_[v]; i < vc_off_[v + 1] && in; ++i) {
            const Corner& x = vc_[i];
            in = block_of(x.succ) == blk && block_of(x.pred) == blk && inner_[x.succ] && inner_[x.pred];
          }
          next[v] = in;
        }
      });
      inner_.swap(next);
    }
  }

  /// Growth in two passes. First in blocks of points (runs of sorted indices, so slabs of grid
  /// cells), in parallel, each on the candidates within it: serial growth was the largest cost
  /// of the finishing stages (0.75 s of 2.1 s at 1M points). The block size depends on the
  /// point count only, so the surface is the same for any thread count, and a cloud of one
  /// block grows exactly as one region always did. Then one serial pass grows across the seams
  /// between blocks, from the candidates there that continue a grown triangle.
  ///
  /// Flat candidates (largest angle over 150 degrees: nearly collinear particles) need care.
  /// Where growth stops at a fixed line (a block's edge) or two fronts meet head-on (a seam),
  /// the gap left along a row of particles is just a flat triangle's, and the flat ones taken
  /// there tilted vertex normals by up to 30 degrees (75 vertices of the 100k Fibonacci sphere,
  /// where serial growth took no flat triangle at all). So a block takes a flat candidate only
  /// two rings inside it, and the seams pass takes none: those gaps close as small holes,
  /// which the repair fills.
  ///
  /// A block works on its own copy of its candidates and their states, by their positions in
  /// its list (the corner lists say so for the time), not on the ranks: the candidates it
  /// reads are then together in memory, not spread over the whole list in quality order.
  void grow() {
    tracker_.stage("extracting the surface", 0.7, 0.85, cand_.size());
    const size_t n = P_.size(), m = cand_.size();
    if (m >= kOther) throw Error(Status::LimitExceeded, "more than 2^31 candidate triangles");
    const size_t blocks = std::clamp<size_t>(n / kMinBlockPoints, 1, kMaxBlocks);
    block_scale_ = ((uint64_t(blocks) << 32) - 1) / n;
    mark_inner_points();
    // Each block's candidates, in rank order, and the rest (the seams'), in rank order: the
    // seams' list is one more bucket.
    std::vector<uint32_t> ids(m);
    std::vector<uint32_t> local(m, kOther);  // a candidate's position in its block's list
    auto block_candidate = [&](size_t c) {
      const Triangle& C = cand_[c];
      const uint32_t b = block_of(C[0]);
      return block_takes(b, uint32_t(c), C[0], C[1], C[2]) ? b : uint32_t(blocks);
    };
    const std::vector<size_t> block_start =
        counting_place(m, blocks + 1, block_candidate, [&](size_t c, size_t pos) { ids[pos] = uint32_t(c); });
    detail::parallel_blocks(blocks, 1, [&](size_t bb, size_t be) {
      for (size_t b = bb; b < be; ++b)
        for (size_t pos = block_start[b]; pos < block_start[b + 1]; ++pos) local[ids[pos]] = uint32_t(pos - block_start[b]);
    });
    // The seams' candidates: the last list.
    const std::vector<uint32_t> seams(ids.begin() + block_start[blocks], ids.end());
    // The corner lists name the candidates by block positions (kOther for the seams').
    detail::parallel_blocks(n, 8192, [&](size_t b, size_t e) {
      for (uint32_t i = vc_off_[b]; i < vc_off_[e]; ++i) {
        const uint32_t c = vc_[i].c;
        vc_[i].c = local[c] == kOther ? c | kOther : local[c];
      }
    });
    std::vector<uint32_t>().swap(local);
    std::vector<size_t> grown(blocks, 0), seeds(blocks, 0);
    detail::parallel_blocks(blocks, 1, [&](size_t bb, size_t be) {
      for (size_t b = bb; b < be; ++b) {
        const uint32_t* id = ids.data() + block_start[b];
        const size_t count = block_start[b + 1] - block_start[b];
        std::vector<Triangle> cand(count);
        std::vector<uint8_t> state(count, kOpen);
        for (size_t i = 0; i < count; ++i) cand[i] = cand_[id[i]];
        Region r;
        r.cand = cand.data();
        r.state = state.data();
        r.count = count;
        r.block = true;
        RankQueue heap(count);
        grow_region(r, heap, true);
        for (size_t i = 0; i < count; ++i) state_[id[i]] = state[i];
        grown[b] = r.grown;
        seeds[b] = r.seeds;
      }
    });
    tracker_.check();
    // Back to ranks.
    detail::parallel_blocks(n, 8192, [&](size_t b, size_t e) {
      for (size_t v = b; v < e; ++v) {
        const uint32_t* id = ids.data() + block_start[block_of(uint32_t(v))];
        for (uint32_t i = vc_off_[v]; i < vc_off_[v + 1]; ++i) {
          Corner& x = vc_[i];
          x.c = (x.c & kOther) ? x.c & ~kOther : id[x.c];
        }
      }
    });
    std::vector<uint32_t>().swap(ids);
    // The seams pass starts from the candidates that continue a grown triangle: one of their
    // edges, reversed, is an accepted triangle's (what puts a candidate on the front). Only
    // seams' candidates on three untouched points can seed it: each block took every seed
    // within it, and points only get touched.
    std::vector<uint8_t> kind(seams.size(), 0);  // 1: on the front, 2: may seed
    detail::parallel_blocks(seams.size(), 4096, [&](size_t b, size_t e) {
      for (size_t i = b; i < e; ++i) {
        const Triangle& C = cand_[seams[i]];
        if (!acc_count_[C[0]] && !acc_count_[C[1]] && !acc_count_[C[2]]) kind[i] = 2;
        for (int k = 0; k < 3 && !kind[i]; ++k) {
          const uint32_t a = C[k], v = C[(k + 1) % 3];  // the edge a -> v; is v -> a taken?
          const Corner* x = vc_.data() + vc_off_[v];
          for (uint32_t j = 0; j < acc_count_[v]; ++j) kind[i] |= x[j].succ == a;
        }
      }
    });
    std::vector<uint32_t> seeds_left;
    RankQueue heap(m);
    for (size_t i = 0; i < seams.size(); ++i) {
      if (kind[i] == 1) heap.push(seams[i]);
      if (kind[i] == 2) seeds_left.push_back(seams[i]);
    }
    Region all;
    all.cand = cand_.data();
    all.state = state_.data();
    all.count = m;
    all.seed_from = &seeds_left;
    grow_region(all, heap, blocks == 1);
    tracker_.check();
    for (size_t b = 0; b < blocks; ++b) {
      stats_.grown += grown[b];
      stats_.seeds += seeds[b];
    }
    stats_.grown += all.grown;
    stats_.seeds += all.seeds;
    std::vector<Triangle>().swap(cand_);
    std::vector<uint8_t>().swap(state_);
    // The surface's triangles in space order: each at its lowest vertex (its first corner,
    // as raw triangles are (i < j < k) and orienting swaps the other two), in candidate order
    // there. The repair and the vertex normals then read triangles near each other in memory.
    // Gathered per fixed block of points, then joined in block order.
    const size_t block = 8192, nblocks = (n + block - 1) / block;
    std::vector<std::vector<Triangle>> part(nblocks);
    detail::parallel_blocks(nblocks, 1, [&](size_t bb, size_t be) {
      std::vector<Corner> mine;
      for (size_t blk = bb; blk < be; ++blk) {
        part[blk].reserve(2 * block);
        for (size_t v = blk * block; v < std::min(n, (blk + 1) * block); ++v) {
          const Corner* x = vc_.data() + vc_off_[v];
          mine.clear();
          for (uint32_t i = 0; i < acc_count_[v]; ++i)
            if (v < x[i].succ && v < x[i].pred) mine.push_back(x[i]);
          std::sort(mine.begin(), mine.end(), [](const Corner& p, const Corner& q) { return p.c < q.c; });
          for (const Corner& c : mine) part[blk].push_back({uint32_t(v), c.succ, c.pred});
        }
      }
    });
    std::vector<size_t> at(nblocks + 1, 0);
    for (size_t blk = 0; blk < nblocks; ++blk) at[blk + 1] = at[blk] + part[blk].size();
    tris_.resize(at[nblocks]);
    detail::parallel_blocks(nblocks, 1, [&](size_t bb, size_t be) {
      for (size_t blk = bb; blk < be; ++blk) {
        std::copy(part[blk].begin(), part[blk].end(), tris_.begin() + ptrdiff_t(at[blk]));
        std::vector<Triangle>().swap(part[blk]);
      }
    });
  }

  // ---- repair ----------------------------------------------------------------------------
  //
  // Works on the accepted triangles: vertex -> triangles as a CSR built once plus a small
  // overflow for triangles added later, and the set of boundary half-edges (a -> b with no
  // b -> a), kept up to date as triangles come and go, so that tracing loops and finding
  // pinched vertices look only at the boundary, not at the whole surface.

  template <class F>
  void for_each_tri(uint32_t v, F&& f) const {
    for (uint32_t i = vt_off_[v]; i < vt_off_[v + 1]; ++i)
      if (alive_[vt_[i]]) f(vt_[i]);
    if (has_extra_[v]) {
      auto it = extra_.find(v);
      if (it != extra_.end())
        for (uint32_t t : it->second)
          if (alive_[t]) f(t);
    }
  }

  Vec3 face_normal(const Triangle& T) const { return normalized(cross(P_[T[1]] - P_[T[0]], P_[T[2]] - P_[T[0]])); }

  bool directed_used(uint32_t a, uint32_t b) const {
    bool used = false;
    for_each_tri(a, [&](uint32_t t) {
      const Triangle& T = tris_[t];
      if (T[(corner_of(T, a) + 1) % 3] == b) used = true;
    });
    return used;
  }

  bool edge_exists(uint32_t a, uint32_t b) const { return directed_used(a, b) || directed_used(b, a); }

  static uint64_t half_key(uint32_t a, uint32_t b) { return (uint64_t(a) << 32) | b; }

  bool triangle_exists(uint32_t a, uint32_t b, uint32_t c) const {
    bool found = false;
    for_each_tri(a, [&](uint32_t t) {
      const Triangle& T = tris_[t];
      if ((T[0] == b || T[1] == b || T[2] == b) && (T[0] == c || T[1] == c || T[2] == c)) found = true;
    });
    return found;
  }

  /// The surface's index (vertex -> triangles, boundary half-edges) for the repair and the
  /// vertex normals, read off the growth's corner lists (which are then freed): a vertex's
  /// accepted corners lead its list, each with its triangle's other two corners.
  void index() {
    const size_t n = P_.size();
    alive_.assign(tris_.size(), 1);
    has_extra_.assign(n, 0);
    vt_off_.assign(n + 1, 0);
    detail::parallel_blocks(n, 8192, [&](size_t b, size_t e) {
      for (size_t v = b; v < e; ++v) vt_off_[v + 1] = acc_count_[v];
    });
    std::partial_sum(vt_off_.begin(), vt_off_.end(), vt_off_.begin());
    vt_.resize(vt_off_[n]);
    {
      std::vector<uint32_t> fill(vt_off_.begin(), vt_off_.end() - 1);
      for (uint32_t t = 0; t < tris_.size(); ++t)
        for (uint32_t v : tris_[t]) vt_[fill[v]++] = t;
    }
    tracker_.check();
    // Per vertex: its boundary half-edges v -> s (no accepted triangle holds s -> v, i.e. no
    // corner at v has s as its predecessor). Found in parallel and joined in block order.
    const size_t block = 8192, blocks = (n + block - 1) / block;
    std::vector<std::vector<uint64_t>> found(blocks);
    detail::parallel_blocks(blocks, 1, [&](size_t bb, size_t be) {
      for (size_t b = bb; b < be; ++b) {
        if (tracker_.cancelled()) return;
        tracker_.tick(0);  // on the calling thread: lets a cancel request in
        for (size_t v = b * block; v < std::min(n, (b + 1) * block); ++v) {
          const Corner* x = vc_.data() + vc_off_[v];
          const uint32_t m = acc_count_[v];
          for (uint32_t i = 0; i < m; ++i) {
            bool closed = false;
            for (uint32_t j = 0; j < m && !closed; ++j) closed = x[j].pred == x[i].succ;
            if (!closed) found[b].push_back(half_key(uint32_t(v), x[i].succ));
          }
        }
      }
    });
    tracker_.check();
    for (const auto& f : found) boundary_.insert(f.begin(), f.end());
    // Growth is over: free its structures.
    decltype(vc_)().swap(vc_);
    std::vector<uint32_t>().swap(vc_off_);
  }

  void add_triangle(const Triangle& T) {
    const uint32_t id = uint32_t(tris_.size());
    tris_.push_back(T);
    alive_.push_back(1);
    for (uint32_t v : T) {
      extra_[v].push_back(id);
      has_extra_[v] = 1;
    }
    for (int k = 0; k < 3; ++k) {
      const uint32_t a = T[k], b = T[(k + 1) % 3];
      if (!boundary_.erase(half_key(b, a))) boundary_.insert(half_key(a, b));
    }
  }

  void kill_triangle(uint32_t t) {
    alive_[t] = 0;
    const Triangle& T = tris_[t];
    for (int k = 0; k < 3; ++k) {
      const uint32_t a = T[k], b = T[(k + 1) % 3];
      if (!boundary_.erase(half_key(a, b))) boundary_.insert(half_key(b, a));
    }
  }

  /// Boundary loops, each a vertex sequence following the boundary edges v_i -> v_{i+1};
  /// loops through a vertex twice are split there. Sorted, each starting at its smallest
  /// vertex, so the repair is deterministic.
  std::vector<std::vector<uint32_t>> trace_loops() const {
    std::vector<uint64_t> bnd(boundary_.begin(), boundary_.end());
    std::sort(bnd.begin(), bnd.end());
    std::vector<uint8_t> used(bnd.size(), 0);
    auto find_edge = [&](uint32_t a, uint32_t b) -> int64_t {
      auto it = std::lower_bound(bnd.begin(), bnd.end(), half_key(a, b));
      return it != bnd.end() && *it == half_key(a, b) ? it - bnd.begin() : -1;
    };
    // Next boundary edge after a -> b: leave b along the wedge that follows, counter-clockwise,
    // the gap where a -> b's triangle ends.
    auto next_edge = [&](uint32_t a, uint32_t b) -> int64_t {
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
    for (size_t start = 0; start < bnd.size(); ++start) {
      if (used[start]) continue;
      std::vector<uint32_t> path;
      int64_t e = int64_t(start);
      while (e >= 0 && !used[size_t(e)]) {
        used[size_t(e)] = 1;
        const uint32_t a = uint32_t(bnd[size_t(e)] >> 32), b = uint32_t(bnd[size_t(e)]);
        // Split at a repeated vertex: the part since its last visit is a loop of its own.
        auto it = std::find(path.begin(), path.end(), a);
        if (it != path.end()) {
          loops.emplace_back(it, path.end());
          path.erase(it, path.end());
        }
        path.push_back(a);
        if (b == path.front()) break;
        e = next_edge(a, b);
      }
      if (path.size() >= 3) loops.push_back(std::move(path));
    }
    for (auto& l : loops) std::rotate(l.begin(), std::min_element(l.begin(), l.end()), l.end());
    std::sort(loops.begin(), loops.end());
    return loops;
  }

  /// Fill one loop, keeping the surface manifold: no edge that exists elsewhere may become a
  /// diagonal, edges stay within the fill limit. Small loops (wrong diagonals, sampling gaps)
  /// take the triangulation that minimises the largest angle; a loop is one gap at each of its
  /// vertices, so any such fill keeps every fan a disk. Larger loops take the one that
  /// minimises the largest dihedral angle, then the area (Liepa 2003), with no fold sharper
  /// than kMaxFillDihedral against each other or the surrounding surface, so the patch
  /// continues the surface instead of folding over it (`max_fold`, see fill_folded_loops for
  /// the larger one). Returns false (and adds nothing) when no such triangulation exists.
  static constexpr double kMaxFillDihedral = 2.4;     // radians, about 137 degrees
  static constexpr double kMaxCreaseDihedral = 2.8;   // radians, about 160 degrees
  bool fill_loop(const std::vector<uint32_t>& L, double max_fold = kMaxFillDihedral) {
    const size_t m = L.size();
    if (m < 3) return false;
    const double limit2 = std::pow(o_.fill_edge_factor * o_.max_edge, 2);
    const bool smooth = m > o_.small_hole;
    auto diag_ok = [&](size_t i, size_t j) {
      if ((j == i + 1) || (i == 0 && j == m - 1)) return true;
      return squared_distance(P_[L[i]], P_[L[j]]) <= limit2 && !edge_exists(L[i], L[j]);
    };
    // The surface's triangle across each loop edge L[i] -> L[i+1], for the dihedral angles.
    std::vector<Vec3> outside(m);
    for (size_t i = 0; i < m; ++i) {
        const uint32_t a = L[i], b = L[(i + 1) % m];
      for_each_tri(a, [&](uint32_t t) {
        const Triangle& T = tris_[t];
        if (T[(corner_of(T, a) + 1) % 3] == b)
          outside[i] = face_normal(T);
      });
    }
    auto bend = [](const Vec3& a, const Vec3& b) { return std::acos(std::clamp(dot(a, b), -1.0, 1.0)); };
    // (worst value, total) of the best triangulation of the chain i..k, and its apex.
    std::vector<double> worst(m * m, INFINITY), total(m * m, INFINITY);
    std::vector<uint32_t> apex(m * m, 0);
    for (size_t i = 0; i + 1 < m; ++i) worst[i * m + i + 1] = total[i * m + i + 1] = 0;
    auto chain_normal = [&](size_t i, size_t j) {
      return j == i + 1 ? outside[i] : face_normal({L[j], L[apex[i * m + j]], L[i]});  // the fill's (L[k], L[j], L[i])
    };
    for (size_t len = 2; len < m; ++len)
      for (size_t i = 0; i + len < m; ++i) {
        const size_t k = i + len;
        if (!diag_ok(i, k)) continue;
        for (size_t j = i + 1; j < k; ++j) {
          const double wl = worst[i * m + j], wr = worst[j * m + k];
          if (!std::isfinite(wl) || !std::isfinite(wr)) continue;
          const Vec3 f = cross(P_[L[j]] - P_[L[k]], P_[L[i]] - P_[L[k]]);
          const double area = 0.5 * norm(f);
          if (!(area > 0)) continue;
          if (m == 3 && triangle_exists(L[0], L[1], L[2])) continue;  // the loop of a lone triangle
          // The triangle's folds: against the surface across each loop edge it holds, for
          // every loop (the short outline of a small isolated patch is its outside, and
          // capping it would lay a reversed copy on the patch: a flat, closed pillow), and
          // for larger loops also against the fill triangles across its diagonals.
          const Vec3 nrm = f / (2 * area);
          double fold = 0;
          if (smooth || j == i + 1) fold = bend(nrm, chain_normal(i, j));
          if (smooth || k == j + 1) fold = std::max(fold, bend(nrm, chain_normal(j, k)));
          if (i == 0 && k == m - 1) fold = std::max(fold, bend(nrm, outside[m - 1]));
          if (fold > max_fold) continue;
          const double value = smooth ? fold : max_angle(P_[L[k]], P_[L[j]], P_[L[i]]);
          const double add = smooth ? area : value;
          const double w = std::max({wl, wr, value}), tt = total[i * m + j] + total[j * m + k] + add;
          if (w < worst[i * m + k] || (w == worst[i * m + k] && tt < total[i * m + k])) {
            worst[i * m + k] = w;
            total[i * m + k] = tt;
            apex[i * m + k] = uint32_t(j);
          }
        }
      }
    if (!std::isfinite(worst[m - 1])) return false;
    std::vector<std::pair<size_t, size_t>> todo{{0, m - 1}};
    std::vector<Triangle> added;
    while (!todo.empty()) {
      auto [i, k] = todo.back();
      todo.pop_back();
      if (k <= i + 1) continue;
      const size_t j = apex[i * m + k];
      added.push_back({L[k], L[j], L[i]});
      todo.push_back({i, j});
      todo.push_back({j, k});
    }
    for (const Triangle& T : added) add_triangle(T);
    ++stats_.holes_filled;
    stats_.hole_triangles += added.size();
    return true;
  }

  /// Fill every loop with at most `max_size` edges; returns how many were filled.
  size_t fill_loops(size_t max_size) {
    if (boundary_.empty()) return 0;
    size_t filled = 0;
    for (const auto& L : trace_loops())
      if (L.size() <= max_size && fill_loop(L)) ++filled;
    return filled;
  }

  /// The loops that fill_loops left for folding too sharply, filled with folds up to
  /// kMaxCreaseDihedral where the loop lies in a component of more than m^2 triangles (m: its
  /// edges). Sharp creases and corners need the sharper folds: a 60-degree wedge bends its
  /// surface by 120 degrees, and the holes where it meets another face, or where jitter
  /// tilted the triangles around a gap, had no fill within 137 degrees (one in four prisms of
  /// 45-75-degree wedges, and jittered resamplings of the rocker arm and the coarse bunny,
  /// were left open). The component rule keeps the 137-degree limit where it matters: a
  /// small isolated patch (a depth scan's flat rows) is a disk of about 0.18 m^2 triangles
  /// inside its outline m, and capping that outline lays a reversed copy on the patch.
  size_t fill_folded_loops(size_t max_size) {
    if (boundary_.empty()) return 0;
    std::vector<std::vector<uint32_t>> loops;
    for (auto& L : trace_loops())
      if (L.size() <= max_size) loops.push_back(std::move(L));
    if (loops.empty()) return 0;
    std::vector<uint32_t> piece, count;
    surface_pieces(piece, count);
    size_t filled = 0;
    for (const auto& L : loops) {
      const uint64_t m = L.size();
      if (count[piece[L[0]]] > m * m && fill_loop(L, kMaxCreaseDihedral)) ++filled;
    }
    return filled;
  }

  /// The pieces of the surface (triangles sharing a vertex are connected), by union-find:
  /// each vertex's piece, named by the piece's lowest vertex, and each piece's triangles,
  /// counted at that vertex.
  void surface_pieces(std::vector<uint32_t>& piece, std::vector<uint32_t>& triangles) const {
    const size_t n = P_.size();
    piece.resize(n);
    std::iota(piece.begin(), piece.end(), 0u);
    auto find = [&](uint32_t x) {
      while (piece[x] != x) x = piece[x] = piece[piece[x]];
      return x;
    };
    for (uint32_t t = 0; t < tris_.size(); ++t) {
      if (!alive_[t]) continue;
      for (int k = 1; k < 3; ++k) {
        const uint32_t a = find(tris_[t][0]), b = find(tris_[t][k]);
        if (a != b) piece[std::max(a, b)] = std::min(a, b);
      }
    }
    for (uint32_t v = 0; v < n; ++v) piece[v] = find(v);
    triangles.assign(n, 0);
    for (uint32_t t = 0; t < tris_.size(); ++t)
      if (alive_[t]) ++triangles[piece[tris_[t][0]]];
  }

  /// At vertices whose triangles form more than one fan, keep the largest fan. Such a vertex
  /// has a gap between its fans, so it starts two or more boundary edges: only those are checked.
  size_t unpinch() {
    std::vector<uint32_t> starts;
    for (uint64_t e : boundary_) starts.push_back(uint32_t(e >> 32));
    std::sort(starts.begin(), starts.end());
    std::vector<uint32_t> suspects;
    for (size_t i = 1; i < starts.size(); ++i)
      if (starts[i] == starts[i - 1]) suspects.push_back(starts[i]);
    // Fills and insertions are not held to the wedge rule: check their corners too.
    for (const auto& [v, list] : extra_) suspects.push_back(v);
    std::sort(suspects.begin(), suspects.end());
    suspects.erase(std::unique(suspects.begin(), suspects.end()), suspects.end());
    size_t removed_fans = 0;
    std::vector<uint32_t> ts, parent, size;
    for (uint32_t v : suspects) {
      ts.clear();
      for_each_tri(v, [&](uint32_t t) { ts.push_back(t); });
      if (ts.size() < 2) continue;
      parent.resize(ts.size());
      std::iota(parent.begin(), parent.end(), 0u);
      auto find = [&](uint32_t x) {
        while (parent[x] != x) x = parent[x] = parent[parent[x]];
        return x;
      };
      for (size_t i = 0; i < ts.size(); ++i)
        for (size_t j = i + 1; j < ts.size(); ++j) {
          const Triangle &A = tris_[ts[i]], &B = tris_[ts[j]];
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
        if (find(uint32_t(i)) != best) kill_triangle(ts[i]);
      removed_fans += fans - 1;
    }
    return removed_fans;
  }

  /// Does a boundary half-edge start at v (an edge v -> w of a triangle with no w -> v)?
  bool starts_boundary(uint32_t v) const {
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

  /// A particle the surface passed by is inserted into the surface triangle it lies over
  /// (split in three), or, at a boundary, joined to the nearest boundary edge: every input
  /// particle ends up a vertex of the surface.
  size_t insert_unused(const std::vector<Triangle>& raw) {
    std::vector<uint32_t> unused;
    for (uint32_t p = 0; p < P_.size(); ++p) {
      if (!active_[p]) continue;
      bool used = false;
      for_each_tri(p, [&](uint32_t) { used = true; });
      if (!used) unused.push_back(p);
    }
    if (unused.empty()) return 0;
    // The raw triangles at each unused particle tell which surface is around it.
    std::vector<std::vector<uint32_t>> around(unused.size());
    for (const Triangle& t : raw)
      for (int k = 0; k < 3; ++k) {
        auto it = std::lower_bound(unused.begin(), unused.end(), t[k]);
        if (it != unused.end() && *it == t[k])
          for (int q = 1; q < 3; ++q) around[size_t(it - unused.begin())].push_back(t[(k + q) % 3]);
      }
    std::unique_ptr<NeighborGrid> near;
    size_t inserted = 0;
    for (size_t u = 0; u < unused.size(); ++u) {
      const uint32_t p = unused[u];
      auto& nb = around[u];
      std::sort(nb.begin(), nb.end());
      nb.erase(std::unique(nb.begin(), nb.end()), nb.end());
      if (nb.empty()) {
        // In no raw triangle (fewer than two neighbours within L, e.g. at the rim of a real
        // opening): the surface near it can only be its boundary. Take the boundary vertices
        // within L as its neighbours.
        // A grid over the particles, built at the first such particle: scanning the whole
        // boundary per particle is quadratic on scans with many openings.
        if (!near) near = std::make_unique<NeighborGrid>(P_.data(), P_.size(), o_.max_edge);
        near->for_each_within(P_[p], o_.max_edge, [&](uint32_t s, double) {
          const uint32_t a = near->original_index(s);
          if (a != p && active_[a] && starts_boundary(a)) nb.push_back(a);
        });
        std::sort(nb.begin(), nb.end());
        nb.erase(std::unique(nb.begin(), nb.end()), nb.end());
      }
      double best = INFINITY;
      int64_t best_t = -1;
      for (uint32_t w : nb)
        for_each_tri(w, [&](uint32_t t) {
          const Triangle& T = tris_[t];
          const Vec3 a = P_[T[0]], b = P_[T[1]], c = P_[T[2]];
          const Vec3 n = cross(b - a, c - a);
          const double n2 = squared_norm(n);
          if (!(n2 > 0)) return;
          const Vec3 q = P_[p];
          const double la = dot(cross(c - b, q - b), n) / n2, lb = dot(cross(a - c, q - c), n) / n2;
          // Strictly inside: a particle on an edge goes to the edge split below, which keeps
          // every triangle non-degenerate.
          if (la < 1e-6 || lb < 1e-6 || 1 - la - lb < 1e-6) return;
          const double h = std::abs(dot(q - a, n)) / std::sqrt(n2);
          if (h < best) {
            best = h;
            best_t = t;
          }
        });
      if (best_t >= 0 && best <= o_.max_edge) {
        const Triangle T = tris_[size_t(best_t)];
        kill_triangle(uint32_t(best_t));
        add_triangle({T[0], T[1], p});
        add_triangle({T[1], T[2], p});
        add_triangle({T[2], T[0], p});
        ++inserted;
        continue;
      }
      // Else split the nearest edge a -> b at p: each triangle (a, b, c) on it becomes
      // (a, p, c) and (p, b, c). The fans stay disks and the windings agree. Edges whose split
      // would give a degenerate triangle (p in line with a corner: rows of a depth scan) are
      // passed over for the next nearest.
      std::vector<std::pair<double, std::pair<uint32_t, uint32_t>>> edges;
      for (uint32_t w : nb)
        for_each_tri(w, [&](uint32_t t) {
          for (int k = 0; k < 3; ++k) {
            const uint32_t a = tris_[t][k], b = tris_[t][(k + 1) % 3];
            const Vec3 ab = P_[b] - P_[a];
            const double u = std::clamp(dot(P_[p] - P_[a], ab) / squared_norm(ab), 0.0, 1.0);
            const double d = squared_distance(P_[p], P_[a] + ab * u);
            if (d <= o_.max_edge * o_.max_edge) edges.push_back({d, {std::min(a, b), std::max(a, b)}});
          }
        });
      std::sort(edges.begin(), edges.end());
      edges.erase(std::unique(edges.begin(), edges.end()), edges.end());
      auto proper = [&](uint32_t a, uint32_t b, uint32_t c) {
        const Vec3 u = P_[b] - P_[a], v = P_[c] - P_[a], w = P_[c] - P_[b];
        const double n2 = squared_norm(cross(u, v));
        const double l1 = squared_norm(u), l2 = squared_norm(v), l3 = squared_norm(w);
        const double lmax = std::max({l1, l2, l3}), lmid = l1 + l2 + l3 - lmax - std::min({l1, l2, l3});
        return n2 > 1e-20 * lmax * lmid;
      };
      for (const auto& [d, e] : edges) {
        // Plain variables, not a structured binding: the lambdas below capture them, which
        // clang before 16 (the sanitizer build's clang 14) does not allow.
        const uint32_t a = e.first, b = e.second;
        std::vector<uint32_t> on_edge;
        for_each_tri(a, [&](uint32_t t) {
          const Triangle& T = tris_[t];
          const int k = corner_of(T, a);
          if (T[(k + 1) % 3] == b || T[(k + 2) % 3] == b) on_edge.push_back(t);
        });
        bool ok = !on_edge.empty();
        for (uint32_t t : on_edge) {
          const Triangle& T = tris_[t];
          const uint32_t c = T[0] != a && T[0] != b ? T[0] : (T[1] != a && T[1] != b ? T[1] : T[2]);
          ok = ok && proper(a, p, c) && proper(p, b, c);
        }
        if (!ok) continue;
        for (uint32_t t : on_edge) {
          const Triangle T = tris_[t];
          const int k = corner_of(T, a);
          // Name the corners so the edge runs x -> y in T = (x, y, c).
          const bool forward = T[(k + 1) % 3] == b;
          const uint32_t x = forward ? a : b, y = forward ? b : a;
          const uint32_t c = T[(corner_of(T, x) + 2) % 3];
          kill_triangle(t);
          add_triangle({x, p, c});
          add_triangle({p, y, c});
        }
        ++inserted;
        break;
      }
    }
    return inserted;
  }

  /// Fragments of a few triangles that lie against a larger piece of surface (a lone triangle
  /// or a tiny closed "bubble" grown from particles the main surface passed by, where it is
  /// thin or sharp) are dissolved; insert_unused then puts their particles into the surface
  /// around them. A small piece on its own (a droplet of four particles) is a surface of its
  /// own and stays: a fragment is only dissolved if a raw triangle joins it to another piece.
  size_t drop_fragments(const std::vector<Triangle>& raw) {
    const size_t n = P_.size();
    std::vector<uint32_t> piece, count;
    surface_pieces(piece, count);
    std::vector<uint8_t> small(n, 0), touching(n, 0);
    bool any = false;
    for (uint32_t v = 0; v < n; ++v)
      if (piece[v] == v && count[v] > 0 && count[v] <= kMaxFragment) small[v] = any = true;
    if (!any) return 0;
    // A raw triangle with corners in a small piece and in another (used) piece joins them.
    for (const Triangle& t : raw) {
      const uint32_t r0 = piece[t[0]], r1 = piece[t[1]], r2 = piece[t[2]];
      for (uint32_t a : {r0, r1, r2})
        if (small[a])
          for (uint32_t b : {r0, r1, r2})
            if (b != a && count[b] > 0) touching[a] = 1;
    }
    size_t dropped = 0;
    for (uint32_t t = 0; t < tris_.size(); ++t) {
      if (!alive_[t]) continue;
      const uint32_t r = piece[tris_[t][0]];
      if (small[r] && touching[r]) {
        kill_triangle(t);
        ++dropped;
      }
    }
    return dropped;
  }
  static constexpr uint32_t kMaxFragment = 12;
  /// loop_width is cubic in the loop's edges: a 1400-edge opening of a scan took 2 s of a 2.4 s
  /// run. Above this the width is not computed (reported as infinite: such loops are openings).
  static constexpr size_t kMaxWidthLoop = 128;

  /// The smallest possible longest edge over all triangulations of a loop (a min-max DP), in
  /// units of L: how far apart the particles across the loop are.
  double loop_width(const std::vector<uint32_t>& L) const {
    const size_t m = L.size();
    std::vector<double> w(m * m, INFINITY);
    for (size_t i = 0; i + 1 < m; ++i) w[i * m + i + 1] = distance(P_[L[i]], P_[L[i + 1]]);
    for (size_t len = 2; len < m; ++len)
      for (size_t i = 0; i + len < m; ++i) {
        const size_t k = i + len;
        const double d = distance(P_[L[i]], P_[L[k]]);
        for (size_t j = i + 1; j < k; ++j) w[i * m + k] = std::min(w[i * m + k], std::max({w[i * m + j], w[j * m + k], d}));
      }
    return w[m - 1] / o_.max_edge;
  }

  void repair(const std::vector<Triangle>& raw) {
    tracker_.stage("repairing", 0.85, 0.97);
    // Small loops first (wrong diagonals, sampling gaps), then pinches, then larger loops.
    // A check between the steps: each is a pass over the whole mesh (up to a second at 1M
    // points), and a host's cancel request is only seen in a check (issue 9).
    fill_loops(o_.small_hole);
    tracker_.check();
    stats_.pinches_resolved += unpinch();
    tracker_.check();
    fill_loops(o_.small_hole);
    tracker_.check();
    if (o_.max_hole > o_.small_hole) fill_loops(o_.max_hole);
    tracker_.check();
    stats_.pinches_resolved += unpinch();
    tracker_.check();
    drop_fragments(raw);
    tracker_.check();
    if (insert_unused(raw) > 0) {
      tracker_.check();
      fill_loops(o_.small_hole);
      stats_.pinches_resolved += unpinch();
    }
    tracker_.check();
    if (o_.max_hole > 0 && fill_folded_loops(o_.max_hole) > 0) {
      tracker_.check();
      stats_.pinches_resolved += unpinch();
    }
    tracker_.check();
    if (!boundary_.empty()) {
      const auto left = trace_loops();
      stats_.holes_left = left.size();
      for (const auto& l : left) {
        stats_.largest_hole_left = std::max(stats_.largest_hole_left, l.size());
        if (stats_.open_loops.size() < 1000) stats_.open_loops.push_back({l.size(), l.size() <= kMaxWidthLoop ? loop_width(l) : INFINITY});
      }
    }
  }

  /// The surface's angle-weighted vertex normals; points in no triangle keep `fallback`. Per
  /// vertex in parallel, over its triangles in triangle order: the sums (so the bits) of a
  /// serial pass over the final triangles, for any thread count. Counts the active points in
  /// no triangle into `unused`.
  std::vector<Vec3> vertex_normals(const std::vector<Vec3>& fallback, size_t& unused) const {
    std::vector<Vec3> out(P_.size());
    std::atomic<size_t> none{0};
    detail::parallel_blocks(P_.size(), 4096, [&](size_t b, size_t e) {
      size_t block_none = 0;
      for (size_t v = b; v < e; ++v) {
        Vec3 sum, widest;
        double weight = 0, widest_angle = 0;
        bool any = false;
        for_each_tri(uint32_t(v), [&](uint32_t t) {
          any = true;
          const Triangle& T = tris_[t];
          const int k = corner_of(T, uint32_t(v));
          const Vec3 f = face_normal(T);
          const double angle = fast_acos(corner_cosine(P_[v], P_[T[(k + 1) % 3]], P_[T[(k + 2) % 3]]));
          if (!(angle > 0) || !(squared_norm(f) > 0)) return;  // a degenerate triangle
          sum += f * angle;
          weight += angle;
          if (angle > widest_angle) {
            widest_angle = angle;
            widest = f;
          }
        });
        // Where the triangles cancel (two folded onto each other at a scan's depth edge, where
        // the points of a row are collinear) the particle's own normal serves, else its widest
        // triangle's: no used vertex is left with a zero or arbitrary normal.
        if (norm(sum) > 1e-6 * weight) out[v] = normalized(sum);
        else out[v] = squared_norm(fallback[v]) > 0 || !(widest_angle > 0) ? fallback[v] : widest;
        block_none += active_[v] && !any;
      }
      none.fetch_add(block_none, std::memory_order_relaxed);
    });
    unused = none.load();
    return out;
  }

  /// The surface's triangles (the live ones, in order).
  std::vector<Triangle> take() {
    std::vector<Triangle> out;
    out.reserve(tris_.size());
    for (uint32_t t = 0; t < tris_.size(); ++t)
      if (alive_[t]) out.push_back(tris_[t]);
    return out;
  }
  /// Boundary half-edges left (only meaningful after repair()).
  std::vector<uint64_t> boundary() const {
    std::vector<uint64_t> b(boundary_.begin(), boundary_.end());
    std::sort(b.begin(), b.end());
    return b;
  }

 private:
  const std::vector<Vec3>& P_;
  const std::vector<Vec3>& N_;
  const std::vector<uint8_t>& active_;
  BuilderOptions o_;
  BuilderStats& stats_;
  ProgressTracker& tracker_;
  std::vector<Frame> frame_;
  // growth
  std::vector<Triangle> cand_;
  std::vector<uint8_t> state_;
  /// A candidate's corner at a vertex: the candidate, the vertices after and before the
  /// vertex in its winding, and its arc about the vertex normal. Kept per vertex, so that the
  /// growth tests read one short contiguous list instead of the candidates scattered in memory.
  struct Corner {
    uint32_t c, succ, pred;
    Arc arc;
  };
  std::vector<Corner, UninitAllocator<Corner>> vc_;
  std::vector<uint32_t> vc_off_;
  std::vector<uint32_t> acc_count_;
  uint64_t block_scale_ = 0;     ///< see block_of()
  std::vector<uint8_t> inner_;   ///< per vertex: no path of up to two candidate edges leaves its block
  /// Candidates ranked from here on are flat: largest angle over 150 degrees (see grow()).
  uint32_t flat_from_ = 0;
  static constexpr float kFlatQuality = 0.866f;  // -cos(150 degrees)
  /// Growth blocks: as many as fit at least kMinBlockPoints points each, up to kMaxBlocks
  /// (fewer blocks, fewer seams; 16 keep 16 threads busy).
  static constexpr size_t kMinBlockPoints = 16384, kMaxBlocks = 16;

  // repair
  std::vector<Triangle> tris_;
  std::vector<uint8_t> alive_;
  std::vector<uint32_t> vt_off_, vt_;
  std::unordered_map<uint32_t, std::vector<uint32_t>> extra_;
  std::vector<uint8_t> has_extra_;  ///< per vertex: holds a list in extra_
  std::unordered_set<uint64_t> boundary_;
};

}  // namespace

std::vector<Triangle> build_surface(const std::vector<Vec3>& positions, const std::vector<Vec3>& normals,
                                    const std::vector<uint8_t>& active, const std::vector<Triangle>& raw,
                                    const BuilderOptions& options, bool repair, BuilderStats& stats,
                                    ProgressTracker& tracker, std::vector<Vec3>& vertex_normals) {
  using Clock = std::chrono::steady_clock;
  auto since = [](Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); };
  auto t0 = Clock::now();
  Builder b(positions, normals, active, options, stats, tracker);
  b.add_candidates(raw);
  stats.seconds_candidates = since(t0);
  t0 = Clock::now();
  b.grow();
  b.index();
  stats.seconds_growth = since(t0);
  t0 = Clock::now();
  if (repair) b.repair(raw);
  stats.seconds_repair = since(t0);
  stats.boundary = b.boundary();
  tracker.check();
  vertex_normals = b.vertex_normals(normals, stats.unused_points);
  return b.take();
}

size_t orient_closed_components_outward(const std::vector<Vec3>& P, std::vector<Triangle>& T,
                                        const std::vector<uint64_t>& boundary, std::vector<Vec3>* vertex_normals) {
  // Components by shared vertices (the same as by shared edges on a manifold without
  // pinches); a component is open if it holds a boundary half-edge. A concurrent union-find
  // that always links the higher root under the lower: each component ends at its lowest
  // point, whatever the threads did (a serial pass over 2M triangles took 40-50 ms).
  const size_t n = P.size();
  std::vector<uint32_t> parent(n);
  std::iota(parent.begin(), parent.end(), 0u);
  auto up = [&](uint32_t x) { return std::atomic_ref<uint32_t>(parent[x]).load(std::memory_order_relaxed); };
  auto find = [&](uint32_t x) {  // halving the path: a parent's parent is an ancestor too
    for (uint32_t p = up(x); p != x; p = up(x)) {
      const uint32_t g = up(p);
      if (g != p) std::atomic_ref<uint32_t>(parent[x]).store(g, std::memory_order_relaxed);
      x = g;
    }
    return x;
  };
  detail::parallel_blocks(T.size(), 8192, [&](size_t b, size_t e) {
    for (size_t i = b; i < e; ++i)
      for (int k = 1; k < 3; ++k) {
        uint32_t a = T[i][0], c = T[i][k];
        while (true) {
          a = find(a);
          c = find(c);
          if (a == c) break;
          if (a < c) std::swap(a, c);  // link the higher root a under c
          uint32_t expected = a;
          if (std::atomic_ref<uint32_t>(parent[a]).compare_exchange_strong(expected, c, std::memory_order_relaxed)) break;
        }
      }
  });
  std::vector<uint32_t> root(n);
  detail::parallel_blocks(n, 8192, [&](size_t b, size_t e) {
    for (size_t v = b; v < e; ++v) root[v] = find(uint32_t(v));
  });
  std::vector<uint8_t> open(n, 0);
  for (uint64_t e : boundary) open[root[uint32_t(e >> 32)]] = 1;
  // Signed volumes: partial sums per fixed chunk of triangles (in space order, so a chunk
  // meets few components), added up in chunk order: the same sums for any thread count.
  const size_t chunk = 16384, chunks = (T.size() + chunk - 1) / chunk;
  std::vector<std::vector<std::pair<uint32_t, double>>> part(chunks);
  detail::parallel_blocks(chunks, 1, [&](size_t hb, size_t he) {
    for (size_t h = hb; h < he; ++h)
      for (size_t i = h * chunk; i < std::min(T.size(), (h + 1) * chunk); ++i) {
        const Triangle& t = T[i];
        const uint32_t r = root[t[0]];
        const Vec3 o = P[r];
        const double v = dot(P[t[0]] - o, cross(P[t[1]] - o, P[t[2]] - o));
        auto& pt = part[h];
        auto it = std::find_if(pt.rbegin(), pt.rend(), [r](const auto& x) { return x.first == r; });
        if (it != pt.rend()) it->second += v;
        else pt.push_back({r, v});
      }
  });
  std::vector<double> vol(n, 0.0);
  for (const auto& pt : part)
    for (const auto& [r, v] : pt) vol[r] += v;
  auto turned = [&](uint32_t r) { return !open[r] && vol[r] < 0; };
  detail::parallel_blocks(T.size(), 8192, [&](size_t b, size_t e) {
    for (size_t i = b; i < e; ++i)
      if (turned(root[T[i][0]])) std::swap(T[i][1], T[i][2]);
  });
  std::atomic<size_t> flipped{0};
  detail::parallel_blocks(n, 8192, [&](size_t b, size_t e) {
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
