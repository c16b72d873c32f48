// The Embree peer of the ray-casting benchmark: a triangle mesh into an Embree BVH, then one
// primary ray per pixel, behind a plain interface so that only its own translation unit
// includes Embree.
#pragma once

#include <cstdint>
#include <vector>

#include "particlemesh/core/vec3.h"

namespace peer {

struct EmbreeResult {
  double build_seconds = 0;  ///< rtcNewScene .. rtcCommitScene (the BVH)
  double trace_seconds = 0;  ///< the primary rays, with a Lambert shade of each hit
  uint64_t hits = 0;
  std::vector<uint8_t> hit;  ///< per pixel (row-major): 1 where the ray hit
};

/// Whether the benchmark was built with Embree.
bool embree_available();

/// Primary rays through a pinhole camera (eye, orthonormal forward / right / up, tan of half
/// the vertical and horizontal fields of view), as particlemesh's renderer casts them:
/// pixel (x, y) looks along forward + right (2 (x + 1/2) / W - 1) th + up (1 - 2 (y + 1/2) / H) tv.
/// `points`: x y z per vertex; `triangles`: three vertex indices each.
EmbreeResult embree_primary_rays(const std::vector<float>& points, const std::vector<uint32_t>& triangles,
                                 const particlemesh::Vec3& eye, const particlemesh::Vec3& forward,
                                 const particlemesh::Vec3& right, const particlemesh::Vec3& up, double tv, double th,
                                 int width, int height, int threads);

}  // namespace peer
