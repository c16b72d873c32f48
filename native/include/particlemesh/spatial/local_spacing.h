// Each particle's own spacing, from its neighbourhood: real scans are sampled unevenly (a
// depth camera's samples spread with the distance; a turntable scan is denser where the
// surface faces the sensor), so one spacing for the whole cloud is too short in some places
// and too long in others.
#pragma once

#include "particlemesh/core/config.h"

#include <cstddef>
#include <vector>

#include "particlemesh/core/export.h"
#include "particlemesh/core/progress.h"
#include "particlemesh/core/vec3.h"

namespace PM_NAMESPACE {

struct LocalSpacing {
  /// Per input point: the spacing of the sampling around it (see estimate_local_spacing).
  /// Exact duplicates are one point: every copy gets its place's spacing.
  std::vector<double> spacing;
  /// The median nearest-neighbour distance of the distinct points (what estimate_spacing
  /// returns): the cloud's typical spacing r0.
  double median_nn = 0;
  /// How irregular the sampling is: the median over the points of the coefficient of variation
  /// of the nearest-neighbour distances around each (the point's and its neighbourhood's).
  /// Evenly spaced samplings measure 0 to about 0.3; points dropped uniformly at random on a
  /// surface about 0.5. Above 0.35 triangulation lengthens its edge limits (up to 1.75 x from
  /// 0.45 on): there the triangles that cover the surface reach farther than the spacing says.
  double irregularity = 0;
  /// The factor triangulation lengthens every edge limit by for that irregularity: 1 up to
  /// 0.35, 1.75 from 0.45 on, in proportion between.
  double reach_factor = 1;
  /// How far the points scatter across the surface: the median over the points of
  /// sqrt(lambda_0 / lambda_1), the spread of the point's nearest neighbours off the plane
  /// fitted to them over their spread along its second direction. Evenly sampled clean surfaces
  /// measure under 0.2 (0.02 on a fine sphere; a coarse model's vertices up to ~0.2 from its
  /// curvature), depth-camera scans 0.25-0.3, a surface whose points are moved off it by noise
  /// of half their spacing ~0.37 and of a whole spacing ~0.6, particles filling a volume ~0.85.
  double thickness = 0;
};

/// A sampling thicker than this (LocalSpacing::thickness) scatters across its surface: clean
/// surfaces measured under 0.2 (a coarse model's vertices, from its curvature, up to 0.19),
/// depth-camera scans 0.24-0.30, points moved off a sphere by noise of half their spacing
/// 0.37. Triangulation's normal orientation trusts edges between two sheets less there, and
/// the command-line tool's hints offer smoothing.
constexpr double kNoisySamplingThickness = 0.22;
/// ... up to this: thicker, the particles fill a volume (a block of SPH particles measured
/// 0.86; the noisiest sphere, moved off by noise of a whole spacing, 0.59): polygonize's.
constexpr double kVolumeSamplingThickness = 0.75;
/// From this on a noisy surface's samples are as thick as a thin layer of volume particles (a
/// sphere moved off by noise of 0.7 spacings measured 0.47, a fluid's SPH frame 0.54): where
/// triangulation leaves loops open, it says they may be volume particles (SurfaceStats::
/// looks_like_volume), which polygonize meshes.
constexpr double kThinLayerSamplingThickness = 0.45;
/// Whether a sampling of this thickness scatters across a surface without filling a volume.
constexpr bool noisy_sampling(double thickness) {
  return thickness > kNoisySamplingThickness && thickness < kVolumeSamplingThickness;
}

/// The local spacing of every point, from its 16 nearest neighbours (up to the first one more
/// than twice as far as the one before: a stray cluster is a neighbourhood of its own). The
/// larger of
///  - the median nearest-neighbour distance around it (the median over its neighbourhood of
///    the medians of the neighbours' nearest-neighbour distances): what r0 is for the whole
///    cloud, not raised at the rim of an opening, where a point has neighbours on one side;
///  - its sector reach: in the plane fitted to the neighbours, the nearest neighbour in each
///    of six 60-degree sectors (centred on the direction they spread most along), the third
///    nearest of those, smoothed by the 90th percentile over the neighbourhood, in units of
///    what an even (Poisson-disk) sampling gives. Where the sampling is denser along one
///    direction than across it (a depth camera's rows on a surface seen at a grazing angle, a
///    line scanner's lines) most sectors' nearest lie across, and the reach is the spacing
///    across; neighbours all on one line widen the neighbourhood until it spans the surface.
///    Where no plane spans it even then - a curve of samples (one row of a depth camera that
///    the downsampling left on its own, a wire), or fewer than six neighbours (a small
///    cluster) - the reach is the longest edge of the shortest triangle the point makes with
///    two of its neighbours with no angle over 150 degrees (on an even sampling about the
///    sector reach too): the reach that lets a surface take the point in at all. A point whose
///    neighbours all lie in one line gets none.
/// The neighbourhoods are taken over the distinct points: exact copies of a point (a file
/// written twice, a scan merged with itself, Blender's jittered emission repeating its pattern)
/// are not each other's neighbours, and the spacings and the irregularity are those of the
/// cloud without them.
/// An even sampling gets its median nearest-neighbour distance everywhere (within ~15 %).
/// Deterministic (the same for any thread count and input order) and linear in the points for
/// surface samplings (a uniform grid); O(N) memory.
/// @throws Error(InvalidInput) if fewer than two distinct points or a non-finite coordinate;
///         Error(InvalidArgument) if points is NULL with n > 0.
PM_EXPORT LocalSpacing estimate_local_spacing(const Vec3* points, size_t n, int threads = 0,
                                              const ProgressCallback& progress = {});

}  // namespace particlemesh
