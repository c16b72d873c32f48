// Internal: turning the closed components of the finished surface (and those closed but for
// small openings) to face outward.
#pragma once

#include "particlemesh/core/config.h"

#include <cstddef>
#include <cstdint>
#include <vector>

#include "particlemesh/core/vec3.h"
#include "particlemesh/mesh/tri_mesh.h"

namespace PM_NAMESPACE::detail {

/// Turn every closed component (one holding none of the `boundary` half-edges, a << 32 | b)
/// to face away from the solid it bounds: outward (positive volume), or into the cavity for
/// one inside an odd number of others (mesh/nesting.h: a hollow ball's inner wall), negating
/// its points' `vertex_normals` (if given) to match; returns how many flipped. Components are
/// by shared vertices (the same as by shared edges on a manifold without pinches). The result
/// does not depend on the thread count.
/// With `flat` given, closed components that enclose no volume (flat pillows: a patch and a
/// reversed copy of it, as points exactly in one plane, e.g. quantized coordinates, can give)
/// are opened first: of each, the side that faces as its corners' `sides` normals (the
/// particles') is kept, the other side's triangles removed (the rest keep their order); where
/// that side is not a surface with simple outlines (or no `sides` are given), the whole piece
/// goes. With `turn` false nothing is turned.
struct FlatPieces {
  const std::vector<Vec3>* sides = nullptr;  ///< in: the particles' normals
  size_t pieces = 0;                         ///< flat closed pieces found
  size_t removed = 0;                        ///< of those, removed whole
  size_t triangles = 0;                      ///< triangles removed
  size_t points = 0;                         ///< particles left in no triangle
  std::vector<size_t> loops;                 ///< the edges of each outline the kept sides have
};
/// With `nearly` given and its loops, an open component closed but for openings small beside it
/// is turned as a closed one is, judged with each opening capped: the fans from each of its
/// loops' centroid (caps used only for the judging, not kept) add at most kMaxCapShare of its
/// area, and it then encloses a clear volume (|V| at least kMinCappedVolume of area^1.5; a
/// sphere's is 0.094). A model's vertices whose surface keeps a few holes open would
/// otherwise face whichever way the normals' spanning tree chose, inward as often as not.
/// The caller gives loops only where that tree's choice was all there was (no input normals,
/// no viewpoint): a scanner's normals inside a room face into it rightly.
constexpr double kMaxCapShare = 0.4;
constexpr double kMinCappedVolume = 0.01;
struct NearlyClosed {
  /// in: the loops left open, each a vertex sequence along the boundary half-edges v_i ->
  /// v_{i+1} (EditableSurface::trace_loops); none, nothing is judged so.
  const std::vector<std::vector<uint32_t>>* loops = nullptr;
  size_t pieces = 0;     ///< out: open components judged as closed
  size_t turned = 0;     ///< out: of those, turned
};
/// With `folds` given (and turning on), after turning: which triangles face into the solid
/// their piece bounds, for the pieces of at least kMinFoldTriangles triangles closed (not
/// inside another) or closed but for small openings (their loops' caps, as NearlyClosed caps them, add at most kMaxCapShare of their
/// area; `nearly`'s loops): the ray from just off a triangle's centre along its normal,
/// straight up, crosses the piece and its caps an odd number of times (exact for a closed
/// surface, whatever the ray). A consistently wound piece can still face inward over part of
/// itself: where the normals' spanning tree crossed between the two sides of a thin part,
/// the surface folds over from one side's winding to the other's. Every k-th triangle is
/// judged first (about `samples` of them; 0: none); only where more than `share` of their
/// area faces inward is every triangle judged. Smaller pieces are not judged: the closed
/// pieces of a few triangles that a noisy scan leaves (hundreds on a lidar sweep's near field,
/// bench/RESULTS.md) bound no solid worth the name, and judging them started a second build
/// of the whole surface that was never kept.
constexpr uint32_t kMinFoldTriangles = 64;
struct Folds {
  size_t samples = 2048;           ///< in: triangles judged first
  double share = 0.02;             ///< in: above this share of their area inward, all judged
  double sampled_area = 0;         ///< out: the area of the first triangles judged
  double sampled_inward_area = 0;  ///< out: of that, facing inward
  std::vector<uint8_t> inward;     ///< out, once all are judged: per triangle, 1 = facing inward
  double judged_area = 0;          ///< out, the same: the area of every triangle judged
  double inward_area = 0;          ///< out, the same: of that, facing inward
  size_t pieces = 0;               ///< out: the surface's pieces (components by shared vertices)
};

size_t orient_closed_components_outward(const std::vector<Vec3>& positions, std::vector<Triangle>& triangles,
                                        const std::vector<uint64_t>& boundary,
                                        std::vector<Vec3>* vertex_normals = nullptr, bool turn = true,
                                        FlatPieces* flat = nullptr, NearlyClosed* nearly = nullptr,
                                        Folds* folds = nullptr);

}  // namespace particlemesh::detail
