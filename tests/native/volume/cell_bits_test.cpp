// Polygonize's inside test as bits (volume/cell_bits.h) against the test it replaces, one
// node and one cell at a time: the crossing edges, the cells with both states and their
// cases, on random blocks whose samples sit at, just above and just below the threshold (and
// at the infinities a proven-inside neighbour fills in), with and without a tile's range.
#include <gtest/gtest.h>

#include <bit>
#include <cmath>
#include <limits>
#include <random>
#include <tuple>
#include <vector>

#include "volume/cell_bits.h"

using namespace particlemesh;
using namespace particlemesh::detail;

namespace {

constexpr int kB = kSampleBlock;
constexpr float kInf = std::numeric_limits<float>::infinity();

// The floats next to T and T itself (as float), the comparisons' hard cases.
std::vector<float> near_threshold(double T) {
  const float f = float(T);
  return {f, std::nextafter(f, kInf), std::nextafter(f, -kInf), std::nextafter(std::nextafter(f, kInf), kInf),
          std::nextafter(std::nextafter(f, -kInf), -kInf)};
}

}  // namespace

TEST(PolygonizeCellBits, FloatThresholdIsTheDoubleTest) {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(-3.0, 3.0);
  std::vector<double> thresholds = {0.0, -0.0, 1.0, 0.5, 0.1, 1e-300, -1e-300, 1e30, 3.5e38, 1e300, -1e300,
                                    double(std::numeric_limits<float>::max()), std::numeric_limits<double>::infinity(),
                                    -std::numeric_limits<double>::infinity(), double(std::numeric_limits<float>::denorm_min()) / 3};
  for (int i = 0; i < 2000; ++i) thresholds.push_back(std::ldexp(u(rng), int(u(rng) * 10)));
  for (int i = 0; i < 200; ++i) thresholds.push_back(double(float(u(rng))));  // exactly a float
  for (const double T : thresholds) {
    const float Tf = float_threshold(T);
    std::vector<float> values = {0.0f, -0.0f, kInf, -kInf, std::numeric_limits<float>::quiet_NaN(),
                                 std::numeric_limits<float>::max(), std::numeric_limits<float>::lowest()};
    if (std::isfinite(T) && std::fabs(T) < 1e38)
      for (const float v : near_threshold(T)) values.push_back(v);
    for (int k = 0; k < 20; ++k) values.push_back(float(u(rng)));
    for (const float v : values) EXPECT_EQ(v >= Tf, double(v) >= T) << "T " << T << " v " << v;
  }
}

TEST(PolygonizeCellBits, BitCountIsPopcount) {
  std::mt19937_64 rng(3);
  for (const uint64_t w : {uint64_t(0), ~uint64_t(0), uint64_t(1), uint64_t(1) << 63}) EXPECT_EQ(bit_count(w), uint32_t(std::popcount(w)));
  for (int i = 0; i < 10000; ++i) {
    const uint64_t w = rng() & rng();  // sparse and dense words alike
    EXPECT_EQ(bit_count(w), uint32_t(std::popcount(w)));
    EXPECT_EQ(bit_count(~w), uint32_t(std::popcount(~w)));
  }
}

