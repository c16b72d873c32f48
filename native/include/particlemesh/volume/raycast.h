// Direct surface sampling (thesis chapter 5, section 5.1.3): exact intersections of rays with
// the iso-surface F(x) = T of volume particles (field.h), without a mesh.
//
// Along a ray x(t) = o + t d every particle's s = |x - p|^2 / R^2 is a quadratic in t, so
// with a polynomial kernel (kernel.h) each particle's contribution is a polynomial in t of
// twice the kernel's degree in s, on the interval of t where the ray is inside its support
// sphere. The spheres' entry and exit points cut the ray into intervals on which a fixed set
// of particles contributes; on each, F(x(t)) - T is one polynomial (degree 4 for Poly4, 6 for
// Wyvill and Poly6; Tonnesen 1989, Wyvill and Trotman 1989), whose roots are the surface.
//
// - Acceleration: a bounding volume hierarchy over the particles' support spheres (binary,
//   median split on the longest axis, at most 8 particles per leaf), walked front to back
//   with a priority queue of nodes ordered by where the ray enters their boxes. Chosen over a
//   uniform grid because radii may differ per particle (a grid sized for the largest one
//   puts too many particles in each cell), particles come in clusters with wide empty gaps
//   (splashes, separate bodies; a grid walk pays for every empty cell, the hierarchy skips
//   the gap in one step), and the queue says at every moment how far along the ray no
//   unvisited sphere begins: the intervals before that point are final, so the first hit
//   is found without visiting the spheres behind it. (A camera's rays share one walk per
//   tile of pixels instead: cast_camera_rays in render.h, the same hits.)
// - Intervals: each is solved in its own variable u = (t - t0) / (t1 - t0) in [0, 1], with
//   the particles' offsets taken from the interval's start, so the coefficients stay of the
//   order of the kernel whatever the distance to the ray's origin (a polynomial in the global
//   t would lose all precision for a camera far from the particles). Work per interval is
//   proportional to the particles active on it (about 30 for evenly packed particles at the
//   default radius), so a ray costs time linear in the spheres it meets.
// - Roots: degree 4 (Poly4) in closed form (Ferrari's quartic), degree 6 (Wyvill, Poly6) by
//   certified isolation (Bernstein coefficients and Descartes' rule of signs, de Casteljau
//   halving), both then polished by safeguarded Newton to full double precision.
// - Blinn's kernel is not a polynomial: on each interval the crossings are bracketed by
//   marching with steps no longer than |F - T| / L, where L bounds |dF/dt| on the interval
//   (sum of |w_i| 2.2567 / R_i; Blinn's exponential has |dg/dt| <= sqrt(2k) e^(-1/2) / R),
//   so no crossing is stepped over, with a floor of kBlinnMinStep R_min per step (a sliver
//   of inside thinner than that along the ray may be missed), then polished by safeguarded
//   Newton in the bracket. This is the "iterative solver on a guessed interval" of Blinn
//   (1982) with a bracket that is proven, not guessed.
//
// Hits: every place where the state "inside" (F >= T) changes along the ray, in increasing
// t, with the normal -grad F / |grad F| (outward) and whether the ray enters or leaves; so
// entering and leaving alternate, starting with the opposite of starts_inside.
//
// Tangent rule: a ray that touches the surface without crossing it (F - T has a double root)
// reports no hit there. Precisely: two consecutive crossings between which |F - T| nowhere
// exceeds kTangentTolerance x (T + max |w_i|) (the rounding error of evaluating F, so the
// pair is indistinguishable from a touch) are dropped together. A grazing ray therefore
// reports either nothing or a genuine entering/leaving pair, never one hit and never the
// same point twice.
#pragma once

#include "particlemesh/core/config.h"

#include <cstddef>
#include <cstdint>
#include <limits>
#include <memory>
#include <optional>
#include <vector>

#include "particlemesh/core/export.h"
#include "particlemesh/core/progress.h"
#include "particlemesh/core/vec3.h"
#include "particlemesh/volume/field.h"

