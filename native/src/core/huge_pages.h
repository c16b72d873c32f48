// Internal: ask the kernel for transparent huge pages under a large, fresh buffer.
//
// A buffer of tens of MB written once costs the kernel one page fault per 4 KiB page (its
// memory-cgroup charge, its zeroing, its page-table locks), a large share of a pass that
// only fills it (Loop's limit positions and normals, the refined triangles). Where
// transparent huge pages are enabled "madvise" (the default of many distributions),
// madvise(MADV_HUGEPAGE) on the buffer's 2 MiB-aligned interior before it is first touched
// turns 512 such faults into one. Elsewhere (THP "never" or "always", other systems) the
// call changes nothing; the contents never depend on it.
#pragma once

#include "particlemesh/core/config.h"

#include <cstddef>
#include <cstdint>
#include <vector>

#if defined(__linux__)
#include <sys/mman.h>
#endif

namespace PM_NAMESPACE::detail {

/// v.resize(n), after asking for huge pages under the new storage when it is large (at
/// least 8 MiB) and v has no storage yet. The contents are as resize() makes them.
template <class T>
void resize_huge(std::vector<T>& v, size_t n) {
#if defined(__linux__) && defined(MADV_HUGEPAGE)
  constexpr size_t kHuge = size_t(2) << 20;
  if (v.capacity() == 0 && n * sizeof(T) >= 4 * kHuge) {
    v.reserve(n);
    const uintptr_t begin = reinterpret_cast<uintptr_t>(v.data());
    const uintptr_t lo = (begin + kHuge - 1) & ~uintptr_t(kHuge - 1);
    const uintptr_t hi = (begin + n * sizeof(T)) & ~uintptr_t(kHuge - 1);
    if (hi > lo) ::madvise(reinterpret_cast<void*>(lo), hi - lo, MADV_HUGEPAGE);  // advice: failure is harmless
  }
#endif
  v.resize(n);
}

}  // namespace particlemesh::detail
