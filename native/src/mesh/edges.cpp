#include "particlemesh/mesh/edges.h"

#include <algorithm>
#include <atomic>
#include <numeric>
#include <string>

#include "core/parallel.h"
#include "particlemesh/core/error.h"

namespace PM_NAMESPACE {

// Hand-written: OpenMesh builds its half-edge structure (and refuses non-manifold input) to
// get edges, and Blender's own edge pass was most of the time of writing a mesh into it
// (bench/RESULTS.md): here each edge belongs to its lower vertex, whose few
// higher neighbours are sorted in place.
MeshEdges mesh_edges(const std::vector<Triangle>& triangles, size_t vertex_count, int threads) {
  if (vertex_count >= (size_t(1) << 32)) throw Error(Status::LimitExceeded, "more than 2^32 - 1 vertices");
  if (triangles.size() >= (size_t(1) << 30)) throw Error(Status::LimitExceeded, "more than 2^30 triangles");
  for (size_t t = 0; t < triangles.size(); ++t) {
    const Triangle& T = triangles[t];
    for (uint32_t v : T)
      if (v >= vertex_count)
        throw Error(Status::InvalidArgument, "triangle " + std::to_string(t) + " has vertex index " + std::to_string(v) +
                                                 ", beyond the " + std::to_string(vertex_count) + " vertices");
    if (T[0] == T[1] || T[1] == T[2] || T[0] == T[2])
      throw Error(Status::InvalidArgument, "triangle " + std::to_string(t) + " repeats a vertex");
  }
  MeshEdges out;
  detail::with_threads(threads, [&] {
    const size_t n = vertex_count, m = triangles.size();
    // Per lower vertex, the higher ends of its corners' edges (with repeats), then sorted and
    // made unique in place: [off[v], end[v]).
    std::vector<uint32_t> off(n + 1, 0);
    detail::parallel_blocks(m, 8192, [&](size_t b, size_t e) {
      for (size_t t = b; t < e; ++t)
        for (int k = 0; k < 3; ++k) {
          const uint32_t x = triangles[t][k], y = triangles[t][(k + 1) % 3];
          std::atomic_ref<uint32_t>(off[std::min(x, y) + 1]).fetch_add(1, std::memory_order_relaxed);
        }
    });
    std::partial_sum(off.begin(), off.end(), off.begin());
    std::vector<uint32_t> higher(off[n]);
    std::vector<uint32_t> end(off.begin(), off.end() - 1);  // fill cursors first
    detail::parallel_blocks(m, 8192, [&](size_t b, size_t e) {
      for (size_t t = b; t < e; ++t)
        for (int k = 0; k < 3; ++k) {
          const uint32_t x = triangles[t][k], y = triangles[t][(k + 1) % 3];
          higher[std::atomic_ref<uint32_t>(end[std::min(x, y)]).fetch_add(1, std::memory_order_relaxed)] = std::max(x, y);
        }
    });
    // Sorted, so the order of the fill (which depends on the threads) is gone.
    std::vector<uint32_t> first(n + 1, 0);  // the id of v's first edge, then the total
    detail::parallel_blocks(n, 8192, [&](size_t b, size_t e) {
      for (size_t v = b; v < e; ++v) {
        std::sort(higher.begin() + off[v], higher.begin() + end[v]);
        end[v] = uint32_t(std::unique(higher.begin() + off[v], higher.begin() + end[v]) - higher.begin());
        first[v + 1] = end[v] - off[v];
      }
    });
    std::partial_sum(first.begin(), first.end(), first.begin());
    out.edges.resize(first[n]);
    detail::parallel_blocks(n, 8192, [&](size_t b, size_t e) {
      for (size_t v = b; v < e; ++v)
        for (uint32_t i = off[v]; i < end[v]; ++i) out.edges[first[v] + (i - off[v])] = {uint32_t(v), higher[i]};
    });
    out.corner_edges.resize(3 * m);
    detail::parallel_blocks(m, 8192, [&](size_t b, size_t e) {
      for (size_t t = b; t < e; ++t)
        for (int k = 0; k < 3; ++k) {
          const uint32_t x = triangles[t][k], y = triangles[t][(k + 1) % 3], lo = std::min(x, y);
          const auto at = std::lower_bound(higher.begin() + off[lo], higher.begin() + end[lo], std::max(x, y));
          out.corner_edges[3 * t + size_t(k)] = first[lo] + uint32_t(at - (higher.begin() + off[lo]));
        }
    });
  });
  return out;
}

}  // namespace particlemesh
