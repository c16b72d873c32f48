// Internal: union-find over 0..n-1, the connected pieces of a mesh (by vertices, triangles or
// corners), serial and concurrent. The lower root always becomes the parent, so each set's
// root is its lowest element and the result depends on nothing but the elements (not the
// order of the unions, nor the threads').
#pragma once

#include "particlemesh/core/config.h"

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <numeric>
#include <utility>
#include <vector>

namespace PM_NAMESPACE::detail {

class DisjointSets {
 public:
  explicit DisjointSets(size_t n) : parent_(n) { std::iota(parent_.begin(), parent_.end(), uint32_t(0)); }
  /// The set's root (its lowest element); halves the path on the way.
  uint32_t find(uint32_t x) {
    while (parent_[x] != x) x = parent_[x] = parent_[parent_[x]];
    return x;
  }
  void unite(uint32_t a, uint32_t b) {
    a = find(a);
    b = find(b);
    if (a == b) return;
    if (a < b) std::swap(a, b);
    parent_[a] = b;
  }

 private:
  std::vector<uint32_t> parent_;
};

/// The same sets, joined by several threads at once. A root is only ever linked under a lower
/// root (compare-and-swap), so each set's root is its lowest element whatever the order of
/// the unions; finding halves the path (a non-root's parent only ever moves up, so any
/// ancestor is a correct parent).
class ConcurrentDisjointSets {
 public:
  explicit ConcurrentDisjointSets(size_t n) : parent_(n) {
    for (size_t i = 0; i < n; ++i) parent_[i].store(uint32_t(i), std::memory_order_relaxed);
  }
  uint32_t find(uint32_t x) {
    while (true) {
      const uint32_t p = parent_[x].load(std::memory_order_relaxed);
      if (p == x) return x;
      const uint32_t g = parent_[p].load(std::memory_order_relaxed);
      if (g != p) parent_[x].store(g, std::memory_order_relaxed);
      x = g;
    }
  }
  void unite(uint32_t a, uint32_t b) {
    while (true) {
      a = find(a);
      b = find(b);
      if (a == b) return;
      if (a < b) std::swap(a, b);  // link the higher root a under b
      uint32_t expected = a;
      if (parent_[a].compare_exchange_strong(expected, b, std::memory_order_relaxed)) return;
    }
  }

 private:
  std::vector<std::atomic<uint32_t>> parent_;
};

}  // namespace particlemesh::detail
