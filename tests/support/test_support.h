// Shared helpers for the C++ test suites.
#pragma once

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <functional>
#include <map>
#include <numbers>
#include <numeric>
#include <random>
#include <set>
#include <string>
#include <vector>

#include "particlemesh/core/error.h"
#include "particlemesh/mesh/point_cloud.h"
#include "particlemesh/mesh/tri_mesh.h"
#include "particlemesh/sample/shapes.h"

namespace particlemesh::test {

/// Built with AddressSanitizer (scripts/sanitize.sh): the long tests run on smaller inputs
/// there (the same code paths; every call costs 3-10 times as much).
#if defined(__SANITIZE_ADDRESS__)
inline constexpr bool kSanitized = true;
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
inline constexpr bool kSanitized = true;
#else
inline constexpr bool kSanitized = false;
#endif
#else
inline constexpr bool kSanitized = false;
#endif

/// The status a call ends with: Ok, or the Error it throws (its message into *message).
inline Status status_of(const std::function<void()>& f, std::string* message = nullptr) {
  try {
    f();
  } catch (const Error& e) {
    if (message) *message = e.what();
    return e.status();
  }
  return Status::Ok;
}

/// Path of a file in the shared data folder (PM_TEST_DATA, set by CTest), or "" when the
/// folder is absent; use PM_REQUIRE_DATA to skip with a message.
inline std::string shared_data(const std::string& relative) {
  const char* dir = std::getenv("PM_TEST_DATA");
  if (dir == nullptr) return {};
  const std::filesystem::path p = std::filesystem::path(dir) / relative;
  return std::filesystem::exists(p) ? p.string() : std::string();
}

#define PM_REQUIRE_DATA(var, relative)                                                        \
  const std::string var = ::particlemesh::test::shared_data(relative);                        \
  if (var.empty()) GTEST_SKIP() << "shared test data " << (relative)                          \
                                << " not found (set PM_TEST_DATA to the shared/data folder)"

/// A scratch folder under the build tree, emptied per test.
inline std::filesystem::path scratch_dir(const std::string& name) {
  const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
  std::filesystem::path p = std::filesystem::temp_directory_path() / "particlemesh_tests" /
                            (std::string(info->test_suite_name()) + "." + info->name() + "." + name);
  std::filesystem::remove_all(p);
  std::filesystem::create_directories(p);
  return p;
}

/// Non-manifold meshes: a "book" of flat pages (a grid of nr x nz quads each, in the directions
/// `angles` around the z axis) sharing their spine, the segment x = y = 0, 0 <= z <= 1 (nz
/// edges in as many triangles as pages); and two closed tetrahedra sharing the edge (0, 1), in
/// four triangles, with no boundary.
inline TriMesh book_mesh(const std::vector<double>& angles, int nz = 4, int nr = 3) {
  TriMesh m;
  std::vector<uint32_t> spine(size_t(nz) + 1);
  for (int j = 0; j <= nz; ++j) spine[size_t(j)] = uint32_t(j), m.positions.push_back({0, 0, double(j) / nz});
  for (double a : angles) {
    auto at = [&](int i, int j) -> uint32_t {
      if (i == 0) return spine[size_t(j)];
      return uint32_t(m.positions.size() - size_t(nr * (nz + 1)) + size_t((i - 1) * (nz + 1) + j));
    };
    for (int i = 1; i <= nr; ++i)
      for (int j = 0; j <= nz; ++j) {
        const double r = double(i) / nr;
        m.positions.push_back({r * std::cos(a), r * std::sin(a), double(j) / nz});
      }
    for (int i = 0; i < nr; ++i)
      for (int j = 0; j < nz; ++j) {
        const uint32_t p = at(i, j), q = at(i + 1, j), r = at(i + 1, j + 1), s = at(i, j + 1);
        m.triangles.push_back({p, q, r});
        m.triangles.push_back({p, r, s});
      }
  }
  return m;
}

inline TriMesh tetrahedra_sharing_an_edge() {
  TriMesh m;
  m.positions = {{0, 0, 0}, {1, 0, 0}, {0.3, 1, 0}, {0.4, 0.3, 1}, {0.5, -1, 0.2}, {0.4, -0.3, -1}};
  const Triangle tet[4] = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};
  for (const Triangle& t : tet) m.triangles.push_back(t);
  for (Triangle t : tet) {  // the second: 2 -> 4, 3 -> 5, wound to face out of its own solid
    for (auto& v : t) v = v == 2 ? 4 : v == 3 ? 5 : v;
    std::swap(t[1], t[2]);
    m.triangles.push_back(t);
  }
  return m;
}

/// Triangles as sorted vertex triples in a sorted vector (orientation ignored).
inline std::vector<Triangle> canonical(std::vector<Triangle> t) {
  for (auto& x : t) std::sort(x.begin(), x.end());
  std::sort(t.begin(), t.end());
  return t;
}

/// Uniform random points in [0, size)^3 with a fixed seed.
inline PointCloud random_cloud(size_t n, uint64_t seed, double size = 1.0) {
  std::mt19937_64 rng(seed);
  auto u = [&] { return double(rng() >> 11) * 0x1.0p-53 * size; };
  PointCloud c;
  for (size_t i = 0; i < n; ++i) c.positions.push_back({u(), u(), u()});
  return c;
}

