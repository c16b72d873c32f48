// From surface particles to a shading-ready surface: the triangles of Tonnesen's
// smallest-sphere test (his thesis, section 5.2.3; see triangulate.h) turned into a
// consistently oriented 2-manifold with its "undesirable triangulations" (section 5.2.4)
// resolved.
//
// Stages, each exposed by an option:
//  1. The raw smallest-sphere test (triangulate_raw).
//  2. Normals: local PCA oriented over a minimum spanning tree of the neighbour graph (after
//     Hoppe et al. 1992); when the cloud has normals they decide the orientation (see
//     SurfaceOptions::normals).
//  3. Co-normality: a triangle whose corner normals differ by more than `normal_angle`, or
//     whose face normal and a corner normal differ by more than min(normal_angle, 90), is not
//     surface (sheets with opposite normals, folds, the faces of tetrahedral bridges).
//  4. Manifold extraction: candidates oriented by the normals, each directed edge used once,
//     a tangent-plane wedge rule at every vertex, best-first growth from a front
//     (quality = the smallest largest angle, then the raw order), new seeds only when the front
//     is exhausted.
//  5. Repair: split boundary loops at pinched vertices, fill loops of up to 6 edges, keep the
//     largest fan at each remaining pinched vertex, then fill loops of up to `fill_holes`
//     edges. A loop is filled only if it can be triangulated with edges no longer than
//     fill_edge_factor x L that keep every fan a disk, winding with the normals: holes left by
//     sampling and extraction are that narrow; a real opening (no particles within that
//     distance across it) is wider and stays open, and is reported. Above 1.5, every pass
//     but the last fills within 1.5 x L, and the last fills the loops still open within
//     fill_edge_factor x L.
//  6. Orientation: every closed component is turned to face outward: to enclose positive
//     volume, or negative for one inside another (a hollow object's inner wall faces into
//     its cavity; mesh/nesting.h). Where the normals' spanning tree alone chose which way
//     the surface faces (no input normals, no viewpoint), an open component closed but for
//     small openings is judged as a closed one, its loops capped (surface/orient_outward.h).
#pragma once

#include "particlemesh/core/config.h"

#include <cstddef>

#include "particlemesh/core/export.h"
#include "particlemesh/surface/triangulate.h"

