// Internal: a large fresh vector's pages faulted in on all cores before it is filled.
//
// std::vector::resize value-initialises every new element on the calling thread, so a fresh
// output of tens of MB (a polygonized mesh's positions, normals and triangles) costs one page
// fault per 4 KiB page - the kernel's zeroing, its memory-cgroup charge, its page-table locks
// - all on one core, while the others wait for the parallel pass that fills it. Touching one
// byte of every page first, in parallel, moves those faults onto every core; the resize that
// follows then only writes memory that is already mapped. The contents are what resize()
// makes them either way.
#pragma once

#include "particlemesh/core/config.h"

#include <algorithm>
#include <cstddef>
#include <type_traits>
#include <vector>

#include "core/parallel.h"

namespace PM_NAMESPACE::detail {

/// v.resize(n) for an empty v: the new storage's pages are first touched on all cores of the
/// current arena when it is large (at least 4 MiB), then resize() value-initialises it as
/// usual. Not for a v that already has elements (resize() then keeps them).
template <class T>
void resize_touched(std::vector<T>& v, size_t n) {
  static_assert(std::is_trivially_copyable_v<T> && std::is_trivially_destructible_v<T>);
  constexpr size_t kPage = 4096, kChunk = size_t(1) << 21;  // a task touches 2 MiB
  const size_t bytes = n * sizeof(T);
  if (v.capacity() == 0 && bytes >= 2 * kChunk) {
    v.reserve(n);
    // Raw storage, no element constructed yet: writing its bytes is allowed (T is trivial).
    volatile unsigned char* const base = reinterpret_cast<unsigned char*>(v.data());
    parallel_blocks((bytes + kChunk - 1) / kChunk, 1, [&](size_t b, size_t e) {
      for (size_t at = b * kChunk, end = std::min(bytes, e * kChunk); at < end; at += kPage) base[at] = 0;
    });
  }
  v.resize(n);
}

}  // namespace particlemesh::detail