/// The cloud with Gaussian noise of deviation sigma added to every coordinate (fixed seed).
inline PointCloud jittered(PointCloud c, double sigma, uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> g(0.0, sigma);
  for (auto& p : c.positions) p += Vec3{g(rng), g(rng), g(rng)};
  return c;
}

/// A Fibonacci sphere with its lower half `dense` points' worth and its upper half `sparse`'s.
inline PointCloud two_density_sphere(size_t dense, size_t sparse) {
  PointCloud out;
  for (const Vec3& p : fibonacci_sphere(dense).positions)
    if (p.z < 0) out.positions.push_back(p);
  for (const Vec3& p : fibonacci_sphere(sparse).positions)
    if (p.z >= 0) out.positions.push_back(p);
  return out;
}

/// n points dropped uniformly at random on a triangle mesh (each in a triangle chosen by area,
/// uniformly inside it), fixed seed: what Blender's "Random" emission, or sampling a mesh
/// uniformly by area, gives - a Poisson process, not an even sampling.
inline PointCloud random_surface_sample(const TriMesh& mesh, size_t n, uint64_t seed) {
  std::vector<double> area(mesh.triangles.size());
  for (size_t f = 0; f < area.size(); ++f) {
    const Triangle& t = mesh.triangles[f];
    const Vec3 a = mesh.positions[t[0]], b = mesh.positions[t[1]], c = mesh.positions[t[2]];
    area[f] = norm(cross(b - a, c - a));
  }
  std::partial_sum(area.begin(), area.end(), area.begin());
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  PointCloud out;
  for (size_t i = 0; i < n; ++i) {
    const size_t f = size_t(std::upper_bound(area.begin(), area.end(), u(rng) * area.back()) - area.begin());
    const Triangle& t = mesh.triangles[std::min(f, area.size() - 1)];
    double x = u(rng), y = u(rng);
    if (x + y > 1) x = 1 - x, y = 1 - y;
    const Vec3 a = mesh.positions[t[0]];
    out.positions.push_back(a + (mesh.positions[t[1]] - a) * x + (mesh.positions[t[2]] - a) * y);
  }
  return out;
}

/// n points uniformly at random on the unit sphere (z and the angle around it uniform:
/// Archimedes' equal areas), fixed seed.
inline PointCloud random_sphere(size_t n, uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  PointCloud out;
  for (size_t i = 0; i < n; ++i) {
    const double z = 2 * u(rng) - 1, phi = 2 * std::numbers::pi * u(rng), r = std::sqrt(1 - z * z);
    out.positions.push_back({r * std::cos(phi), r * std::sin(phi), z});
  }
  return out;
}

/// Every point of `c` written `copies` times in a row (point i at copies x i ... copies x i +
/// copies - 1): a file written twice, a scan merged with itself, Blender's jittered emission
/// repeating its pattern.
inline PointCloud with_copies(const PointCloud& c, size_t copies) {
  PointCloud out;
  for (const Vec3& p : c.positions) out.positions.insert(out.positions.end(), copies, p);
  return out;
}

/// A sheet near z = 0 sampled in rows: `along` apart within a row, rows `across` apart,
/// alternate rows shifted by half a step (a depth camera's rows on a surface seen at a grazing
/// angle), jittered by up to 5 % of the steps in x and y, and by up to 5 % of `along` in z when
/// `jitter_z` (else exactly flat).
inline PointCloud row_sheet(size_t nx, size_t ny, double along, double across, uint64_t seed, bool jitter_z) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(-0.05, 0.05);
  PointCloud c;
  for (size_t j = 0; j < ny; ++j)
    for (size_t i = 0; i < nx; ++i) {
      const double x = (double(i) + 0.5 * double(j % 2) + u(rng)) * along;
      const double y = (double(j) + u(rng)) * across;
      c.positions.push_back({x, y, jitter_z ? u(rng) * along : 0.0});
    }
  return c;
}

/// One row of a depth camera at the origin (columns `du` apart in tan(angle), the row at
/// y/z = -0.4) on a plane inclined along the row, its depths rounded to `quantum` as a depth
/// sensor's are: runs of points in line at one depth, each run a step from the next - a curve
/// of samples, nothing beside it (what a voxel grid leaves of a scan where one row remains).
inline PointCloud one_depth_row(size_t columns, double du, double quantum) {
  PointCloud c;
  for (size_t i = 0; i < columns; ++i) {
    const double u = (double(i) - 0.5 * double(columns)) * du;
    const double z = quantum * std::round(1.0 / (1.0 - 0.5 * u) / quantum);
    c.positions.push_back({u * z, -0.4 * z, z});
  }
  return c;
}

/// Undirected edge -> number of triangles using it.
inline std::map<std::pair<uint32_t, uint32_t>, int> edge_counts(const std::vector<Triangle>& tris) {
  std::map<std::pair<uint32_t, uint32_t>, int> e;
  for (const auto& t : tris)
    for (int c = 0; c < 3; ++c) {
      uint32_t a = t[c], b = t[(c + 1) % 3];
      if (a > b) std::swap(a, b);
      ++e[{a, b}];
    }
  return e;
}

}  // namespace particlemesh::test