namespace PM_NAMESPACE {

namespace detail {
struct RayCasterAccess;
}

/// See the tangent rule at the top of this file.
inline constexpr double kTangentTolerance = 1e-12;
/// Blinn's kernel: the shortest marching step, as a fraction of the smallest radius.
inline constexpr double kBlinnMinStep = 1.0 / 256.0;

struct RayHit {
  double t = 0;           ///< ray parameter: the point is origin + t * direction
  Vec3 position;          ///< origin + t * direction
  Vec3 normal;            ///< -grad F / |grad F| at the point (outward); zero if grad F = 0
  bool entering = false;  ///< the ray passes from outside (F < T) to inside (F >= T)
};

/// All crossings of one ray.
struct RayHits {
  bool starts_inside = false;  ///< F >= T at t_min
  std::vector<RayHit> hits;    ///< increasing t; entering alternates, hits[0].entering == !starts_inside
};

/// Counters of one query (to check the cost, and for benchmarks).
struct RayStats {
  uint64_t nodes_visited = 0;     ///< hierarchy nodes whose box the ray entered
  uint64_t spheres_entered = 0;   ///< support spheres the ray crossed (within [t_min, t_max])
  uint64_t intervals = 0;         ///< intervals with at least one active particle
  uint64_t intervals_solved = 0;  ///< intervals whose polynomial (or march) was solved
};

/// Ray queries on a particle field. Building costs O(N log N); queries are const and safe to
/// run from many threads at once.
class PM_EXPORT RayCaster {
 public:
  RayCaster();
  /// Build the hierarchy over the field's particles (those of zero strength are left out:
  /// they contribute nothing). The field is copied; its kernel, radii, strengths and
  /// threshold are those used.
  explicit RayCaster(ParticleField field);
  ~RayCaster();
  RayCaster(RayCaster&&) noexcept;
  RayCaster& operator=(RayCaster&&) noexcept;

  const ParticleField& field() const;

  /// All crossings of the ray origin + t direction, t_min <= t <= t_max, in increasing t.
  /// direction need not be unit length (t is in units of its length).
  /// @throws Error(InvalidArgument) non-finite origin or direction, zero direction,
  ///         t_min > t_max or a NaN bound.
  RayHits all_hits(const Vec3& origin, const Vec3& direction, double t_min = 0,
                   double t_max = std::numeric_limits<double>::infinity(), RayStats* stats = nullptr) const;

  /// The first crossing (entering, or leaving when the ray starts inside), or none. Stops at
  /// that crossing: the spheres behind it are not visited.
  std::optional<RayHit> first_hit(const Vec3& origin, const Vec3& direction, double t_min = 0,
                                  double t_max = std::numeric_limits<double>::infinity(),
                                  RayStats* stats = nullptr) const;

  /// Number of nodes of the hierarchy (for tests and statistics).
  size_t node_count() const;

  struct Impl;

 private:
  friend struct detail::RayCasterAccess;
  std::unique_ptr<Impl> impl_;
};

/// Options of the batch queries.
struct RaycastOptions {
  double t_min = 0;  ///< hits with t_min <= t <= t_max only
  double t_max = std::numeric_limits<double>::infinity();
  int threads = 0;   ///< 0 = all cores; the results do not depend on it
  ProgressCallback progress;
};

/// First hits of many rays.
struct FirstHits {
  std::vector<double> t;        ///< per ray: t of the first hit, +infinity for a miss
  std::vector<Vec3> positions;  ///< per ray (zero for a miss)
  std::vector<Vec3> normals;    ///< per ray (zero for a miss)
  std::vector<uint8_t> entering;///< per ray: 1 entering, 0 leaving or miss
  size_t hit_count = 0;         ///< rays with a hit
};

/// All hits of many rays, concatenated: the hits of ray i are hits[offsets[i] .. offsets[i+1]).
struct AllHits {
  std::vector<uint64_t> offsets;       ///< n + 1 entries, offsets[0] = 0
  std::vector<RayHit> hits;
  std::vector<uint8_t> starts_inside;  ///< per ray
};

/// First hits of rays i = 0..n-1 (origins[i], directions[i]), on all cores.
/// @throws Error(InvalidArgument) naming the first bad ray ("directions[12] is zero"), or a
///         bad t range; Error(Cancelled) from the progress callback.
PM_EXPORT FirstHits cast_first_hits(const RayCaster& caster, const Vec3* origins, const Vec3* directions,
                                    size_t n, const RaycastOptions& options = {});

/// All hits of rays i = 0..n-1. Same errors as cast_first_hits.
PM_EXPORT AllHits cast_all_hits(const RayCaster& caster, const Vec3* origins, const Vec3* directions, size_t n,
                                const RaycastOptions& options = {});

}  // namespace particlemesh