namespace PM_NAMESPACE {

struct SurfaceOptions : TriangulateOptions {
  /// Co-normality limit in degrees (Tonnesen's thesis, section 5.2.4): corner normals may differ by at most this,
  /// and the face normal from each corner's by at most this and never more than 90. Sheets
  /// facing each other (normals ~180 degrees apart) are separated at any setting; the default
  /// 120 also lets the surface turn sharp creases (a wedge of 60 degrees or more: its sides'
  /// normals are 180 - 60 apart); 90 leaves a slit along every crease sharper than about 75
  /// degrees.
  double normal_angle = 120.0;
  /// Where the surface's normals come from:
  ///  - Auto (default): local plane fits (PCA over the particles within L) give the tangent
  ///    planes, which vary smoothly at the sampling scale even where the input's normals are
  ///    faceted or noisy; the input's normals, when the cloud has them, decide which way each
  ///    particle faces where they are a consistent orientation (a thin part's two sides may
  ///    face opposite ways; normals flipped along a line, as those turned toward a sensor on a
  ///    closed object are, are not), else which way each piece of the orientation tree faces
  ///    (majority vote); without them each
  ///    piece faces the way its minimum spanning tree propagates from its highest point (+z).
  ///  - Input: the cloud's normals as they are (the cloud must have them).
  ///  - Estimate: local plane fits and the spanning tree only, ignoring any input normals.
  enum class NormalSource { Auto, Input, Estimate };
  NormalSource normals = NormalSource::Auto;
  /// Repair stage (hole filling, unpinching). Off: the extraction's output as grown.
  bool repair = true;
  /// Largest boundary loop, in edges, that may be filled (0 = fill none).
  size_t fill_holes = 100;
  /// Fill triangles' edges are at most fill_edge_factor x L: the documented criterion that
  /// tells a hole (narrower) from a real opening (wider). Above 1.5, the repair's passes fill
  /// with edges of at most 1.5 x L first, and only the loops still open after the particles
  /// are put back are filled up to this factor: a wider limit then patches those gaps and
  /// changes nothing else.
  double fill_edge_factor = 1.5;
  /// Remove every piece of the surface (triangles joined through shared vertices) of fewer
  /// than this many triangles: the stray triangles and slivers a scan leaves among its rows
  /// or at its fringe (MeshLab's "remove isolated pieces"). Their particles are then in no
  /// triangle (SurfaceStats::unused_points), and their outlines are not counted as loops
  /// left open. 0 (default) keeps every piece: a few particles apart from the rest (a
  /// droplet, a small part) are a surface of their own.
  size_t min_component_triangles = 0;
  /// Turn each closed component to face outward: away from the solid it bounds (positive
  /// signed volume), or into the cavity for a closed component inside another (a hollow
  /// object's inner wall; by how many enclose it, as topology_report's outward judges); and,
  /// where the normals were estimated without input normals or a viewpoint, each open one
  /// closed but for small openings, judged with its loops capped (SurfaceStats::nearly_closed_turned),
  /// and a part found folded over to face into its solid built again with its normals turned
  /// (SurfaceStats::folded_triangles).
  bool orient = true;
  /// Each particle's edge limit follows the sampling around it (real scans are sampled
  /// unevenly): L_i = max_edge_factor x h_i, h_i its local spacing (estimate_local_spacing;
  /// within 15 % of r0 it is r0, so an even sampling meshes as with one spacing; at most 3 r0),
  /// scaled so that the cloud's median nearest-neighbour distance is `spacing` when that is
  /// given; where the particles lie at random (LocalSpacing::irregularity over 0.35) every
  /// h_i and the cap grow by up to 1.75 x (TriangulateStats::reach_factor), as the triangles
  /// that cover such a sampling reach farther. An edge may be as long as the mean of its ends'
  /// limits. Everything measured in L
  /// uses the local value: the neighbour search, the plane fits, the fill limit, the widths of
  /// open loops. false: one limit L = max_edge_factor x spacing for the whole cloud, as the raw
  /// test (triangulate_raw) has.
  bool local_spacing = true;
  /// Where a scan was taken from (a PCD's VIEWPOINT, pcl::PointCloud::sensor_origin_), if
  /// known: no triangle then has an edge within 12.5 degrees of the view ray through it (such
  /// an edge joins a surface to what lies behind it, across a depth jump). Used only where the
  /// cloud looks like a scan from there (most points' estimated planes face it at well below
  /// grazing angles; SurfaceStats::viewpoint_used says whether it was).
  bool has_viewpoint = false;
  Vec3 viewpoint;
};

/// Loops left open at most this many L across (a patch over one needs no longer edges) are
/// gaps in the sampling rather than the surface's openings: a scan's outline or a model's real
/// holes are many times wider (3.7 L and more on the shared scans and models).
inline constexpr double kNarrowLoopWidth = 3.0;

/// Pieces of the surface with fewer triangles than this are counted as strays
/// (SurfaceStats::stray_pieces).
inline constexpr size_t kStrayPieceTriangles = 10;

struct SurfaceStats {
  bool normals_estimated = false;
  size_t candidates = 0;          ///< raw triangles that passed co-normality
  size_t rejected_conormal = 0;   ///< raw triangles dropped by co-normality
  size_t grown = 0;               ///< triangles accepted by the extraction
  size_t seeds = 0;               ///< growth regions started
  size_t pinches_resolved = 0;    ///< extra fans removed at pinched vertices
  /// Handles smaller than the sampling taken out: where a part thinner than the particles'
  /// spacing was joined across (a tunnel through a claw's tip), the patch within 1.5 L that
  /// holds the handle is replaced by a fill of its outline, its particles put back where they
  /// fit (Guskov and Wood, "Topological noise removal", 2001).
  size_t small_handles_removed = 0;
  size_t holes_filled = 0;
  size_t hole_triangles = 0;
  size_t holes_left = 0;          ///< boundary loops left open (real openings, or too large)
  size_t largest_hole_left = 0;   ///< edges of the largest loop left open
  /// The loops left open (at most 1000): their edge count and width, the smallest possible
  /// longest edge of a patch across them, in units of L (above fill_edge_factor: a real opening).
  /// The width is computed for loops of up to 128 edges (it costs the cube of the edges) and is
  /// infinite above (null in the CLI's JSON report).
  struct OpenLoop {
    size_t edges = 0;
    double width = 0;
  };
  std::vector<OpenLoop> open_loops;
  /// Of those, the loops at most kNarrowLoopWidth x L across that the fill did not try for being
  /// wider than fill_edge_factor or longer than fill_holes: gaps in the sampling (a model's
  /// vertices, with long thin triangles between them, leave such), not the surface's openings.
  /// `width` and `edges` are their largest: fill_edge_factor >= width and fill_holes >= edges
  /// let the fill try every one of them. All 0 without repair or with fill_holes 0.
  struct NarrowLoops {
    size_t count = 0;
    double width = 0;
    size_t edges = 0;
  };
  NarrowLoops narrow_loops;
  /// The edges of every loop left open, ascending: the holes left by size (a scan's sampling
  /// gaps are loops of a few edges, its real openings and outlines long ones).
  std::vector<size_t> holes_left_edges;
  size_t components_flipped = 0;  ///< closed components turned outward
  /// Closed pieces that enclosed no volume, opened: a patch and a reversed copy of it, which
  /// particles exactly in one plane (quantized coordinates: a float32 UTM northing, a CAD
  /// model's faces) can close into. The side facing as the particles' normals is kept, an open
  /// piece (its outline counted among the loops left open); where that side is not a surface
  /// with simple outlines the piece is removed and its particles are unused.
  size_t flat_pieces_opened = 0;
  /// Open components closed but for small openings (capped, they add at most 40 % to its area
  /// and enclose a clear volume), turned to face outward as closed ones are, where the
  /// normals' spanning tree alone chose which way they faced (no input normals, no
  /// viewpoint): a model's vertices whose surface keeps a few holes.
  size_t nearly_closed_turned = 0;
  /// Triangles of the surface first built that faced into the solid their part bounds, where
  /// the surface was then built again: part of a closed component (or one closed but for
  /// small openings) came out folded over, as where the normals' spanning tree crossed between
  /// the two sides of a thin part. The normals were turned to the sides the faces were found
  /// to face and the surface built again, kept where at most half as much of it faced inward
  /// and it was hardly more broken (0: not built again, or not kept). Looked for where the tree alone chose which way the normals face (no input
  /// normals, no viewpoint), as nearly_closed_turned.
  size_t folded_triangles = 0;
  size_t unused_points = 0;       ///< distinct particles in no triangle
  size_t components_removed = 0;  ///< pieces removed for min_component_triangles
  size_t component_triangles_removed = 0;  ///< their triangles
  /// The pieces of fewer than kStrayPieceTriangles triangles left in the surface (after
  /// min_component_triangles), counted when loops are left open (a closed surface is not
  /// searched): a scan's stray triangles among its rows. `largest`: the most triangles of one;
  /// min_component_triangles = largest + 1 removes them all.
  struct StrayPieces {
    size_t count = 0, triangles = 0, largest = 0;
  };
  StrayPieces stray_pieces;
  /// The particles' local spacings in units of r0 (all 1 without local_spacing): smallest,
  /// 10th percentile, median, 90th percentile, largest, over the distinct particles.
  struct Spread {
    double min = 1, p10 = 1, median = 1, p90 = 1, max = 1;
  };
  Spread local_spacing;
  bool viewpoint_used = false;    ///< SurfaceOptions::viewpoint was given and taken
  size_t rejected_shadow = 0;     ///< raw triangles dropped for bridging a depth jump
  /// The particles probably fill a volume (a fluid simulation's frame) rather than sample a
  /// surface: loops were left open, and co-normality dropped over 35 % of the raw triangles
  /// (triangles across particles facing opposite ways) or the sampling is as thick as a thin
  /// layer of them (TriangulateStats::sampling_thickness at least kThinLayerSamplingThickness).
  /// Surface samples drop at most ~15 % (noisy scans; 0-3 % on clean samples), SPH frames
  /// 22-76 % (the thinner ones since noisy samplings are oriented within their sheets); parts
  /// 1-1.5 spacings thick drop ~60 % too, but they close. polygonize meshes volume particles.
  bool looks_like_volume = false;
  double seconds_normals = 0;
  double seconds_extraction = 0;
  double seconds_repair = 0;
  double seconds_orient = 0;
};

struct SurfaceResult {
  /// Vertices are the input particles (index i = particle i). Normals: per vertex, from the
  /// surface's faces (angle-weighted), so they agree with the winding; particles in no
  /// triangle keep their (given or estimated) normal.
  TriMesh mesh;
  TriangulateStats triangulation;
  SurfaceStats surface;
};

/// The whole chain. Deterministic, byte-identical for any thread count.
/// @throws like triangulate_raw, plus Error(InvalidArgument) for bad surface options.
PM_EXPORT SurfaceResult reconstruct_surface(const PointCloud& cloud, const SurfaceOptions& options = {});

}  // namespace particlemesh
