// Refine once, evaluate many: subdivision of a mesh whose vertices move while its triangles
// stay the same (an animation, a simulation's frames, live previews in a DCC).
//
// smooth_mesh() checks the mesh, has OpenSubdiv refine its topology (about half of a Loop
// call) and then interpolates the positions through it. A Smoother does the first two once,
// for the triangles it is given, and keeps what they produced: for Loop, every refined
// vertex's weights over the vertices of the level before (OpenSubdiv's stencils, recorded
// from Far::PrimvarRefiner, in the order it applies them), the last level's triangles, and
// what the limit needs. evaluate() then applies those weights to new positions on all cores:
// the same mesh, bit for bit, as smooth_mesh() of the same triangles with those positions,
// for a fraction of its cost (bench/RESULTS.md). Butterfly (OpenMesh) has no reusable
// refinement: its evaluate() runs the whole subdivision again, as smooth_mesh() does.
//
// Memory (Loop): about 60 bytes per output triangle for the weights, rings and triangles
// (a refinement to 1.6 million triangles keeps about 100 MB), kept while the Smoother lives.
#pragma once

#include <cstddef>
#include <memory>
#include <vector>

#include "particlemesh/core/export.h"
#include "particlemesh/mesh/tri_mesh.h"
#include "particlemesh/smooth/subdivide.h"

namespace PM_NAMESPACE {

class PM_EXPORT Smoother {
 public:
  /// Check `mesh` and refine its topology as smooth_mesh(mesh, options) would (the same
  /// checks and errors; options.progress reports this work). The mesh's triangles and its
  /// vertex count are what later meshes must have; its positions only serve the checks and
  /// the orientation repair (see subdivide.h).
  /// @throws as smooth_mesh().
  explicit Smoother(const TriMesh& mesh, const SmoothOptions& options = {});
  ~Smoother();
  Smoother(Smoother&&) noexcept;
  Smoother& operator=(Smoother&&) noexcept;

  /// smooth_mesh(m, options) for the mesh m with this smoother's triangles and the given
  /// positions (one per vertex of the mesh it was made from) and attributes (any names, each
  /// vertex count x components values): the same result, byte for byte. When moved vertices
  /// turn a repaired component inside out (its orientation came from its volume), the whole
  /// smooth_mesh() runs instead, so the result still agrees. Values per triangle corner
  /// (texture coordinates) belong to the triangles: the mesh the smoother was made from gives
  /// them, subdivided once. Thread-safe (const).
  /// @throws Error(InvalidInput) a position count other than the vertex count, a non-finite
  ///         or too large coordinate or attribute value (the message names the vertex).
  SmoothResult evaluate(const std::vector<Vec3>& positions,
                        const std::vector<VertexAttribute>& attributes = {}) const;

  /// Whether a mesh with these triangles over `vertex_count` vertices is one this smoother
  /// evaluates (the same triangles, in the same order, the same vertex count).
  bool matches(const std::vector<Triangle>& triangles, size_t vertex_count) const;

  size_t vertex_count() const;    ///< vertices of the mesh it was made from
  size_t triangle_count() const;  ///< triangles of the mesh it was made from
  const SmoothOptions& options() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace particlemesh
