#include "particlemesh/mesh/edges.h"

#include <algorithm>
#include <atomic>
#include <cstdlib>
#include <limits>
#include <memory>
#include <mutex>
#include <string>

#include "core/parallel.h"
#include "mesh/edges_impl.h"
#include "particlemesh/core/error.h"

namespace PM_NAMESPACE {

namespace detail {

namespace {

/// The error for triangle t, which has an index >= vertex_count or a repeated vertex.
[[noreturn]] void bad_triangle(const uint32_t* T, size_t t, size_t vertex_count) {
  for (int k = 0; k < 3; ++k)
    if (T[k] >= vertex_count)
      throw Error(Status::InvalidArgument, "triangle " + std::to_string(t) + " has vertex index " +
                                               std::to_string(T[k]) + ", beyond the " +
                                               std::to_string(vertex_count) + " vertices");
  throw Error(Status::InvalidArgument, "triangle " + std::to_string(t) + " repeats a vertex");
}

/// The numbering's (higher vertex, corner) slots: 8 bytes a corner, 35 MB for a 1.47M-triangle
/// frame. A block that large comes back from the allocator as fresh pages on every call
/// (glibc maps blocks over 32 MB anew, jemalloc - Blender's - returns large blocks to the
/// system once freed), and their 4 KiB page faults were a third of the numbering's time in
/// Blender's live mode, which numbers every new frame's edges. So the block is kept for the
/// next call, up to kKeptBytes; a call finding none (or another call's in use) allocates its
/// own. Left uninitialised: every slot is written before it is read.
class Slots {
 public:
  explicit Slots(size_t n) {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      if (kept_size_ >= n) {
        data_ = std::move(kept_);
        size_ = kept_size_;
        kept_size_ = 0;
      }
    }
    if (!data_) {
      data_.reset(static_cast<uint64_t*>(std::malloc(std::max<size_t>(n, 1) * sizeof(uint64_t))));
      if (!data_) throw std::bad_alloc();
      size_ = n;
    }
  }
  Slots(const Slots&) = delete;
  Slots& operator=(const Slots&) = delete;
  ~Slots() {
    if (size_ * sizeof(uint64_t) > kKeptBytes) return;
    std::lock_guard<std::mutex> lock(mutex_);
    if (size_ > kept_size_) {
      kept_ = std::move(data_);
      kept_size_ = size_;
    }
  }
  uint64_t* data() { return data_.get(); }

  /// The most memory kept between calls (a frame of about 2.7M triangles).
  static constexpr size_t kKeptBytes = size_t(64) << 20;

