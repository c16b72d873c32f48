// Tonnesen's triangulation of surface particles, the smallest-sphere test, exactly (D. Tonnesen,
// "Dynamically Coupled Particle Systems for Geometric Modeling, Reconstruction, and
// Animation", PhD thesis, University of Toronto, 1998, chapter 5, section 5.2.3).
//
// Triangle (i, j, k) is kept iff
//   1. all three edges are at most L = max_edge_factor * r0 long, and
//   2. no other particle lies strictly inside the smallest sphere enclosing the three points:
//      for an acute or right triangle the sphere through the three points centred in their
//      plane (circumcircle as a great circle), for an obtuse one the sphere with the longest
//      edge as diameter.
//
// Degenerate triplets are skipped: coincident points, or a corner angle whose sine is below
// 1e-10 (collinear points). Exact duplicates of a point are set aside (reported), so the
// lowest-index copy stands for all of them.
//
// Ties. A point q "on" the sphere (|q - c|^2 - rho^2 within 1e-9 rho^2) is decided by symbolic
// perturbation: every point p gets a tiny power weight eps^rank(p), where rank is the
// lexicographic order of the coordinates (x, then y, then z). The weighted sphere of the
// triangle then passes q's perturbed power with the sign of the first non-zero coefficient,
// taken in rank order, of  sum_v lambda_v(q) w_v - w_q  (lambda: barycentric coordinates of q's
// projection on the triangle's plane, or on the diameter's line for an obtuse triangle).
// This is a genuine perturbation of the input, so every co-circular set (the four corners of
// a square lattice cell, a regular polygon) gets exactly one triangulation, and because the
// rank comes from the coordinates, not the input order, the output does not depend on how
// the points are permuted. A right angle within 1e-9 rad counts as right (circumsphere).
//
// This raw set is NOT a surface: on real even samplings it holds 20-29 % more triangles than
// a surface (overlapping pairs on quads, slivers). Use reconstruct_surface() for a mesh.
#pragma once

#include "particlemesh/core/config.h"

#include <cstddef>
#include <cstdint>

#include "particlemesh/core/export.h"
#include "particlemesh/core/progress.h"
#include "particlemesh/mesh/point_cloud.h"
#include "particlemesh/mesh/tri_mesh.h"

namespace PM_NAMESPACE {

struct TriangulateOptions {
  /// Particle spacing r0 in world units (not relative). 0 = estimate it as the median
  /// nearest-neighbour distance (estimate_spacing).
  double spacing = 0;
  /// L = max_edge_factor * r0: the longest edge a triangle may have. Tonnesen's default is 2.
  double max_edge_factor = 2.0;
  /// Worker threads, 0 = all cores. The output does not depend on it.
  int threads = 0;
  /// Fail with LimitExceeded if a point has more neighbours within L than this: a sign the
  /// points are packed far denser than the spacing, where the triplet count would explode.
  /// With a local spacing (reconstruct_surface's default) the spacing is the cloud's own, not
  /// the caller's: a point whose reach (2L/sqrt(3)) holds more has its L shortened to the
  /// reach that holds this many (TriangulateStats::shortened_limits), and nothing fails.
  size_t max_neighbors = 256;
  /// Fail with LimitExceeded, before the test starts, if the candidate triplets it would
  /// examine (pairs of a point's higher-index neighbours within L) average more than this
  /// per distinct point: L is then far too large for the spacing, and the test's work grows
  /// as (L / r0)^4 on a surface. With the default neighbour cap this triggers about where
  /// that does (L ~ 7 r0 on an even surface sample); it bounds the work when max_neighbors
  /// is raised. Evenly sampled surfaces at L = 2 r0 need about 20 per point, volume-filling
  /// particles about 120. 0 = no limit.
  size_t max_triplets_per_point = 4096;
  ProgressCallback progress;
};

struct TriangulateStats {
  double spacing = 0;            ///< r0 used
  bool spacing_estimated = false;
  double max_edge = 0;           ///< L used
  size_t points = 0;
  size_t duplicate_points = 0;   ///< exact duplicates set aside
  /// Near copies set aside (reconstruct_surface with a local spacing): where
  /// at least a quarter of the distinct points have a neighbour ten times nearer than every
  /// other (an airborne scanner's first and last returns off hard ground), each such pair
  /// is one particle, its lower index, as exact duplicates are.
  size_t near_duplicates = 0;
  size_t max_neighbors_seen = 0; ///< the largest neighbour count within L
  size_t triplets = 0;           ///< pairs of higher neighbours within L, over all points (see max_triplets_per_point)
  size_t candidates = 0;         ///< non-degenerate triplets with all edges <= L
  size_t degenerate = 0;         ///< triplets with edges <= L skipped as collinear
  /// candidates whose test met a point in the tie zone (judged by the symbolic tie-break)
  /// before one inside their sphere, if any
  size_t ties = 0;
  size_t kept = 0;               ///< triangles kept
  /// With a local spacing: how irregular the sampling is (LocalSpacing::irregularity), and the
  /// factor every edge limit was lengthened by for it (1 on an even sampling; up to 1.75 where
  /// the particles lie at random). 0 and 1 otherwise.
  double sampling_irregularity = 0;
  double reach_factor = 1;
  /// With a local spacing: how far the particles scatter across the surface
  /// (LocalSpacing::thickness; noisy scans ~0.3 and more, a volume ~0.85), 0 otherwise.
  double sampling_thickness = 0;
  /// With a local spacing, where at least a tenth of the particles' local spacings were held
  /// to the cap of 3 r0 (a scanner's rows far apart for their spacing along them): the 90th
  /// percentile of the local spacings before the cap, in units of the cloud's median
  /// nearest-neighbour distance (how far the rows lie apart). 0 otherwise.
  double uncapped_spacing_p90 = 0;
  /// With a local spacing: over the particles whose local spacing lies past the cap of 3 r0,
  /// the median of it over the median nearest-neighbour distance around them: several where
  /// rows lie far apart for their spacing along them (the spacing across sets it), about 1
  /// where a part is sampled sparser all round (a scan merged with a much finer one). 0 where
  /// no particle's lies past the cap.
  double capped_spacing_over_nn = 0;
  /// With a local spacing: particles whose edge limit was shortened so that their reach
  /// holds at most max_neighbors others (see TriangulateOptions::max_neighbors).
  size_t shortened_limits = 0;
  double seconds_spacing = 0;
  double seconds_neighbors = 0;
  double seconds_test = 0;
};

struct TriangulateResult {
  /// Vertices are the input particles (index i = particle i, normals copied if given);
  /// triangles are canonical: (a, b, c) with a < b < c, sorted lexicographically.
  TriMesh mesh;
  TriangulateStats stats;
};

/// The smallest-sphere test over all triplets with edges <= L, found through a uniform grid of cell L:
/// linear work for evenly spaced points, all cores used, byte-identical output for any
/// thread count. Every input particle is a vertex of the result.
/// @throws Error(InvalidInput) empty/one-point/all-coincident cloud, NaN or Inf coordinate;
///         Error(InvalidArgument) bad option; Error(LimitExceeded) see max_neighbors and
///         max_triplets_per_point;
///         Error(Cancelled) when the progress callback returns false.
PM_EXPORT TriangulateResult triangulate_raw(const PointCloud& cloud,
                                            const TriangulateOptions& options = {});

}  // namespace particlemesh
