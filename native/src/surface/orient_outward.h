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
size_t orient_closed_components_outward(const std::vector<Vec3>& positions, std::vector<Triangle>& triangles,
                                        const std::vector<uint64_t>& boundary,
                                        std::vector<Vec3>* vertex_normals = nullptr, bool turn = true,
                                        FlatPieces* flat = nullptr, NearlyClosed* nearly = nullptr);

}  // namespace particlemesh::detail