 private:
  struct Free {
    void operator()(uint64_t* p) const { std::free(p); }
  };
  std::unique_ptr<uint64_t, Free> data_;
  size_t size_ = 0;
  static inline std::mutex mutex_;
  static inline std::unique_ptr<uint64_t, Free> kept_;
  static inline size_t kept_size_ = 0;
};

}  // namespace

// Hand-written: OpenMesh builds its half-edge structure (and refuses non-manifold input) to
// get edges, and Blender's own edge pass was most of the time of writing a mesh into it
// (bench/RESULTS.md). Each edge belongs to its lower vertex: the corners are bucketed by
// their edge's lower vertex as (higher vertex, corner) pairs, each vertex's few pairs are
// sorted (its corners on one edge next to each other), and one walk over the sorted pairs
// numbers the edges and gives every corner its edge.
size_t number_edges(const uint32_t* triangles, size_t m, size_t n, int threads, uint32_t* corner_edges,
                    const std::function<uint32_t*(size_t)>& edges_at) {
  if (n >= (size_t(1) << 32)) throw Error(Status::LimitExceeded, "more than 2^32 - 1 vertices");
  if (m >= (size_t(1) << 30)) throw Error(Status::LimitExceeded, "more than 2^30 triangles");
  size_t count = 0;
  with_threads(threads, [&] {
    // Every triangle checked first (the first bad one is named).
    std::atomic<size_t> first_bad{std::numeric_limits<size_t>::max()};
    parallel_blocks(m, 8192, [&](size_t b, size_t e) {
      for (size_t t = b; t < e; ++t) {
        const uint32_t* T = triangles + 3 * t;
        if (T[0] >= n || T[1] >= n || T[2] >= n || T[0] == T[1] || T[1] == T[2] || T[0] == T[2]) {
          size_t seen = first_bad.load(std::memory_order_relaxed);
          while (t < seen && !first_bad.compare_exchange_weak(seen, t, std::memory_order_relaxed)) {
          }
          return;  // the rest of the block can only be later
        }
      }
    });
    if (const size_t t = first_bad.load(); t < m) bad_triangle(triangles + 3 * t, t, n);
    // Per lower vertex v, its corners' slots [start[v], start[v + 1]). The vertices are cut
    // into one range per thread, and each range's task reads every triangle but counts and
    // places only the corners whose edge's lower vertex is its own: no two tasks write the
    // same slot, so no atomic increments (a locked add per corner, twice, was most of the
    // time; reading the triangles again per range is cheap beside it).
    const size_t ranges = std::clamp<size_t>(size_t(tbb::this_task_arena::max_concurrency()), 1, 64);
    const auto range_start = [&](size_t r) { return uint32_t(n * r / ranges); };
    const auto each_corner_of = [&](size_t r, auto&& fn) {
      const uint32_t lo = range_start(r), hi = range_start(r + 1);
      for (size_t t = 0; t < m; ++t) {
        const uint32_t* T = triangles + 3 * t;
        for (size_t k = 0; k < 3; ++k) {
          const uint32_t x = T[k], y = T[k == 2 ? 0 : k + 1];
          const uint32_t lower = std::min(x, y);
          if (lower >= lo && lower < hi) fn(lower, std::max(x, y), 3 * t + k);
        }
      }
    };
    std::vector<uint32_t> start(n + 1, 0);
    parallel_blocks(ranges, 1, [&](size_t rb, size_t re) {
      for (size_t r = rb; r < re; ++r) each_corner_of(r, [&](uint32_t lower, uint32_t, size_t) { ++start[lower + 1]; });
    });
    for (size_t v = 0; v < n; ++v) start[v + 1] += start[v];
    // (higher vertex << 32 | corner) per slot; 3 m < 2^32.
    Slots slots(3 * m);
    uint64_t* const pairs = slots.data();
    {
      std::vector<uint32_t> cursor(start.begin(), start.end() - 1);
      parallel_blocks(ranges, 1, [&](size_t rb, size_t re) {
        for (size_t r = rb; r < re; ++r)
          each_corner_of(r, [&](uint32_t lower, uint32_t higher, size_t c) {
            pairs[cursor[lower]++] = (uint64_t(higher) << 32) | uint64_t(c);
          });
      });
    }
    // Fixed blocks of vertices: each sorts its vertices' pairs and counts its edges, then,
    // from its first edge's number, numbers them.
    constexpr size_t kBlock = 4096;
    const size_t blocks = (n + kBlock - 1) / kBlock;
    std::vector<size_t> first(blocks + 1, 0);
    parallel_blocks(blocks, 1, [&](size_t bb, size_t be) {
      for (size_t b = bb; b < be; ++b) {
        size_t edges = 0;
        for (size_t v = b * kBlock; v < std::min(n, (b + 1) * kBlock); ++v) {
          uint64_t* p = pairs + start[v];
          uint64_t* end = pairs + start[v + 1];
          if (end - p > 16) {
            std::sort(p, end);
          } else if (end - p > 1) {  // the common few: insertion sort
            for (uint64_t* i = p + 1; i < end; ++i)
              for (uint64_t* j = i; j > p && j[-1] > *j; --j) std::swap(j[-1], *j);
          }
          for (uint64_t* i = p; i < end; ++i) edges += (i == p || (i[-1] >> 32) != (*i >> 32));
        }
        first[b + 1] = edges;
      }
    });
    for (size_t b = 0; b < blocks; ++b) first[b + 1] += first[b];
    count = first[blocks];
    uint32_t* out = edges_at(count);
    parallel_blocks(blocks, 1, [&](size_t bb, size_t be) {
      for (size_t b = bb; b < be; ++b) {
        size_t next = first[b];
        for (size_t v = b * kBlock; v < std::min(n, (b + 1) * kBlock); ++v) {
          const uint64_t* p = pairs + start[v];
          const uint64_t* end = pairs + start[v + 1];
          size_t current = 0;
          for (const uint64_t* i = p; i < end; ++i) {
            const uint32_t higher = uint32_t(*i >> 32);
            if (i == p || uint32_t(i[-1] >> 32) != higher) {
              current = next++;
              out[2 * current] = uint32_t(v);
              out[2 * current + 1] = higher;
            }
            corner_edges[uint32_t(*i)] = uint32_t(current);
          }
        }
      }
    });
  });
  return count;
}

}  // namespace detail

MeshEdges mesh_edges(const std::vector<Triangle>& triangles, size_t vertex_count, int threads) {
  static_assert(sizeof(Triangle) == 3 * sizeof(uint32_t) && sizeof(std::array<uint32_t, 2>) == 2 * sizeof(uint32_t));
  MeshEdges out;
  out.corner_edges.resize(3 * triangles.size());
  detail::number_edges(reinterpret_cast<const uint32_t*>(triangles.data()), triangles.size(), vertex_count, threads,
                       out.corner_edges.data(), [&](size_t count) {
                         out.edges.resize(count);
                         return reinterpret_cast<uint32_t*>(out.edges.data());
                       });
  return out;
}

}  // namespace particlemesh
