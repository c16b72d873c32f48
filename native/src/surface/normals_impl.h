// Internal: normal estimation over an existing grid and neighbour lists.
#pragma once

#include "particlemesh/core/config.h"

#include <vector>

#include "core/progress_tracker.h"
#include "particlemesh/core/vec3.h"
#include "particlemesh/mesh/tri_mesh.h"
#include "particlemesh/spatial/neighbor_grid.h"
#include "surface/neighbor_lists.h"

namespace PM_NAMESPACE::detail {

/// Unoriented unit normals indexed by SORTED index (duplicates copy their representative's)
/// from the lists' neighbours within `radius[s]` of each point s (its edge limit L_s: at most
/// the lists' radius; between two points the pair limit of theirs, raw_triangulation.h).
/// A plain PCA of a point's neighbourhood mixes in a second sheet that passes within the
/// radius (at a fold, a thin part, the rim of two close surfaces), tilting the normal. So when
/// `triangles` (the raw smallest-sphere triangles, sorted indices) are given, the plane comes from
/// the raw triangle at the point with the most neighbours within a quarter of the radius of
/// its plane (the point's own sheet is the denser one near it), refined by a PCA of those
/// inliers; a plane whose other neighbours lie well out on both sides of it (one ring of
/// samples around a thin part) gives way to the best one-sided plane nearer the plain PCA's
/// normal. Without triangles, or where none has three inliers, the plain PCA is used.
std::vector<Vec3> pca_normals_sorted(const NeighborGrid& grid, const std::vector<uint32_t>& rep,
                                     const NeighborLists& lists, const std::vector<double>& radius,
                                     ProgressTracker& tracker, const std::vector<Triangle>* triangles = nullptr);

/// Orient unit normals (sorted index) consistently over a minimum spanning tree of the
/// neighbour graph (Hoppe et al. 1992) with signed edges: an edge that lies in the tangent
/// planes joins points of one sheet, whose normals must agree; an edge along the (parallel)
/// normals crosses a gap between two sheets, whose normals must be opposite (across any gap
/// of a closed surface the outward normals both face the gap or both face away). Each edge
/// costs 1 - |n_i . n_j| plus how far it is from being clearly one or the other, so the tree
/// follows the clearest evidence first. Each tree faces as `reference` normals (sorted index,
/// may be empty) say on the majority of its points, else its highest point faces +z.
/// `noisy` (a sampling that scatters across its surface, kNoisySamplingThickness, but fills
/// no volume, kVolumeSamplingThickness): an edge
/// along the normals is as likely two samples of one sheet a noise's depth apart as two
/// sheets, so edges between sheets cost 1 more: the tree takes one only where no edge within
/// a sheet joins.
void orient_normals_mst(const NeighborGrid& grid, const std::vector<uint32_t>& rep,
                        const NeighborLists& lists, const std::vector<double>& radius, std::vector<Vec3>& normals,
                        const std::vector<Vec3>& reference, ProgressTracker& tracker, bool noisy = false);

/// Orient unit normals (sorted index) by reference normals (sorted index): where a reference
/// clearly says which way a point faces (|cos| >= 0.3) it decides; the rest take the side the
/// decided neighbours of their sheet vote for. O(N); used when the cloud brings normals.
/// Returns false when the references are not a consistent orientation: more than 1.5 % of
/// clearly decided neighbour pairs in one plane face opposite ways (a thin part's two sides
/// aside), or those that do make one chain longer than 2.5 sqrt(points), as normals turned
/// toward a sensor do along the silhouette of a closed object seen from outside. The normals
/// are then to be re-oriented.
bool orient_normals_by_reference(const NeighborGrid& grid, const std::vector<uint32_t>& rep,
                                 const NeighborLists& lists, const std::vector<double>& radius,
                                 std::vector<Vec3>& normals, const std::vector<Vec3>& reference,
                                 ProgressTracker& tracker);

}  // namespace particlemesh::detail
