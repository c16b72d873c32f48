// resize_touched: the same vector resize() makes, whatever the size and thread count.
#include <gtest/gtest.h>

#include <array>
#include <cstdint>
#include <vector>

#include "core/first_touch.h"
#include "core/parallel.h"
#include "particlemesh/core/vec3.h"

namespace pm = particlemesh;

namespace {

// A type whose value-initialised state is not all zero bits: the touch must not stand in
// for resize()'s construction.
struct Marked {
  uint32_t id = 0xFFFFFFFFu;
  float weight = 1.5f;
};

TEST(FirstTouch, LargeVectorsAreValueInitialisedLikeResize) {
  // 3 MiB of Vec3 is under the touch's threshold, 24 MiB over it (and not a whole number of
  // 2 MiB chunks or 4 KiB pages).
  for (const size_t n : {size_t(0), size_t(1), size_t(131072), size_t(1000003)}) {
    for (const int threads : {1, 2, 4}) {
      std::vector<pm::Vec3> v;
      pm::detail::with_threads(threads, [&] { pm::detail::resize_touched(v, n); });
      ASSERT_EQ(v.size(), n);
      for (size_t i = 0; i < n; ++i)
        ASSERT_TRUE(v[i].x == 0 && v[i].y == 0 && v[i].z == 0) << "element " << i << " of " << n;
    }
  }
  std::vector<std::array<uint32_t, 3>> t;
  pm::detail::resize_touched(t, 2000001);
  ASSERT_EQ(t.size(), 2000001u);
  for (const auto& tri : t) ASSERT_EQ(tri, (std::array<uint32_t, 3>{0, 0, 0}));
}

TEST(FirstTouch, DefaultMemberInitialisersAreKept) {
  std::vector<Marked> v;
  pm::detail::resize_touched(v, 3000000);  // 24 MB: touched first
  ASSERT_EQ(v.size(), 3000000u);
  for (const Marked& m : v) {
    ASSERT_EQ(m.id, 0xFFFFFFFFu);
    ASSERT_EQ(m.weight, 1.5f);
  }
}

TEST(FirstTouch, AVectorWithElementsKeepsThem) {
  // Elements 0 and 512 start at bytes 0 and 4096 of the storage: where a touch would write.
  std::vector<Marked> v(1000);
  v[0].id = 7;
  v[512].id = 9;
  pm::detail::resize_touched(v, 2000000);
  ASSERT_EQ(v.size(), 2000000u);
  EXPECT_EQ(v[0].id, 7u);
  EXPECT_EQ(v[512].id, 9u);
  EXPECT_EQ(v[1999999].id, 0xFFFFFFFFu);
}

}  // namespace
