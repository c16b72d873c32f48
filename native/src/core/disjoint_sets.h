// Internal: union-find over 0..n-1, the connected pieces of a mesh (by vertices, triangles or
// corners). The lower root always becomes the parent, so each set's root is its lowest
// element and the result depends on nothing but the elements (not the order of the unions).
#pragma once

#include "particlemesh/core/config.h"

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

}  // namespace particlemesh::detail
