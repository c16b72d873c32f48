#include <gtest/gtest.h>

#include <cfloat>
#include <cmath>
#include <string>

#include "particlemesh/core/error.h"
#include "particlemesh/mesh/point_cloud.h"

namespace pm = particlemesh;

namespace {
// The message validate_point_cloud throws for `c`, or "" when it accepts it.
std::string rejection(const pm::PointCloud& c) {
  try {
    pm::validate_point_cloud(c);
  } catch (const pm::Error& e) {
    EXPECT_EQ(e.status(), pm::Status::InvalidInput);
    return e.what();
  }
  return "";
}
}  // namespace

// The coordinates are checked in blocks, in parallel: the error still names the first bad
// value (by index, then axis), wherever the bad values lie, in the positions and then the
// normals; every finite value, the extreme ones too, passes.
TEST(ValidatePointCloud, NamesTheFirstValueThatIsNotFinite) {
  pm::PointCloud c;
  for (int i = 0; i < 100000; ++i) c.positions.push_back({0.001 * i, std::sin(0.01 * i), -0.5 * i});
  c.normals.assign(c.positions.size(), pm::Vec3{0, 0, 1});
  c.positions[7].x = DBL_MAX;
  c.positions[8].y = -0.0;
  c.positions[9].z = DBL_MIN / 4;  // subnormal
  c.positions[99999].z = -DBL_MAX;
  EXPECT_EQ(rejection(c), "");
  pm::PointCloud bad = c;
  bad.positions[90000].x = INFINITY;
  bad.positions[70001].y = NAN;
  bad.positions[70001].z = INFINITY;
  EXPECT_NE(rejection(bad).find("positions[70001].y is NaN"), std::string::npos) << rejection(bad);
  bad.positions[16384].z = -INFINITY;  // the first of a block
  EXPECT_NE(rejection(bad).find("positions[16384].z is infinite"), std::string::npos) << rejection(bad);
  bad.positions[16383].x = NAN;  // the last of the block before
  EXPECT_NE(rejection(bad).find("positions[16383].x is NaN"), std::string::npos) << rejection(bad);
  bad = c;
  bad.positions[99999].x = NAN;  // the last point
  EXPECT_NE(rejection(bad).find("positions[99999].x is NaN"), std::string::npos) << rejection(bad);
  bad = c;
  bad.normals[50000].y = NAN;
  EXPECT_NE(rejection(bad).find("normals[50000].y is NaN"), std::string::npos) << rejection(bad);
}
