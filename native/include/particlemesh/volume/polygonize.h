// Polygonization of the implicit surface of volume particles (thesis chapter 5, section 5.1.2:
// sample space, classify the samples inside/outside, place the crossings on the edges between
// inside and outside samples, fit polygons), done so that the work follows the surface.
//
// 1. Sampling only where the surface may be. Space is cut into blocks of 8 x 8 x 8 grid nodes
//    (cell size h). Blocks that no particle's support reaches are never touched: F is zero
//    there, and T > 0. Of the others, a block is proven inside (every node's F >= T) or
//    outside (every node's F < T) from bounds of the summed kernels: an upper bound from each
//    particle's nearest point of the block, and a lower bound at the centre of every
//    2 x 2 x 2 group of nodes from the kernels' convexity, F(x) >= F(c) + grad F(c).(x - c)
//    - K |x - c|^2 (spherical kernels with strengths >= 0; otherwise every reached block is
//    sampled). Only the blocks that may hold surface, and proven ones next to a crossing, are
//    sampled and stored: memory and sampling follow the surface; the proofs cost about 40 %
//    of sampling a block and never change the mesh (their margins are far above the samples'
//    rounding). A thin sheet costs a thin layer of blocks, never its bounding box. Each block
//    sums its particles' contributions in a fixed order, so the samples do not depend on the
//    thread count.
// 2. Classification: a node is inside when F >= T.
// 3. Crossings: a vertex on every grid edge between an inside and an outside node, first by
//    linear interpolation of the samples, then refined on the true field F along the edge
//    (safeguarded Newton, each step corrected for the field's curvature along the edge), so
//    vertices lie on the iso-surface, not on its trilinear approximation; each vertex is
//    created once (by the block owning the edge's lower node) and shared by the four cells
//    around its edge: an indexed mesh without duplicates.
//    Vertex normals are -grad F / |grad F| at the vertex (outward).
// 4. Polygons: marching cubes with every ambiguous face resolved by the asymptotic decider
//    (Nielsen and Hamann 1991), computed from that face's four samples only, so the two cells
//    sharing a face always agree: the mesh is crack-free. The polygons of a cell are traced
//    from its face segments (a table built once from that rule, not copied), so every
//    surface edge is shared by exactly two triangles and every vertex has a single fan: the
//    output is a closed, consistently oriented 2-manifold (counter-clockwise seen from
//    outside). An ambiguous cell interior is resolved as separate sheets (no tunnel); the
//    rare long polygons around several joined ambiguous faces get a vertex inside the cell
//    (on the surface, found along the gradient) so that no diagonal lies on a cell face.
//    Features thinner than a cell can be missed or merged, as in any sampled method, and in
//    blobs only a cell or two across a few triangles can face against the gradient (the
//    sampled topology is right but the geometry is below the resolution): none on the SPH
//    test frames at splashsurf's parameters, under 1 % of the area on splashy data.
//
// Vertices are clamped to at least 1e-3 h from grid nodes (so no two coincide). The output is
// byte-identical for any thread count.
//
// The lattice: node (i, j, k) lies at origin + h (i, j, k), cell (i, j, k) spans the nodes
// (i..i+1, j..j+1, k..k+1), with origin = (lower - R_max) - 9 h on each axis (computed in that
// order), lower = the particles' smallest coordinates (or domain_min), R_max = the largest
// radius (or domain_max_radius). Every node's sample sums its particles in the order of the
// particle grid (cells of R_max anchored at lower - R_max, then input order; with per-particle
// radii cells of particle_grid_radius, the few particles of larger radius after all others).
// Tiles of one cloud therefore polygonize exactly as the whole cloud when each is given the
// whole cloud's domain_min, domain_max_radius (and domain_grid_radius), the particles within
// reach of its cells (R_max) in their order in the whole cloud, and its cell range: the
// tiles' meshes share the vertices on their seams bit for bit, and together they are the
// whole cloud's mesh (particlemesh.distributed).
#pragma once

#include "particlemesh/core/config.h"

#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <vector>

#include "particlemesh/core/export.h"
#include "particlemesh/core/progress.h"
#include "particlemesh/mesh/point_cloud.h"
#include "particlemesh/mesh/tri_mesh.h"
#include "particlemesh/smooth/taubin.h"
#include "particlemesh/volume/field.h"
#include "particlemesh/volume/kernel.h"

