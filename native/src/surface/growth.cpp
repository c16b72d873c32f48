#include "surface/growth.h"

#include <algorithm>
#include <utility>

#include "core/counting_sort.h"
#include "core/parallel.h"
#include "particlemesh/core/error.h"
#include "surface/rank_queue.h"

namespace PM_NAMESPACE::detail {

namespace {

class Growth {
 public:
  Growth(size_t points, CandidateSet&& c, ProgressTracker& tracker)
      : n_(points),
        tracker_(tracker),
        cand_(std::move(c.cand)),
        vc_(std::move(c.corners)),
        vc_off_(std::move(c.corner_offset)),
        flat_from_(c.flat_from) {
    state_.assign(cand_.size(), kOpen);
    acc_count_.assign(n_, 0);
  }

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
        if (!heap.empty()) {  // likely the next one: load what it reads while this one is checked
          const uint32_t next = heap.top();
          __builtin_prefetch(&r.state[next]);
          for (const uint32_t v : r.cand[next]) {
            __builtin_prefetch(&acc_count_[v]);
            __builtin_prefetch(&vc_[vc_off_[v]]);
          }
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
    for (uint32_t v = 0; v < n_; ++v)
      if (acc_count_[v] == 0)
        for (uint32_t i = vc_off_[v]; i < vc_off_[v + 1]; ++i) out.push_back(vc_[i].c);
    std::sort(out.begin(), out.end());
    out.erase(std::unique(out.begin(), out.end()), out.end());
    return out;
  }

  /// inner_: the points with no candidate path of up to two edges into another block.
  void mark_inner_points() {
    const size_t n = n_;
    inner_.assign(n, 1);
    for (int ring = 0; ring < 2; ++ring) {
      std::vector<uint8_t> next(n);
      parallel_blocks(n, 8192, [&](size_t b, size_t e) {
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
  /// of the finishing stages. The block size depends on the point count only, so the surface
  /// is the same for any thread count, and a cloud of one block grows exactly as one region
  /// would. Then one serial pass grows across the seams between blocks, from the candidates
  /// there that continue a grown triangle.
  ///
  /// Flat candidates (largest angle over 150 degrees: nearly collinear particles) need care.
  /// Where growth stops at a fixed line (a block's edge) or two fronts meet head-on (a seam),
  /// the gap left along a row of particles is just a flat triangle's, and the flat ones taken
  /// there tilted vertex normals by up to 30 degrees (on a Fibonacci sphere, where serial
  /// growth took no flat triangle at all). So a block takes a flat candidate only two rings
  /// inside it, and the seams pass takes none: those gaps close as small holes, which the
  /// repair fills.
  ///
  /// A block works on its own copy of its candidates and their states, by their positions in
  /// its list (the corner lists say so for the time), not on the ranks: the candidates it
  /// reads are then together in memory, not spread over the whole list in quality order.
  GrownSurface grow() {
    tracker_.stage("extracting the surface", 0.7, 0.85, cand_.size());
    const size_t n = n_, m = cand_.size();
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
    parallel_blocks(blocks, 1, [&](size_t bb, size_t be) {
      for (size_t b = bb; b < be; ++b)
        for (size_t pos = block_start[b]; pos < block_start[b + 1]; ++pos) local[ids[pos]] = uint32_t(pos - block_start[b]);
    });
    // The seams' candidates: the last list.
    const std::vector<uint32_t> seams(ids.begin() + block_start[blocks], ids.end());
    // The corner lists name the candidates by block positions (kOther for the seams').
    parallel_blocks(n, 8192, [&](size_t b, size_t e) {
      for (uint32_t i = vc_off_[b]; i < vc_off_[e]; ++i) {
        const uint32_t c = vc_[i].c;
        vc_[i].c = local[c] == kOther ? c | kOther : local[c];
      }
    });
    std::vector<uint32_t>().swap(local);
    std::vector<size_t> grown(blocks, 0), seeds(blocks, 0);
    parallel_blocks(blocks, 1, [&](size_t bb, size_t be) {
      for (size_t b = bb; b < be; ++b) {
        const uint32_t* id = ids.data() + block_start[b];
        const size_t count = block_start[b + 1] - block_start[b];
        std::vector<Triangle> cand(count);
        std::vector<uint8_t> state(count, kOpen);
        // The block's candidates lie spread over the whole ranked list: each fetched a few
        // ahead of its copy.
        constexpr size_t kAhead = 16;
        for (size_t i = 0; i < count; ++i) {
          if (i + kAhead < count) __builtin_prefetch(&cand_[id[i + kAhead]]);
          cand[i] = cand_[id[i]];
        }
        Region r;
        r.cand = cand.data();
        r.state = state.data();
        r.count = count;
        r.block = true;
        RankQueue heap(count);
        grow_region(r, heap, true);
        for (size_t i = 0; i < count; ++i) {
          if (i + kAhead < count) __builtin_prefetch(&state_[id[i + kAhead]], 1);
          state_[id[i]] = state[i];
        }
        grown[b] = r.grown;
        seeds[b] = r.seeds;
      }
    });
    tracker_.check();
    // Back to ranks.
    parallel_blocks(n, 8192, [&](size_t b, size_t e) {
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
    parallel_blocks(seams.size(), 4096, [&](size_t b, size_t e) {
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
    GrownSurface out;
    for (size_t b = 0; b < blocks; ++b) {
      out.grown += grown[b];
      out.seeds += seeds[b];
    }
    out.grown += all.grown;
    out.seeds += all.seeds;
    std::vector<Triangle>().swap(cand_);
    std::vector<uint8_t>().swap(state_);
    // The surface's triangles in space order: each at its lowest vertex (its first corner,
    // as raw triangles are (i < j < k) and orienting swaps the other two), in candidate order
    // there. The repair and the vertex normals then read triangles near each other in memory.
    // Gathered per fixed block of points, then joined in block order.
    const size_t block = 8192, nblocks = (n + block - 1) / block;
    std::vector<std::vector<Triangle>> part(nblocks);
    parallel_blocks(nblocks, 1, [&](size_t bb, size_t be) {
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
    out.triangles.resize(at[nblocks]);
    parallel_blocks(nblocks, 1, [&](size_t bb, size_t be) {
      for (size_t blk = bb; blk < be; ++blk) {
        std::copy(part[blk].begin(), part[blk].end(), out.triangles.begin() + ptrdiff_t(at[blk]));
        std::vector<Triangle>().swap(part[blk]);
      }
    });
    out.corners = std::move(vc_);
    out.corner_offset = std::move(vc_off_);
    out.accepted_count = std::move(acc_count_);
    return out;
  }

 private:
  size_t n_;
  ProgressTracker& tracker_;
  std::vector<Triangle> cand_;
  std::vector<uint8_t> state_;
  std::vector<Corner, UninitAllocator<Corner>> vc_;
  std::vector<uint32_t> vc_off_;
  std::vector<uint32_t> acc_count_;
  uint32_t flat_from_ = 0;
  uint64_t block_scale_ = 0;     ///< see block_of()
  std::vector<uint8_t> inner_;   ///< per vertex: no path of up to two candidate edges leaves its block
  /// Growth blocks: as many as fit at least kMinBlockPoints points each, up to kMaxBlocks
  /// (fewer blocks, fewer seams; 16 keep 16 threads busy).
  static constexpr size_t kMinBlockPoints = 16384, kMaxBlocks = 16;
};

}  // namespace

GrownSurface grow_surface(size_t points, CandidateSet&& candidates, ProgressTracker& tracker) {
  Growth g(points, std::move(candidates), tracker);
  return g.grow();
}

}  // namespace particlemesh::detail
