// What the measures of a cloud's sampling (LocalSpacing::thickness) say about meshing it:
// shared by triangulate's hints and inspect's particle report.
#pragma once

namespace particlemesh::cli {

/// A sampling thicker than this scatters across its surface: clean surfaces measured under
/// 0.2 (a coarse model's vertices, from its curvature, up to 0.19), depth-camera scans
/// 0.24-0.30, points moved off a sphere by noise of half their spacing 0.37 (bench/RESULTS.md,
/// "Exact copies of particles, and noise across the surface").
constexpr double kNoisyThickness = 0.22;
/// ... up to this: thicker, the particles fill a volume (a block of SPH particles measured
/// 0.86; the noisiest sphere, moved off by noise of a whole spacing, 0.59).
constexpr double kVolumeThickness = 0.75;

/// What a thickness says, in a few words for the summaries (`mls`: whether this build has
/// --mls to name).
inline const char* thickness_meaning(double thickness, bool mls) {
  if (!(thickness > kNoisyThickness)) return "a clean surface";
  if (thickness < kVolumeThickness)
    return mls ? "scattered across a surface, as a noisy scan's (triangulate --mls smooths it)"
               : "scattered across a surface, as a noisy scan's";
  return "filling a volume (polygonize meshes it)";
}

}  // namespace particlemesh::cli
