// Internal: the priority queue of the surface growth.
#pragma once

#include "particlemesh/core/config.h"

#include <algorithm>
#include <bit>
#include <cstddef>
#include <cstdint>
#include <vector>

namespace PM_NAMESPACE::detail {

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

}  // namespace particlemesh::detail
