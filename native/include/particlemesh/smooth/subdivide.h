// Smooth surfaces from triangle meshes by subdivision (Tonnesen's thesis, section 5.2.5:
// D. Tonnesen, "Dynamically Coupled Particle Systems for Geometric Modeling, Reconstruction,
// and Animation", PhD thesis, University of Toronto, 1998).
//
//  - Loop (Loop 1987), through OpenSubdiv's Far::TopologyRefiner with the Loop scheme:
//    approximating; uniform refinement to `levels`, then (by default) every vertex is moved
//    to its exact position on the limit surface and given the exact limit normal, so the mesh
//    shades smoothly without a normal-estimation pass. Boundary rules and creases follow
//    OpenSubdiv's (Sdc) semantics.
//  - Butterfly (modified butterfly, Zorin, Schroeder & Sweldens 1996), through OpenMesh's
//    ModifiedButterflyT: interpolating; every original vertex keeps its position exactly, so
//    the surface passes through the particles.
//
// Both split every triangle into four per level: after k levels a closed mesh with V vertices,
// E edges and F triangles has F * 4^k triangles, and each level adds one vertex per edge
// (V' = V + E), so the Euler characteristic does not change. Output vertex i < V is the
// image of control vertex i (see SmoothResult::original_vertex), for both schemes.
//
// Butterfly's input (a TriMesh) must be a 2-manifold: every edge in one or two triangles,
// every vertex a single fan of triangles. Loop also takes non-manifold meshes, as OpenSubdiv
// does: an edge in more than two triangles is an infinitely sharp crease (each sheet meets it
// as at a boundary), a vertex joining several fans a sharp corner; the result keeps them
// (stats.nonmanifold_edges, stats.nonmanifold_vertices), and its limit comes from OpenSubdiv.
// What happens to other input:
//  - for butterfly, an edge in more than two triangles or a vertex joining several fans; for
//    both, a triangle repeating a vertex, two triangles on the same three vertices, a
//    non-finite position or attribute value, an index out of range, no triangles:
//    Error(InvalidInput) naming the edge, vertex or triangle;
//  - unreferenced vertices (e.g. particles the triangulation left out) are dropped; the
//    result says which input vertex each kept one came from (original_vertex);
//  - inconsistent orientation (an edge walked the same way by both its triangles) is
//    repaired: each edge-connected component whose triangles disagree is re-oriented by
//    flood fill from its lowest-index triangle and, when that component is closed, turned to
//    face outward (positive signed volume). A non-orientable component (Moebius strip) is an
//    Error(InvalidInput). Components that were already consistent are left as they are.
//    stats.reoriented_triangles counts the flipped triangles;
//  - triangles of zero area with three distinct corners are topologically fine and are
//    subdivided like the others.
// Input normals are ignored; the result always has normals (see SmoothResult::mesh).
#pragma once

#include "particlemesh/core/config.h"

#include <cstddef>
#include <cstdint>
#include <limits>
#include <vector>

#include "particlemesh/core/export.h"
#include "particlemesh/core/progress.h"
#include "particlemesh/mesh/tri_mesh.h"

