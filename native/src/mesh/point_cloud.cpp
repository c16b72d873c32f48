#include "particlemesh/mesh/point_cloud.h"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

#include "core/parallel.h"
#include "particlemesh/core/error.h"

namespace PM_NAMESPACE {

namespace {
const char* bad_value_name(double v) { return std::isnan(v) ? "NaN" : "infinite"; }

/// Whether every coordinate of values[b, e) is finite: its exponent bits not all set, tested
/// on the bits without a branch (a loop the compiler vectorises).
bool all_finite(const std::vector<Vec3>& values, size_t b, size_t e) {
  constexpr uint64_t kExponent = 0x7ff0000000000000ull;
  uint64_t any = 0;
  for (size_t i = b; i < e; ++i) {
    uint64_t c[3];
    std::memcpy(c, &values[i], sizeof c);
    any |= uint64_t((c[0] & kExponent) == kExponent) | uint64_t((c[1] & kExponent) == kExponent) |
           uint64_t((c[2] & kExponent) == kExponent);
  }
  return any == 0;
}

void check_vectors(const std::vector<Vec3>& values, const char* what) {
  // Checked in parallel blocks first (a million points one value at a time, on one core, were
  // a visible serial step); a block with a bad value is then read one value at a time, the
  // first such block only, so that the error names the first bad value.
  static_assert(sizeof(Vec3) == 3 * sizeof(double));
  constexpr size_t kBlock = 16384;
  const size_t n = values.size(), blocks = (n + kBlock - 1) / kBlock;
  std::vector<uint8_t> bad(blocks, 0);
  detail::parallel_blocks(blocks, 1, [&](size_t bb, size_t be) {
    for (size_t k = bb; k < be; ++k) bad[k] = !all_finite(values, k * kBlock, std::min(n, (k + 1) * kBlock));
  });
  const size_t first = size_t(std::find(bad.begin(), bad.end(), uint8_t(1)) - bad.begin());
  if (first == blocks) return;
  for (size_t i = first * kBlock; i < n; ++i) {
    const Vec3& p = values[i];
    for (int a = 0; a < 3; ++a) {
      if (!std::isfinite(p[a]))
        throw Error(Status::InvalidInput, std::string(what) + "[" + std::to_string(i) + "]." +
                                              "xyz"[a] + " is " + bad_value_name(p[a]));
    }
  }
}
}  // namespace

PointCloud select_points(const PointCloud& cloud, const std::vector<uint32_t>& indices) {
  PointCloud out;
  out.positions.reserve(indices.size());
  for (uint32_t i : indices) out.positions.push_back(cloud.positions[i]);
  if (cloud.has_normals())
    for (uint32_t i : indices) out.normals.push_back(cloud.normals[i]);
  for (const VertexAttribute& a : cloud.attributes) {
    VertexAttribute& b = out.attributes.emplace_back(VertexAttribute{a.name, a.components, {}});
    b.values.reserve(indices.size() * size_t(a.components));
    for (uint32_t i : indices)
      b.values.insert(b.values.end(), a.values.begin() + ptrdiff_t(i) * a.components,
                      a.values.begin() + ptrdiff_t(i + 1) * a.components);
  }
  out.not_read = cloud.not_read;
  return out;
}

void validate_point_cloud(const PointCloud& cloud) {
  if (!cloud.normals.empty() && cloud.normals.size() != cloud.positions.size())
    throw Error(Status::InvalidInput, "the cloud has " + std::to_string(cloud.positions.size()) +
                                          " positions but " + std::to_string(cloud.normals.size()) +
                                          " normals");
  check_vectors(cloud.positions, "positions");
  check_vectors(cloud.normals, "normals");
  for (const auto& a : cloud.attributes) {
    if (a.components < 1 || a.values.size() != cloud.positions.size() * size_t(a.components))
      throw Error(Status::InvalidInput, "attribute '" + a.name + "' has " +
                                            std::to_string(a.values.size()) + " values, expected " +
                                            std::to_string(cloud.positions.size()) + " x " +
                                            std::to_string(a.components));
  }
}

}  // namespace particlemesh
