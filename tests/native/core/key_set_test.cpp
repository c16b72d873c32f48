#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <set>
#include <vector>

#include "core/hashing.h"

namespace pm = particlemesh;

namespace {
std::vector<uint64_t> sorted_keys(const pm::detail::KeySet& s) {
  std::vector<uint64_t> v;
  for (const uint64_t k : s) v.push_back(k);
  std::sort(v.begin(), v.end());
  return v;
}
}  // namespace

// Random inserts and erases, many keys crowding few slots' neighbourhoods (the surface's
// half-edges of nearby vertices: keys that differ in a few low bits), against std::set: the
// same answers, size and keys after every step of a churn that grows the table and empties
// it again (erase's backward shift keeps every key findable).
TEST(KeySet, AgreesWithStdSetThroughInsertsAndErases) {
  std::mt19937_64 rng(5);
  for (const uint64_t spread : {uint64_t(64), uint64_t(5000), ~uint64_t(0) - 1}) {
    pm::detail::KeySet s;
    std::set<uint64_t> ref;
    std::uniform_int_distribution<uint64_t> key(0, spread);
    for (int step = 0; step < 60000; ++step) {
      const uint64_t k = (uint64_t(7) << 32) | key(rng);
      // Inserts first (the table grows), then mostly erases (it empties).
      const bool add = step < 30000 ? rng() % 4 != 0 : rng() % 4 == 0;
      if (add)
        ASSERT_EQ(s.insert(k), ref.insert(k).second) << step;
      else
        ASSERT_EQ(s.erase(k), ref.erase(k) == 1) << step;
      ASSERT_EQ(s.size(), ref.size());
      if (step % 5000 == 0) ASSERT_EQ(sorted_keys(s), std::vector<uint64_t>(ref.begin(), ref.end())) << step;
    }
    EXPECT_EQ(sorted_keys(s), std::vector<uint64_t>(ref.begin(), ref.end()));
    for (const uint64_t k : std::vector<uint64_t>(ref.begin(), ref.end())) EXPECT_TRUE(s.erase(k));
    EXPECT_TRUE(s.empty());
    EXPECT_EQ(s.begin() != s.end(), false);
  }
}

// A table kept nearly half full, smallest and larger (16 and 1024 slots), with a key erased
// and another inserted at every step: clusters wrap around the end of the slots, and each
// erase shifts back keys whose probe wrapped.
TEST(KeySet, NearlyFullTablesKeepEveryKeyThroughChurn) {
  std::mt19937_64 rng(9);
  for (const size_t keep : {size_t(7), size_t(511)}) {
    pm::detail::KeySet s;
    std::vector<uint64_t> ref;
    while (ref.size() < keep) {
      const uint64_t k = rng() >> 1;
      if (s.insert(k)) ref.push_back(k);
    }
    for (int step = 0; step < 20000; ++step) {
      const size_t i = rng() % ref.size();
      ASSERT_TRUE(s.erase(ref[i])) << step;
      ASSERT_FALSE(s.erase(ref[i])) << step;
      ref[i] = rng() >> 1;
      ASSERT_TRUE(s.insert(ref[i])) << step;
      ASSERT_FALSE(s.insert(ref[i])) << step;
      if (keep < 100 || step % 1000 == 0) {
        std::vector<uint64_t> expected = ref;
        std::sort(expected.begin(), expected.end());
        ASSERT_EQ(sorted_keys(s), expected) << step;
      }
    }
  }
}

// The key tables of the grids: every key found at its index, and keys not in the table not
// found, for a few keys (filled one at a time) and for many (filled in parallel, where which
// key takes which slot depends on the threads), with keys crowding a few neighbourhoods of
// slots (the cells of one column: keys that differ in their low bits) and spread ones.
TEST(KeyTable, EveryKeyFoundAtItsIndexFilledSeriallyOrInParallel) {
  std::mt19937_64 rng(13);
  for (const size_t count : {size_t(1000), size_t(300000)}) {
    for (const bool crowded : {true, false}) {
      std::vector<uint64_t> keys;
      for (size_t i = 0; i < count; ++i) keys.push_back(crowded ? (uint64_t(i / 64) << 21) + i % 64 : rng() >> 1);
      std::sort(keys.begin(), keys.end());
      keys.erase(std::unique(keys.begin(), keys.end()), keys.end());
      for (const int threads : {1, 2, 4}) {
        std::vector<uint32_t> table;
        const uint64_t mask =
            pm::detail::with_threads(threads, [&] { return pm::detail::build_key_table(keys, table); });
        ASSERT_EQ(table.size(), mask + 1);
        ASSERT_GE(table.size(), 2 * keys.size());
        for (size_t i = 0; i < keys.size(); ++i)
          ASSERT_EQ(pm::detail::find_key(table, mask, keys, keys[i]), uint32_t(i)) << count << " " << threads;
        // Absent keys: between two present ones, and past the last.
        for (size_t i = 0; i + 1 < keys.size(); i += 97)
          if (keys[i] + 1 != keys[i + 1])
            EXPECT_EQ(pm::detail::find_key(table, mask, keys, keys[i] + 1), pm::detail::kNoKey);
        EXPECT_EQ(pm::detail::find_key(table, mask, keys, keys.back() + 1), pm::detail::kNoKey);
        // Every slot holds a key's index or is empty, and each index is in one slot.
        std::vector<uint8_t> seen(keys.size(), 0);
        for (const uint32_t s : table)
          if (s != pm::detail::kNoKey) {
            ASSERT_LT(s, keys.size());
            ASSERT_EQ(seen[s]++, 0);
          }
      }
    }
  }
}
