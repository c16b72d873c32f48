// Internal: a triangle mesh's corners bucketed by vertex, in parallel and with the same layout
// for any thread count: a counting sort over chunks of triangles (one a thread), so each
// vertex's corners come out in triangle order. The topology report and Loop's limit rings
// walk each vertex's fan from it without reading the triangles again.
#pragma once

#include "particlemesh/core/config.h"

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <type_traits>
#include <vector>

#include <tbb/task_arena.h>

#include "core/huge_pages.h"
#include "core/parallel.h"
#include "particlemesh/mesh/tri_mesh.h"

namespace PM_NAMESPACE::detail {

/// offset (V + 1 entries) and out (3 F entries, resized to that; a std::vector, or a
/// FreshArray that is not filled first): vertex v's corners are out[offset[v] ..
/// offset[v + 1]), in increasing triangle order; the corner c of triangle f is stored as
/// make(f, c) (what the caller's passes need of it: its index 3 f + c, its next and previous
/// vertex, ...). Every vertex index must be below V.
template <class Out, class Make>
void bucket_corners_by_vertex(const std::vector<Triangle>& T, size_t V, std::vector<uint32_t>& offset, Out& out,
                              Make make) {
  const size_t F = T.size();
  offset.assign(V + 1, 0);
  if constexpr (std::is_same_v<Out, FreshArray<typename std::remove_reference_t<decltype(out[0])>>>) {
    out = Out(3 * F);
  } else {
    out.resize(3 * F);
  }
  // A counting sort is stable: each vertex's corners come out in triangle order however the
  // triangles are chunked, so the chunks may follow the threads (one count array of V each).
  const size_t kChunks = std::clamp<size_t>(size_t(tbb::this_task_arena::max_concurrency()), 1, 8);
  const size_t per = (F + kChunks - 1) / kChunks;
  std::vector<uint32_t> at(kChunks * V, 0);  // per chunk and vertex: its count, then its slot
  parallel_blocks(kChunks, 1, [&](size_t cb, size_t ce) {
    for (size_t h = cb; h < ce; ++h) {
      uint32_t* a = at.data() + h * V;
      for (size_t f = h * per; f < std::min(F, (h + 1) * per); ++f) {
        ++a[T[f][0]];
        ++a[T[f][1]];
        ++a[T[f][2]];
      }
    }
  });
  parallel_blocks(V, 16384, [&](size_t b, size_t e) {
    for (size_t v = b; v < e; ++v) {
      uint32_t n = 0;
      for (size_t h = 0; h < kChunks; ++h) n += at[h * V + v];
      offset[v + 1] = n;
    }
  });
  for (size_t v = 0; v < V; ++v) offset[v + 1] += offset[v];
  parallel_blocks(V, 16384, [&](size_t b, size_t e) {
    for (size_t v = b; v < e; ++v) {
      uint32_t slot = offset[v];
      for (size_t h = 0; h < kChunks; ++h) {
        const uint32_t n = at[h * V + v];
        at[h * V + v] = slot;
        slot += n;
      }
    }
  });
  parallel_blocks(kChunks, 1, [&](size_t cb, size_t ce) {
    for (size_t h = cb; h < ce; ++h) {
      uint32_t* a = at.data() + h * V;
      for (size_t f = h * per; f < std::min(F, (h + 1) * per); ++f)
        for (uint32_t c = 0; c < 3; ++c) out[a[T[f][c]]++] = make(f, c);
    }
  });
}

}  // namespace particlemesh::detail
