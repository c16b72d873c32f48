// What the measures of a cloud's sampling (LocalSpacing::thickness) say about meshing it:
// shared by triangulate's hints and inspect's particle report.
#pragma once

#include "particlemesh/spatial/local_spacing.h"

namespace particlemesh::cli {

/// What a thickness says (the library's bounds, particlemesh/spatial/local_spacing.h:
/// kNoisySamplingThickness, kVolumeSamplingThickness), in a few words for the summaries
/// (`mls`: whether this build has --mls to name).
inline const char* thickness_meaning(double thickness, bool mls) {
  if (!(thickness > kNoisySamplingThickness)) return "a clean surface";
  if (noisy_sampling(thickness))
    return mls ? "scattered across a surface, as a noisy scan's (triangulate --mls smooths it)"
               : "scattered across a surface, as a noisy scan's";
  return "filling a volume (polygonize meshes it)";
}

}  // namespace particlemesh::cli
