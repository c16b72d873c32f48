// Internal: polygonize's inside test over a block's 9^3 local nodes as bits. Most cells of
// a block that the surface passes through have all eight corners on one side; the test is
// taken once per node, as one 9-bit row per (y, z) (bit x), and the crossing edges and the
// cells with both states come out of whole rows with a few bit operations, so that only
// those cells load their samples. Header-only (the tests compare it with the test per node
// and per cell that it replaces).
#pragma once

#include "particlemesh/core/config.h"

#include <array>
#include <bit>
#include <cstdint>
#include <cstring>
#include <limits>
#include <cmath>

#include "volume/anisotropic_sampling.h"

namespace PM_NAMESPACE::detail {

inline constexpr int kL = kSampleBlock + 1;                             // local nodes per axis
inline constexpr int kMaskWords = 3 * kSampleBlock * kSampleBlock * kSampleBlock / 64;  // edge bits

/// The set bits of a word: the classic SWAR sum, inline (std::popcount is a call into the
/// compiler's runtime library on baseline x86-64, which has no POPCNT instruction).
inline uint32_t bit_count(uint64_t v) {
  v = v - ((v >> 1) & 0x5555555555555555ull);
  v = (v & 0x3333333333333333ull) + ((v >> 2) & 0x3333333333333333ull);
  v = (v + (v >> 4)) & 0x0f0f0f0f0f0f0f0full;
  return uint32_t((v * 0x0101010101010101ull) >> 56);
}

/// The inside test double(v) >= T as the float comparison v >= float_threshold(T): the
/// smallest float whose value is at or above T (float to double is exact and monotone, so
/// both tests agree for every float, infinities included).
inline float float_threshold(double T) {
  constexpr double kMax = double(std::numeric_limits<float>::max());
  if (T > kMax) return std::numeric_limits<float>::infinity();
  if (T < -kMax) return T == -std::numeric_limits<double>::infinity() ? -std::numeric_limits<float>::infinity()
                                                                       : std::numeric_limits<float>::lowest();
  float f = float(T);
  if (double(f) < T) f = std::nextafter(f, std::numeric_limits<float>::infinity());
  return f;
}

/// rows[y + 9 z], bit x: local node (x, y, z) (local[x + 9 (y + 9 z)]) is inside.
inline void inside_rows(const float* local, float Tf, uint16_t* rows) {
  for (int row = 0; row < kL * kL; ++row) {
    const float* v = local + kL * row;
    unsigned m = 0;
    for (int x = 0; x < kL; ++x) m |= unsigned(v[x] >= Tf) << x;
    rows[row] = uint16_t(m);
  }
}

/// Bit i of byte b moved to bit 3 i: a row's crossings along one axis into the edge mask's
/// layout (bit 3 x + axis).
inline constexpr std::array<uint32_t, 256> kSpread3 = [] {
  std::array<uint32_t, 256> t{};
  for (int b = 0; b < 256; ++b)
    for (int i = 0; i < 8; ++i)
      if ((b >> i) & 1) t[size_t(b)] |= uint32_t(1) << (3 * i);
  return t;
}();

/// Which of a block's cells and nodes (0..7 per axis) a tile's range holds: bit i of cell[a]
/// when its cell i along axis a is in the range's cells, of node[a] when its node i is one of
/// their nodes. All bits without a range.
struct BlockRange {
  unsigned cell[3] = {0xff, 0xff, 0xff};
  unsigned node[3] = {0xff, 0xff, 0xff};
};

/// The range of the cells [cmin, cmax) (nodes cmin..cmax) in block b (its nodes 8 b .. 8 b + 7).
inline BlockRange block_range(const int64_t* b, const int64_t* cmin, const int64_t* cmax) {
  BlockRange rg;
  for (int a = 0; a < 3; ++a) {
    rg.cell[a] = rg.node[a] = 0;
    for (int i = 0; i < kSampleBlock; ++i) {
      const int64_t c = b[a] * kSampleBlock + i;
      if (c >= cmin[a] && c < cmax[a]) rg.cell[a] |= 1u << i;
      if (c >= cmin[a] && c <= cmax[a]) rg.node[a] |= 1u << i;
    }
  }
  return rg;
}

/// The block's edges with a crossing: bit 3 (x + 8 (y + 8 z)) + axis of mask (kMaskWords
/// words) for the edge from node (x, y, z) along axis, where its two nodes differ and the
/// range holds it (an edge of one of its cells).
inline void crossing_mask(const uint16_t* rows, const BlockRange& rg, uint64_t* mask) {
  constexpr int kB = kSampleBlock;
  std::memset(mask, 0, kMaskWords * sizeof(uint64_t));
  for (int z = 0; z < kB; ++z)
    for (int y = 0; y < kB; ++y) {
      const unsigned r = rows[y + kL * z];
      const bool yn = (rg.node[1] >> y) & 1, zn = (rg.node[2] >> z) & 1;
      const bool yc = (rg.cell[1] >> y) & 1, zc = (rg.cell[2] >> z) & 1;
      const unsigned ex = (r ^ (r >> 1)) & (yn && zn ? rg.cell[0] : 0u);
      const unsigned ey = (r ^ rows[y + 1 + kL * z]) & (yc && zn ? rg.node[0] : 0u);
      const unsigned ez = (r ^ rows[y + kL * (z + 1)]) & (yn && zc ? rg.node[0] : 0u);
      const uint64_t v = uint64_t(kSpread3[ex & 0xff]) | uint64_t(kSpread3[ey & 0xff]) << 1 |
                         uint64_t(kSpread3[ez & 0xff]) << 2;
      if (v == 0) continue;
      const int o = 3 * kB * (y + kB * z), w = o >> 6, s = o & 63;  // a row's 24 bits
      mask[w] |= v << s;
      if (s > 64 - 3 * kB) mask[w + 1] |= v >> (64 - s);
    }
}

/// f(x, y, z, case) for each cell of the block that the range holds and that has both inside
/// and outside corners, in the order z, y, x (case: bit c set when corner c = x + 2y + 4z is
/// inside, as McTable numbers them).
template <class F>
inline void for_each_mixed_cell(const uint16_t* rows, const BlockRange& rg, F&& f) {
  constexpr int kB = kSampleBlock;
  for (int z = 0; z < kB; ++z) {
    if (!((rg.cell[2] >> z) & 1)) continue;
    for (int y = 0; y < kB; ++y) {
      if (!((rg.cell[1] >> y) & 1)) continue;
      const unsigned r00 = rows[y + kL * z], r10 = rows[y + 1 + kL * z];
      const unsigned r01 = rows[y + kL * (z + 1)], r11 = rows[y + 1 + kL * (z + 1)];
      // Cell x has an inside corner when bit x or x + 1 of `any` is set, and all inside when
      // both of `all` are.
      const unsigned any = r00 | r10 | r01 | r11, all = r00 & r10 & r01 & r11;
      unsigned m = (any | (any >> 1)) & ~(all & (all >> 1)) & rg.cell[0];
      while (m) {
        const int x = std::countr_zero(m);
        m &= m - 1;
        const int cs = int(((r00 >> x) & 3) | ((r10 >> x) & 3) << 2 | ((r01 >> x) & 3) << 4 | ((r11 >> x) & 3) << 6);
        f(x, y, z, cs);
      }
    }
  }
}

}  // namespace particlemesh::detail
