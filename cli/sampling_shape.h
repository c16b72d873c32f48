// What the measures of a cloud's sampling (LocalSpacing::thickness) say about meshing it:
// shared by triangulate's hints and inspect's particle report.
#pragma once

#include "particlemesh/spatial/local_spacing.h"

namespace particlemesh::cli {

/// A sampling thicker than this scatters across its surface (the library's threshold:
/// bench/RESULTS.md, "Exact copies of particles, and noise across the surface").
constexpr double kNoisyThickness = kNoisySamplingThickness;
/// ... up to this: thicker, the particles fill a volume.
constexpr double kVolumeThickness = kVolumeSamplingThickness;

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
