// Internal: hashing of integer cell coordinates for the open-addressing grid tables.
#pragma once

#include <array>
#include <cstdint>

namespace particlemesh::detail {

inline uint64_t hash_cell(const std::array<int32_t, 3>& c) {
  // splitmix64 finaliser over the packed coordinates: cheap and well mixed.
  uint64_t h = uint64_t(uint32_t(c[0])) * 0x9E3779B97F4A7C15ull ^
               uint64_t(uint32_t(c[1])) * 0xC2B2AE3D27D4EB4Full ^
               uint64_t(uint32_t(c[2])) * 0x165667B19E3779F9ull;
  h ^= h >> 30;
  h *= 0xBF58476D1CE4E5B9ull;
  h ^= h >> 27;
  h *= 0x94D049BB133111EBull;
  h ^= h >> 31;
  return h;
}

}  // namespace particlemesh::detail
