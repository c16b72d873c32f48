// Internal: the hash and the open-addressing table every grid of integer cells uses (the
// neighbour grid, the thinning's kept cells, the sample shapes' cells), and a set of integer
// keys that grows and shrinks (the surface's boundary half-edges).
//
// Written here rather than taken from a library: the tables map keys the caller already
// holds in a sorted array to their index there, so a slot is one uint32_t (a quarter of what
// std::unordered_map or TBB's concurrent maps spend per entry), built once and then only read.
#pragma once

#include "particlemesh/core/config.h"

#include <algorithm>
#include <array>
#include <atomic>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "core/parallel.h"

namespace PM_NAMESPACE::detail {

/// The finaliser of splitmix64 (Steele, Lea and Flood, "Fast splittable pseudorandom number
/// generators", OOPSLA 2014): every input bit reaches every output bit; cheap.
inline uint64_t mix64(uint64_t h) {
  h ^= h >> 30;
  h *= 0xBF58476D1CE4E5B9ull;
  h ^= h >> 27;
  h *= 0x94D049BB133111EBull;
  h ^= h >> 31;
  return h;
}

/// A hash of integer cell coordinates: each coordinate times an odd constant, mixed.
inline uint64_t hash_cell(const std::array<int32_t, 3>& c) {
  return mix64(uint64_t(uint32_t(c[0])) * 0x9E3779B97F4A7C15ull ^
               uint64_t(uint32_t(c[1])) * 0xC2B2AE3D27D4EB4Full ^
               uint64_t(uint32_t(c[2])) * 0x165667B19E3779F9ull);
}

/// The empty slot of a key table.
inline constexpr uint32_t kNoKey = 0xffffffffu;

/// Fills `table` with the indices of the distinct `keys` by linear probing on mix64(key):
/// a power of two of at least 16 slots and twice the key count, so probes stay short.
/// Returns the mask (the table's size - 1) that find_key takes. Many keys (a grid of a million
/// points has a quarter million cells, each insert a cache miss) are inserted in parallel,
/// each slot claimed by a compare-and-swap: where keys collide, which of them takes which
/// slot depends on the threads' timing, but every look-up finds the same index (only its
/// number of probes may differ), so no result does.
inline uint64_t build_key_table(const std::vector<uint64_t>& keys, std::vector<uint32_t>& table) {
  uint64_t size = 16;
  while (size < 2 * uint64_t(keys.size())) size <<= 1;
  const uint64_t mask = size - 1;
  constexpr size_t kParallel = size_t(1) << 16;
  if (keys.size() < kParallel) {
    table.assign(size, kNoKey);
    for (uint32_t i = 0; i < keys.size(); ++i) {
      uint64_t h = mix64(keys[i]) & mask;
      while (table[h] != kNoKey) h = (h + 1) & mask;
      table[h] = i;
    }
    return mask;
  }
  table.resize(size);
  parallel_blocks(size, 65536, [&](size_t b, size_t e) {
    std::fill(table.begin() + ptrdiff_t(b), table.begin() + ptrdiff_t(e), kNoKey);
  });
  parallel_blocks(keys.size(), 4096, [&](size_t b, size_t e) {
    for (size_t i = b; i < e; ++i) {
      for (uint64_t h = mix64(keys[i]) & mask;; h = (h + 1) & mask) {
        uint32_t empty = kNoKey;
        if (std::atomic_ref<uint32_t>(table[h]).compare_exchange_strong(empty, uint32_t(i), std::memory_order_relaxed))
          break;
      }
    }
  });
  return mask;
}

/// The index of `key` in `keys` through a table build_key_table made, or kNoKey.
inline uint32_t find_key(const std::vector<uint32_t>& table, uint64_t mask, const std::vector<uint64_t>& keys,
                         uint64_t key) {
  if (table.empty()) return kNoKey;
  for (uint64_t h = mix64(key) & mask;; h = (h + 1) & mask) {
    const uint32_t i = table[h];
    if (i == kNoKey || keys[i] == key) return i;
  }
}

/// A set of uint64_t keys that grows and shrinks: linear probing on mix64 in a power-of-two
/// array of slots, at most half full, with deletion by backward shift (Knuth, TAOCP vol. 3,
/// 6.4, Algorithm R: the keys after the freed slot whose probe passed it move back, so no
/// tombstone is left and probes stay short however many keys come and go). Walked in slot
/// order, which is no order: callers sort what they take.
///
/// Written here rather than with std::unordered_set: the surface's boundary half-edges are
/// toggled on every triangle added or removed and walked in full by every pass of the repair;
/// a node per key made each walk a chase through memory (most of the loops' tracing on a
/// scan with tens of thousands of them), and the slots here are one array.
class KeySet {
 public:
  /// The one value that cannot be a key.
  static constexpr uint64_t kEmpty = ~uint64_t(0);

  KeySet() : slots_(16, kEmpty), mask_(15) {}

  size_t size() const { return count_; }
  bool empty() const { return count_ == 0; }

  /// Adds `key`; false if it was there.
  bool insert(uint64_t key) {
    if (2 * (count_ + 1) > slots_.size()) grow();
    uint64_t h = mix64(key) & mask_;
    for (; slots_[h] != kEmpty; h = (h + 1) & mask_)
      if (slots_[h] == key) return false;
    slots_[h] = key;
    ++count_;
    return true;
  }

  /// Removes `key`; false if it was not there.
  bool erase(uint64_t key) {
    uint64_t i = mix64(key) & mask_;
    for (; slots_[i] != key; i = (i + 1) & mask_)
      if (slots_[i] == kEmpty) return false;
    // Algorithm R: each key after the gap whose home lies cyclically at or before the gap
    // (its probe passed through it) moves into it, and its own slot becomes the gap.
    for (uint64_t j = (i + 1) & mask_; slots_[j] != kEmpty; j = (j + 1) & mask_) {
      const uint64_t home = mix64(slots_[j]) & mask_;
      const bool passes = i <= j ? (home <= i || home > j) : (home <= i && home > j);
      if (passes) {
        slots_[i] = slots_[j];
        i = j;
      }
    }
    slots_[i] = kEmpty;
    --count_;
    return true;
  }

  /// The keys, in slot order.
  class const_iterator {
   public:
    const_iterator(const uint64_t* at, const uint64_t* end) : at_(at), end_(end) { skip(); }
    uint64_t operator*() const { return *at_; }
    const_iterator& operator++() {
      ++at_;
      skip();
      return *this;
    }
    bool operator!=(const const_iterator& o) const { return at_ != o.at_; }

   private:
    void skip() {
      while (at_ != end_ && *at_ == kEmpty) ++at_;
    }
    const uint64_t* at_;
    const uint64_t* end_;
  };
  const_iterator begin() const { return {slots_.data(), slots_.data() + slots_.size()}; }
  const_iterator end() const { return {slots_.data() + slots_.size(), slots_.data() + slots_.size()}; }

 private:
  void grow() {
    std::vector<uint64_t> old(slots_.size() * 2, kEmpty);
    old.swap(slots_);
    mask_ = slots_.size() - 1;
    count_ = 0;
    for (const uint64_t key : old)
      if (key != kEmpty) insert(key);
  }

  std::vector<uint64_t> slots_;
  uint64_t mask_;
  size_t count_ = 0;
};

}  // namespace particlemesh::detail
