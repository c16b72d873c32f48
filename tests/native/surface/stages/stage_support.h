// Small surfaces for the tests of the surface stages (surface/*.h, the library's internals).
#pragma once

#include <cstdint>
#include <vector>

#include "core/progress_tracker.h"
#include "particlemesh/core/progress.h"
#include "particlemesh/mesh/tri_mesh.h"
#include "surface/candidates.h"
#include "surface/editable_surface.h"

namespace particlemesh::test {

/// A flat sheet of nx x ny points at unit spacing in the plane z = 0, normals +z, and its
/// triangles (two per square, counter-clockwise seen from +z). Point (i, j) is i + nx j.
struct Sheet {
  std::vector<Vec3> P, N;
  std::vector<detail::Frame> frames;
  std::vector<Triangle> tris;
  size_t nx = 0, ny = 0;

  Sheet(size_t nx_, size_t ny_) : nx(nx_), ny(ny_) {
    for (size_t j = 0; j < ny; ++j)
      for (size_t i = 0; i < nx; ++i) {
        P.push_back({double(i), double(j), 0});
        N.push_back({0, 0, 1});
      }
    frames = detail::tangent_frames(N);
    for (size_t j = 0; j + 1 < ny; ++j)
      for (size_t i = 0; i + 1 < nx; ++i) {
        const uint32_t a = id(i, j), b = id(i + 1, j), c = id(i + 1, j + 1), d = id(i, j + 1);
        tris.push_back({a, b, c});
        tris.push_back({a, c, d});
      }
  }
  uint32_t id(size_t i, size_t j) const { return uint32_t(i + nx * j); }
  /// The triangles without those that have a corner in `out`.
  std::vector<Triangle> without(const std::vector<uint32_t>& out) const {
    std::vector<Triangle> kept;
    for (const Triangle& t : tris) {
      bool hit = false;
      for (uint32_t v : t)
        for (uint32_t o : out) hit = hit || v == o;
      if (!hit) kept.push_back(t);
    }
    return kept;
  }
};

/// A tracker with no callback, for calls that need one.
struct QuietTracker {
  ProgressCallback none;
  detail::ProgressTracker tracker{none};
};

}  // namespace particlemesh::test
