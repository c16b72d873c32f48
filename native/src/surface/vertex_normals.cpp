#include "surface/vertex_normals.h"

#include <atomic>
#include <vector>

#include "core/cpu_clones.h"
#include "core/parallel.h"
#include "surface/triangle_angles.h"

namespace PM_NAMESPACE::detail {

namespace {

/// x[i] = fast_acos(x[i]) for m values: a loop the compiler turns into vector instructions,
/// compiled per x86-64 level (PM_CPU_CLONES). One corner after the other, each arc-cosine's
/// chain of products waited for the last; side by side they overlap. The same operations on
/// each value, so the same bits.
PM_CPU_CLONES void fast_acos_all(double* __restrict x, size_t m) {
  for (size_t i = 0; i < m; ++i) x[i] = fast_acos(x[i]);
}

}  // namespace

std::vector<Vec3> surface_vertex_normals(const EditableSurface& s, const std::vector<uint8_t>& active,
                                         const std::vector<Vec3>& fallback, size_t& unused) {
  const std::vector<Vec3>& P = s.positions();
  std::vector<Vec3> out(P.size());
  std::atomic<size_t> none{0};
  parallel_blocks(P.size(), 4096, [&](size_t b, size_t e) {
    size_t block_none = 0;
    // A vertex's triangles' face normals and its corners' cosines, then angles.
    std::vector<Vec3> faces(16);
    std::vector<double> angles(16);
    for (size_t v = b; v < e; ++v) {
      size_t m = 0;
      s.for_each_tri(uint32_t(v), [&](uint32_t t) {
        if (m == faces.size()) faces.resize(2 * m), angles.resize(2 * m);
        const Triangle& T = s.triangle(t);
        const int k = corner_of(T, uint32_t(v));
        faces[m] = s.face_normal(T);
        angles[m++] = corner_cosine(P[v], P[T[(k + 1) % 3]], P[T[(k + 2) % 3]]);
      });
      fast_acos_all(angles.data(), m);
      Vec3 sum, widest;
      double weight = 0, widest_angle = 0;
      const bool any = m > 0;
      for (size_t i = 0; i < m; ++i) {
        const Vec3& f = faces[i];
        const double angle = angles[i];
        if (!(angle > 0) || !(squared_norm(f) > 0)) continue;  // a degenerate triangle
        sum += f * angle;
        weight += angle;
        if (angle > widest_angle) {
          widest_angle = angle;
          widest = f;
        }
      }
      // Where the triangles cancel (two folded onto each other at a scan's depth edge, where
      // the points of a row are collinear) the particle's own normal serves, else its widest
      // triangle's: no used vertex is left with a zero or arbitrary normal.
      if (norm(sum) > 1e-6 * weight) out[v] = normalized(sum);
      else out[v] = squared_norm(fallback[v]) > 0 || !(widest_angle > 0) ? fallback[v] : widest;
      block_none += active[v] && !any;
    }
    none.fetch_add(block_none, std::memory_order_relaxed);
  });
  unused = none.load();
  return out;
}

}  // namespace particlemesh::detail
