#include "surface/view_rays.h"

#include <atomic>

#include "core/parallel.h"

namespace PM_NAMESPACE::detail {

bool plausible_viewpoint(const std::vector<Vec3>& P, const std::vector<Vec3>& N, const std::vector<uint8_t>& active,
                         const Vec3& origin) {
  const double sin_limit = std::sin(12.5 * 3.14159265358979323846 / 180.0);
  std::atomic<size_t> counted{0}, grazing{0}, on{0};
  parallel_blocks(P.size(), 8192, [&](size_t b, size_t e) {
    size_t c = 0, g = 0, o = 0;
    for (size_t i = b; i < e; ++i) {
      if (!active[i]) continue;
      const Vec3 r = P[i] - origin;
      const double rr = squared_norm(r), nn = squared_norm(N[i]);
      if (!(rr > 0)) ++o;
      if (!(rr > 0) || !(nn > 0)) continue;
      ++c;
      const double d = dot(r, N[i]);
      g += d * d < sin_limit * sin_limit * rr * nn;
    }
    counted.fetch_add(c, std::memory_order_relaxed);
    grazing.fetch_add(g, std::memory_order_relaxed);
    on.fetch_add(o, std::memory_order_relaxed);
  });
  return on.load() == 0 && counted.load() > 0 && double(grazing.load()) <= kMaxGrazing * double(counted.load());
}

}  // namespace particlemesh::detail
