// Internal entry of the local spacing estimate, sharing the caller's progress tracker.
#pragma once

#include "particlemesh/core/config.h"

#include <vector>

#include "core/progress_tracker.h"
#include "particlemesh/spatial/local_spacing.h"

namespace PM_NAMESPACE::detail {

/// The neighbours each point's local spacing is taken over.
constexpr int kLocalSpacingNeighbors = 16;
/// On an even (Poisson-disk) surface sampling whose median nearest-neighbour distance is r,
/// the third nearest of the six 60-degree sectors' nearest neighbours around a point is about
/// kSectorReach x r away.
constexpr double kSectorReach = 1.22;
/// A neighbour more than this times as far as the one before ends a point's neighbourhood.
constexpr double kGap = 2.0;
/// The sector reaches are smoothed by this quantile over each point's neighbourhood ...
constexpr double kSmoothQuantile = 0.9;
/// ... divided by this, the quantile's bias on an even (Poisson-disk) sampling, so that its
/// local spacing is its median nearest-neighbour distance.
constexpr double kSmoothBias = 1.16;
/// Local spacings within this fraction of the cloud's r0 are taken as r0 (see triangulate.cpp).
constexpr double kSpacingBand = 0.15;
/// A mesh's local spacings are held to at most this many times its r0 (the median nearest-
/// neighbour distance): sparser than that, samples are too far apart to be one surface at the
/// cloud's scale.
constexpr double kMaxLocalSpacing = 3.0;
/// How irregular a sampling is: the median over the points of the coefficient of variation
/// (standard deviation over mean) of the nearest-neighbour distances of the point and its
/// neighbourhood. Evenly spaced samplings (Poisson-disk samples, lattices, a model's
/// vertices, scans after a voxel grid) measure 0 to about 0.3; points dropped uniformly at
/// random on a surface (a Poisson process: Blender's "Random" emission, a mesh sampled
/// uniformly by area) about 0.5, the Rayleigh distribution's sqrt(4 / pi - 1) = 0.52 less the
/// bias of a 17-point estimate. There the triangles that cover the surface reach much farther
/// than the nearest neighbours: on a uniformly random sample of a sphere the longest edge of
/// 29 % of its Delaunay triangles exceeds twice the local spacing (16 % of the edges; 0.35 %
/// exceed 3.3 times it), so the edge limits are lengthened by irregular_reach().
/// Up to kRegularSampling the limits are as they are ...
constexpr double kRegularSampling = 0.35;
/// ... from kRandomSampling on they are kRandomReach times as long, in between in proportion.
/// 1.75 (edges up to 3.5 local spacings at the default factor 2) as measured on 20k points at
/// random on a sphere, a torus and three models (bench/RESULTS.md, "Particles at random"):
/// 1.5 left loops open on the sphere and the models; 2 closed one of the bunny's five real
/// openings (1.75 keeps four or all five of them, by sample).
constexpr double kRandomSampling = 0.45;
constexpr double kRandomReach = 1.75;

/// The factor the edge limits are lengthened by on a sampling of this irregularity (1 for
/// every evenly spaced sampling).
inline double irregular_reach(double irregularity) {
  const double f = (irregularity - kRegularSampling) / (kRandomSampling - kRegularSampling);
  return 1.0 + (kRandomReach - 1.0) * (f > 1.0 ? 1.0 : f > 0.0 ? f : 0.0);
}

/// Neighbours spread along a line when the second variance of their plane fit is below this
/// fraction of the first (a half disk, at an edge of the surface: about 0.28).
constexpr double kElongated = 0.05;

/// A triangle with an angle over this many degrees is flat: its corners nearly in line (the
/// surface's growth takes such triangles last; see surface/candidates.h).
constexpr double kFlatAngle = 150.0;

/// What the local spacing measures of the sampling as a whole (LocalSpacing::irregularity and
/// ::thickness; 0 when no point has the neighbours for it); and, over the points whose local
/// spacing lies past kMaxLocalSpacing x r0, the median of their local spacing over the median
/// nearest-neighbour distance around them (TriangulateStats::capped_spacing_over_nn; 0 when
/// no point's does).
struct SamplingShape {
  double irregularity = 0;
  double thickness = 0;
  double capped_spacing_over_nn = 0;
};

/// Per input point (see estimate_local_spacing); r0 = the cloud's median nearest-neighbour
/// distance (sets the grid). Assumes finite coordinates; runs in the caller's TBB arena.
/// `shape`, when given, receives the sampling's irregularity (see kRegularSampling) and
/// thickness.
std::vector<double> local_spacing_impl(const Vec3* points, size_t n, double r0, ProgressTracker& tracker,
                                       double begin, double end, SamplingShape* shape = nullptr);

}  // namespace particlemesh::detail