TEST(PolygonizeCellBits, EdgesAndCellsAreThoseOfThePerNodeTest) {
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  int mixed_cells = 0, crossing_edges = 0, ranged_blocks = 0;
  for (int trial = 0; trial < 3000; ++trial) {
    const double T = trial % 3 == 0 ? double(float(u(rng))) : 0.05 + u(rng);
    const std::vector<float> hard = near_threshold(T);
    // Samples: at and around T, far on either side, the infinities; some blocks nearly all
    // one state (most of a block the surface passes through), so the rows run all 0 or all 1.
    const double p_hard = u(rng), bias = u(rng);
    std::vector<float> local(size_t(kL * kL * kL));
    for (float& v : local) {
      const double r = u(rng);
      if (r < p_hard) v = hard[size_t(rng() % hard.size())];
      else if (r < p_hard + 0.02) v = rng() % 2 ? kInf : 0.0f;
      else v = u(rng) < bias ? float(T * (1.0 + u(rng))) : float(T * u(rng));
    }
    // A tile's range around block b = (1, 2, 3): none, or cells cut anywhere near the block.
    const int64_t b[3] = {1, 2, 3};
    int64_t cmin[3], cmax[3];
    const bool ranged = trial % 2 == 1;
    for (int a = 0; a < 3; ++a) {
      const int64_t lo = b[a] * kB - 2 + int64_t(rng() % 12), hi = lo + 1 + int64_t(rng() % 12);
      cmin[a] = ranged ? lo : -1000;
      cmax[a] = ranged ? hi : 1000;
    }
    ranged_blocks += ranged;
    const BlockRange rg = ranged ? block_range(b, cmin, cmax) : BlockRange{};
    auto in = [&](int x, int y, int z) { return double(local[size_t(x + kL * (y + kL * z))]) >= T; };
    auto cell_in_range = [&](int x, int y, int z) {
      const int64_t c[3] = {b[0] * kB + x, b[1] * kB + y, b[2] * kB + z};
      for (int a = 0; a < 3; ++a)
        if (c[a] < cmin[a] || c[a] >= cmax[a]) return false;
      return true;
    };
    auto edge_in_range = [&](int x, int y, int z, int axis) {
      const int64_t c[3] = {b[0] * kB + x, b[1] * kB + y, b[2] * kB + z};
      for (int a = 0; a < 3; ++a)
        if (c[a] < cmin[a] || c[a] > (a == axis ? cmax[a] - 1 : cmax[a])) return false;
      return true;
    };

    uint16_t rows[kL * kL];
    inside_rows(local.data(), float_threshold(T), rows);
    for (int z = 0; z < kL; ++z)
      for (int y = 0; y < kL; ++y)
        for (int x = 0; x < kL; ++x) ASSERT_EQ(((rows[y + kL * z] >> x) & 1) != 0, in(x, y, z));

    uint64_t mask[kMaskWords];
    crossing_mask(rows, rg, mask);
    uint64_t expected[kMaskWords] = {};
    for (int z = 0; z < kB; ++z)
      for (int y = 0; y < kB; ++y)
        for (int x = 0; x < kB; ++x)
          for (int a = 0; a < 3; ++a) {
            const bool other = in(x + (a == 0), y + (a == 1), z + (a == 2));
            if (other != in(x, y, z) && edge_in_range(x, y, z, a)) {
              const int bit = 3 * (x + kB * (y + kB * z)) + a;
              expected[bit >> 6] |= uint64_t(1) << (bit & 63);
              ++crossing_edges;
            }
          }
    for (int w = 0; w < kMaskWords; ++w) ASSERT_EQ(mask[w], expected[w]) << "trial " << trial << " word " << w;

    std::vector<std::tuple<int, int, int, int>> cells, expected_cells;
    for_each_mixed_cell(rows, rg, [&](int x, int y, int z, int cs) { cells.emplace_back(x, y, z, cs); });
    for (int z = 0; z < kB; ++z)
      for (int y = 0; y < kB; ++y)
        for (int x = 0; x < kB; ++x) {
          int cs = 0;
          for (int c = 0; c < 8; ++c)
            if (in(x + (c & 1), y + ((c >> 1) & 1), z + ((c >> 2) & 1))) cs |= 1 << c;
          if (cs != 0 && cs != 255 && cell_in_range(x, y, z)) expected_cells.emplace_back(x, y, z, cs);
        }
    ASSERT_EQ(cells, expected_cells) << "trial " << trial;
    mixed_cells += int(cells.size());
  }
  // The trials did reach the cases they are for.
  EXPECT_GT(mixed_cells, 100000);
  EXPECT_GT(crossing_edges, 100000);
  EXPECT_EQ(ranged_blocks, 1500);
}