namespace PM_NAMESPACE {

enum class SmoothScheme : int {
  Loop = 0,       ///< approximating, C2 except at extraordinary vertices (OpenSubdiv)
  Butterfly = 1,  ///< interpolating modified butterfly, C1 (OpenMesh)
};

/// Loop only: how boundary edges and corners are refined (OpenSubdiv's
/// Sdc::Options::VtxBoundaryInterpolation). Butterfly always uses its own boundary rule: the
/// 4-point curve scheme along boundary edges, boundary vertices staying put like all others.
///
/// OpenSubdiv's third value, VTX_BOUNDARY_NONE, is not offered: with uniform refinement it
/// gives exactly the EdgeOnly positions and limit (OpenSubdiv sharpens boundary edges either
/// way; NONE only marks the faces along the boundary as holes in its patch tables, which
/// smooth_mesh does not use). A test calls OpenSubdiv directly to check this.
enum class BoundaryRule : int {
  /// VTX_BOUNDARY_EDGE_AND_CORNER (default): boundary edges are infinitely sharp creases, so
  /// a boundary becomes a cubic B-spline curve (edge points 1/2-1/2, vertex points
  /// 1/8-3/4-1/8), and corners -- boundary vertices in a single triangle -- are pinned.
  EdgeAndCorner = 0,
  /// VTX_BOUNDARY_EDGE_ONLY: as EdgeAndCorner, but corners are smoothed along the boundary
  /// curve like every other boundary vertex (1/8-3/4-1/8).
  EdgeOnly = 1,
};

/// Loop only: how semi-sharp creases soften (Sdc::Options::CreasingMethod).
enum class CreaseMethod : int {
  Uniform = 0,  ///< CREASE_UNIFORM: sharpness drops by 1 per level
  Chaikin = 1,  ///< CREASE_CHAIKIN: sharpness averaged along the crease (smoother transitions)
};

/// An edge the caller marks as a crease (Loop only).
struct CreaseEdge {
  uint32_t a = 0, b = 0;  ///< the two vertex indices of an edge of the input mesh (either order)
  /// OpenSubdiv's sharpness: infinity (or any value >= 10) = infinitely sharp, the surface
  /// keeps a hard edge along it at every level; s in (0, 10) = semi-sharp, the edge is
  /// refined as sharp for about s levels and smooth after (a rounded crease); 0 = smooth.
  float sharpness = std::numeric_limits<float>::infinity();
};

/// The most levels smooth_mesh accepts; each level multiplies the triangles by 4.
inline constexpr int kMaxSmoothLevels = 10;
/// The largest coordinate magnitude a mesh to smooth may have (and 1e30 for attribute
/// values, which are floats): the schemes' weighted sums, and the limit normals' cross
/// products, stay finite. Larger values are refused with InvalidInput.
inline constexpr double kMaxSmoothCoordinate = 1e50;
inline constexpr float kMaxSmoothAttribute = 1e30f;

struct SmoothOptions {
  SmoothScheme scheme = SmoothScheme::Loop;
  /// Levels of uniform refinement, 0..kMaxSmoothLevels. Every level multiplies the triangle
  /// count by 4. 0 keeps the connectivity (with Loop and `limit`, the control vertices are
  /// moved onto the limit surface).
  int levels = 1;
  /// Loop only (ignored by Butterfly): move every refined vertex to its exact position on the
  /// limit surface and give it the exact limit normal (OpenSubdiv's limit masks); also
  /// evaluates the attributes at the limit. When false the vertices are the refined control
  /// points of the last level and the normals are area-weighted face normals.
  bool limit = true;
  BoundaryRule boundary = BoundaryRule::EdgeAndCorner;
  CreaseMethod crease_method = CreaseMethod::Uniform;
  /// Loop only: edges to keep (semi-)sharp. Vertex indices refer to the input mesh.
  /// Butterfly rejects a non-empty list (OpenMesh's subdivider has no creases).
  std::vector<CreaseEdge> creases;
  /// Refuse (Error LimitExceeded) before allocating anything when F * 4^levels exceeds this
  /// many triangles. Loop needs about 270 bytes per output triangle at its peak with `limit`
  /// (OpenSubdiv's full last-level topology), about 150 without; the default, 2^25 (about
  /// 33.5 million triangles), so stays under about 9 GB. Corner attributes add 12 bytes per
  /// component per output triangle (15 while the last level is made). At most 2^30.
  uint64_t max_triangles = uint64_t(1) << 25;
  /// Worker threads, 0 = all cores. The output does not depend on it.
  int threads = 0;
  /// Called between stages (checking, refining, interpolating each level, limit, output);
  /// returning false cancels at the next stage boundary with Error(Cancelled). OpenSubdiv's
  /// topology refinement is one stage (one call, about half of a Loop run).
  ProgressCallback progress;
};

struct SmoothStats {
  size_t input_vertices = 0;      ///< vertex array size of the input
  size_t dropped_vertices = 0;    ///< unreferenced input vertices left out
  size_t control_vertices = 0;    ///< vertices of the control mesh (input minus dropped)
  size_t control_triangles = 0;
  size_t control_edges = 0;
  size_t boundary_edges = 0;      ///< control edges in a single triangle
  size_t reoriented_triangles = 0;///< triangles flipped by the orientation repair
  size_t nonmanifold_edges = 0;   ///< control edges in more than two triangles (Loop: sharp creases)
  size_t nonmanifold_vertices = 0;///< control vertices joining several fans (Loop: sharp corners)
  size_t creases = 0;             ///< crease edges passed to OpenSubdiv
  size_t vertices = 0;            ///< of the result
  size_t triangles = 0;           ///< of the result (control_triangles * 4^levels)
  int levels = 0;
  bool limit = false;             ///< limit positions and normals were evaluated
  double seconds_prepare = 0;     ///< checks, compaction, orientation repair
  double seconds_refine = 0;      ///< topology refinement and interpolation
  double seconds_limit = 0;       ///< limit positions, normals and attributes
  double seconds_output = 0;      ///< output arrays and normals
};

struct SmoothResult {
  /// The smooth mesh: positions, unit normals (Loop with limit: exact limit normals;
  /// otherwise area-weighted averages of the adjacent triangles' normals), triangles wound
  /// like the (repaired) input, and every input attribute carried through with the same
  /// scheme as the positions (evaluated at the limit when the positions are).
  ///
  /// Both schemes order the triangles alike, so what belongs to an input triangle (a
  /// material, texture coordinates) follows it: the children of input triangle f are
  /// triangles f * 4^levels to (f + 1) * 4^levels - 1, and each level's four children of a
  /// triangle (a, b, c), with ab, bc and ca its edges' new vertices, are (a, ab, ca),
  /// (ab, b, bc), (ca, bc, c) and (bc, ca, ab) in that order. (a, b, c) are the input
  /// triangle's corners, or (a, c, b) for a triangle the orientation repair turned.
  TriMesh mesh;
  /// Output vertex i < original_vertex.size() is the image of input vertex
  /// original_vertex[i] (the identity when no vertex was dropped); later vertices are new.
  std::vector<uint32_t> original_vertex;
  SmoothStats stats;
};

/// Subdivide a triangle mesh into a smooth one.
/// Cost: linear in the output size. Loop refines the topology once (OpenSubdiv, one thread:
/// about half the run) and interpolates the positions and the attribute channels through it
/// concurrently; the butterfly runs one OpenMesh subdivider for the positions and one per
/// three attribute channels, concurrently. About 270 bytes per output triangle at the peak.
/// @param[in] mesh     #V positions, #F triangles, optional attributes (#V x components)
/// @param[in] options  scheme, levels, limit, boundary rule, creases, size limit, threads
/// @return the smooth mesh, the vertex map and statistics
/// @throws Error(InvalidArgument) bad option (levels out of range, a crease that is not an
///         edge, creases with Butterfly); Error(InvalidInput) unusable mesh (see above);
///         Error(LimitExceeded) result larger than max_triangles; Error(Cancelled).
PM_EXPORT SmoothResult smooth_mesh(const TriMesh& mesh, const SmoothOptions& options = {});

}  // namespace particlemesh
