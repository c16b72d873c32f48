// Internal: the hash and the open-addressing table every grid of integer cells uses (the
// neighbour grid, the thinning's kept cells, the sample shapes' cells).
//
// Written here rather than taken from a library: the tables map keys the caller already
// holds in a sorted array to their index there, so a slot is one uint32_t (a quarter of what
// std::unordered_map or TBB's concurrent maps spend per entry), built once and then only read.
#pragma once

#include "particlemesh/core/config.h"

#include <array>
#include <cstdint>
#include <vector>

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
/// Returns the mask (the table's size - 1) that find_key takes.
inline uint64_t build_key_table(const std::vector<uint64_t>& keys, std::vector<uint32_t>& table) {
  uint64_t size = 16;
  while (size < 2 * uint64_t(keys.size())) size <<= 1;
  table.assign(size, kNoKey);
  const uint64_t mask = size - 1;
  for (uint32_t i = 0; i < keys.size(); ++i) {
    uint64_t h = mix64(keys[i]) & mask;
    while (table[h] != kNoKey) h = (h + 1) & mask;
    table[h] = i;
  }
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

}  // namespace particlemesh::detail