namespace PM_NAMESPACE {

/// Default cell size: h = kDefaultCellFraction x R (with the default radius, half the
/// particle spacing).
inline constexpr double kDefaultCellFraction = 0.25;

/// Default memory budget for the sampled grid: 4 GiB.
inline constexpr uint64_t kDefaultMaxGridBytes = uint64_t(4) << 30;

/// Where the polygonization lattice is anchored.
enum class LatticeAnchor {
  /// origin = (lower - R_max) - 9 h (see the top): the lattice follows the particles' box.
  Particles,
  /// The same, rounded down to a multiple of h on each axis (space_anchored_origin): every
  /// node lies at an integer multiple of h in world coordinates, whatever the particles'
  /// box. Consecutive frames of a simulation, whose boxes move by fractions of a cell, are
  /// then sampled at the same points in space (with the same h), so their surfaces do not
  /// shimmer where the fluid is still. What the command-line tool uses.
  Space,
};

/// (lower - R_max) - 9 h rounded down to a multiple of h per axis: floor(o / h) * h, one h
/// lower where that product rounds above o. Tiles given their cloud's domain_min and R_max
/// round the same origin the same way, so LatticeAnchor::Space keeps tiles exact.
inline Vec3 space_anchored_origin(const Vec3& origin, double h) {
  auto down = [h](double o) {
    const double v = std::floor(o / h) * h;
    return v > o ? v - h : v;
  };
  return {down(origin.x), down(origin.y), down(origin.z)};
}

struct PolygonizeOptions {
  Kernel kernel = Kernel::Wyvill;
  /// R for every particle, world units. 0 = the default: kDefaultRadiusFactor (2) x the
  /// median particle spacing (estimate_spacing), or with spherical kernels, when that leaves
  /// over a tenth of the particles outside the surface, the larger radius their packing asks
  /// for (FieldParams::radius). Ignored when `radii` is given.
  double radius = 0;
  /// T > 0. 0 = kDefaultThresholdFraction (0.5) x the field deep inside an evenly packed
  /// volume at the default radius (lattice_field(kernel, 2, 1): 3.33 for Wyvill), which puts
  /// the surface of a packed block about half a spacing outside its outermost particles when
  /// the radius is the default. See field.h.
  double threshold = 0;
  /// Grid cell size h, world units. 0 = kDefaultCellFraction (1/4) x R (R: the radius, or
  /// the median of `radii`).
  double cell_size = 0;
  /// Empty, or one radius per particle (> 0, world units).
  std::vector<double> radii;
  /// Empty (all 1), or one strength per particle (finite).
  std::vector<double> strengths;
  /// Anisotropic kernels (anisotropy.h): off unless anisotropy.enabled.
  AnisotropyOptions anisotropy;
  /// Drop the pieces of the surface that enclose less than this volume (world units cubed;
  /// splashes, lone droplets). 0 = keep every piece.
  double min_component_volume = 0;
  /// Drop the pieces that enclose less than this many particles' worth of volume, N s^3 with s
  /// the median particle spacing (estimated when the default radius did not already need it).
  /// 0 = keep every piece. With min_component_volume, the larger of the two limits applies.
  double min_component_particles = 0;
  /// Collapse every edge shorter than this fraction of the cell size h into one vertex on the
  /// surface (F = T, its normal the field's), where that keeps the surface a closed, oriented
  /// 2-manifold and turns no other triangle by more than 60 degrees: marching cubes' slivers,
  /// the thin triangles where the surface passes close to a lattice node, become ordinary
  /// ones (0.3 takes out nine in ten of the triangles with an angle under 10 degrees, and a
  /// tenth to a fifth of all triangles). After dropping pieces, before smoothing; shortest edges
  /// first, sequential and deterministic. 0 = off (default); at most 0.5.
  double collapse_edges = 0;
  /// Volume-keeping smoothing of the mesh, after dropping pieces (smooth/taubin.h): Taubin's
  /// lambda|mu filter; off (0 iterations) by default. Its threads follow `threads`.
  TaubinOptions surface_smoothing{.iterations = 0};
  /// Worker threads, 0 = all cores. The output does not depend on it.
  int threads = 0;
  /// Fail with LimitExceeded, before allocating, if the large allocations - the block
  /// search, the sampled grid (blocks of samples and their bookkeeping: checked before the
  /// blocks are proven, and before each pass samples blocks) and then the grid with the
  /// output mesh - would need more than this many bytes. The total a run used is
  /// PolygonizeStats::grid_bytes. 0 = no limit.
  uint64_t max_grid_bytes = kDefaultMaxGridBytes;
  ProgressCallback progress;
  /// Empty, or the lower corner of the whole cloud these particles are a tile of (at or below
  /// every particle): the lattice and the particle grid are anchored to it (see the top).
  std::optional<Vec3> domain_min;
  /// 0, or the whole cloud's largest radius (at least every radius here; see the top).
  double domain_max_radius = 0;
  /// With domain_max_radius and per-particle radii: 0 (the particle grid's cells are as wide
  /// as domain_max_radius), or the whole cloud's particle_grid_radius (field.h): the cells
  /// are that wide and the particles of larger radius are kept apart, as for the whole cloud.
  double domain_grid_radius = 0;
  /// Polygonize only the lattice cells with cell_min <= (i, j, k) < cell_max on every axis
  /// (cell indices as at the top). The result holds the triangles of those cells and the
  /// vertices they use (on the range's faces too), in the order the whole lattice would give
  /// them; the field still sees every particle given, so pass the particles within R_max of
  /// the range. Empty: every cell.
  struct CellRange {
    std::array<int64_t, 3> min{}, max{};
  };
  std::optional<CellRange> cells;
  /// Particles (the lattice at the particles' box, as at the top) or Space (nodes at
  /// multiples of h: frames of a sequence do not shimmer; see LatticeAnchor).
  LatticeAnchor lattice_anchor = LatticeAnchor::Particles;
};

struct PolygonizeStats {
  size_t particles = 0;
  Kernel kernel = Kernel::Wyvill;
  double radius = 0;         ///< R used (median of the radii when per particle)
  double max_radius = 0;     ///< largest R_i
  double threshold = 0;      ///< T used
  double cell_size = 0;      ///< h used
  double spacing = 0;        ///< median particle spacing, when the default radius needed it (else 0)
  bool radius_defaulted = false;
  bool threshold_defaulted = false;
  bool cell_size_defaulted = false;
  bool anisotropic = false;          ///< anisotropic kernels were used
  size_t anisotropic_particles = 0;  ///< particles that got an ellipsoid (the rest kept spheres)
  /// With anisotropic kernels and the default threshold: the radius / spacing ratio it was
  /// calibrated for (FieldParams::threshold), else 0.
  double calibration_ratio = 0;
  /// The share of the particles inside the surface (F >= T at their centres;
  /// field_at_particles): low when the radius is too small for how sparsely they are packed.
  double enclosed_fraction = 0;
  /// The radius their packing suggests (field_at_particles; spherical kernels of one radius,
  /// else 0): R itself for evenly packed particles at 2 spacings. The default radius takes it
  /// when 2 spacings leave too many particles outside (FieldParams::radius).
  double density_radius = 0;
  double min_component_volume = 0;   ///< the volume limit applied to pieces (0: none)
  size_t components_removed = 0;     ///< pieces dropped by it
  size_t edges_collapsed = 0;        ///< short edges collapsed (collapse_edges): vertices removed
  int32_t smoothing_iterations = 0;  ///< Taubin iterations applied to the mesh
  size_t candidate_blocks = 0;  ///< blocks near some particle, before the exact support test
  size_t reached_blocks = 0;    ///< blocks of 8^3 nodes that some support reaches
  size_t sampled_blocks = 0;    ///< of those, the blocks sampled (that may hold surface)
  size_t inside_blocks = 0;     ///< reached blocks proven inside, not sampled
  size_t outside_blocks = 0;    ///< reached blocks proven outside, not sampled
  size_t surface_blocks = 0;    ///< blocks with an inside/outside change (meshed)
  uint64_t sampled_nodes = 0;   ///< sampled_blocks x 512
  uint64_t bounding_box_nodes = 0;  ///< nodes a dense grid over the supports' box would need
  uint64_t grid_bytes = 0;      ///< memory of the sparse grid (samples + bookkeeping) and the output mesh: what max_grid_bytes bounds
  size_t vertices = 0;
  size_t triangles = 0;
  uint64_t field_evaluations = 0;  ///< exact evaluations of F (edge refinement and normals)
  double seconds_setup = 0;     ///< spacing estimate, field grid, block search
  double seconds_proofs = 0;    ///< proving blocks inside or outside (no samples needed)
  double seconds_sampling = 0;  ///< summing the particles into the blocks
  double seconds_meshing = 0;   ///< classification, vertices (refinement), triangles
  double seconds_finishing = 0; ///< dropping small pieces and smoothing the mesh
  Vec3 origin;                  ///< the lattice's node (0, 0, 0) (see the top)
};

struct PolygonizeResult {
  /// The surface: vertices with normals from the field gradient (outward), triangles
  /// counter-clockwise seen from outside. Empty (no vertex) when F >= T nowhere on the grid.
  /// The cloud's attributes (velocity, density, ...) are interpolated onto the vertices with
  /// the normalised kernel weights, sum_i w_i a_i / sum_i w_i (isotropic and anisotropic
  /// kernels alike; detail::AttributeSums in polygonize_finish.h says more).
  TriMesh mesh;
  PolygonizeStats stats;
};

/// Polygonize the iso-surface F = T of the particles' field (see the top of this file).
/// Cost: O(N (R/h)^3) to prove and sample (each particle touches the nodes, or the group
/// centres, in its support; sampling only near the surface) and O(surface cells) to mesh;
/// memory proportional to the surface's blocks plus the occupied volume / (8h)^3 blocks'
/// bookkeeping, plus the mesh.
/// @throws Error(InvalidInput) empty cloud, non-finite coordinate;
///         Error(InvalidArgument) kernel, radius, threshold, cell size, radii, strengths,
///         anisotropy, component or smoothing options out of range (the message names the
///         option or the index);
///         Error(LimitExceeded) the grid would exceed max_grid_bytes (checked before the
///         allocation, the message says how much it would need), or the particles span more
///         than 2^24 cells along an axis, or the mesh would exceed 2^32 - 1 vertices;
///         Error(Cancelled) when the progress callback returns false.
PM_EXPORT PolygonizeResult polygonize(const PointCloud& cloud, const PolygonizeOptions& options = {});

/// The same on a field built beforehand (reusing its parameters and particle grid); the
/// kernel, radius, threshold, radii, strengths, domain_min and domain_max_radius of `options`
/// are ignored (the field's own apply).
PM_EXPORT PolygonizeResult polygonize(const ParticleField& field, const PolygonizeOptions& options = {});

}  // namespace particlemesh
