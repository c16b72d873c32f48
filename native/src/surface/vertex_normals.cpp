#include "surface/vertex_normals.h"

#include <atomic>

#include "core/parallel.h"
#include "surface/triangle_angles.h"

namespace PM_NAMESPACE::detail {

std::vector<Vec3> surface_vertex_normals(const EditableSurface& s, const std::vector<uint8_t>& active,
                                         const std::vector<Vec3>& fallback, size_t& unused) {
  const std::vector<Vec3>& P = s.positions();
  std::vector<Vec3> out(P.size());
  std::atomic<size_t> none{0};
  parallel_blocks(P.size(), 4096, [&](size_t b, size_t e) {
    size_t block_none = 0;
    for (size_t v = b; v < e; ++v) {
      Vec3 sum, widest;
      double weight = 0, widest_angle = 0;
      bool any = false;
      s.for_each_tri(uint32_t(v), [&](uint32_t t) {
        any = true;
        const Triangle& T = s.triangle(t);
        const int k = corner_of(T, uint32_t(v));
        const Vec3 f = s.face_normal(T);
        const double angle = fast_acos(corner_cosine(P[v], P[T[(k + 1) % 3]], P[T[(k + 2) % 3]]));
        if (!(angle > 0) || !(squared_norm(f) > 0)) return;  // a degenerate triangle
        sum += f * angle;
        weight += angle;
        if (angle > widest_angle) {
          widest_angle = angle;
          widest = f;
        }
      });
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
