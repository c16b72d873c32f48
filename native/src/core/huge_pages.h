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
#include <cstdlib>
#include <memory>
#include <new>
#include <type_traits>
#include <vector>

#if defined(__linux__)
#include <sys/mman.h>
#endif

namespace PM_NAMESPACE::detail {

/// Asks for transparent huge pages under the 2 MiB-aligned interior of [p, p + bytes) when
/// that is large (at least 8 MiB); call it before the memory is first touched.
inline void advise_huge_pages([[maybe_unused]] void* p, [[maybe_unused]] size_t bytes) {
#if defined(__linux__) && defined(MADV_HUGEPAGE)
  constexpr size_t kHuge = size_t(2) << 20;
  if (bytes < 4 * kHuge) return;
  const uintptr_t begin = reinterpret_cast<uintptr_t>(p);
  const uintptr_t lo = (begin + kHuge - 1) & ~uintptr_t(kHuge - 1);
  const uintptr_t hi = (begin + bytes) & ~uintptr_t(kHuge - 1);
  if (hi > lo) ::madvise(reinterpret_cast<void*>(lo), hi - lo, MADV_HUGEPAGE);  // advice: failure is harmless
#endif
}

/// v.resize(n), after asking for huge pages under the new storage when it is large (at
/// least 8 MiB) and v has no storage yet. The contents are as resize() makes them.
template <class T>
void resize_huge(std::vector<T>& v, size_t n) {
  if (v.capacity() == 0) {
    v.reserve(n);
    advise_huge_pages(v.data(), n * sizeof(T));
  }
  v.resize(n);
}

/// n elements of a trivial type, left uninitialised (for arrays every element of which is
/// written before it is read: no pass that zeroes tens of MB only to overwrite them), with
/// huge pages asked for as by resize_huge.
template <class T>
class FreshArray {
  static_assert(std::is_trivially_default_constructible_v<T> && std::is_trivially_destructible_v<T>);

 public:
  FreshArray() = default;
  explicit FreshArray(size_t n) : data_(static_cast<T*>(std::malloc(n == 0 ? 1 : n * sizeof(T)))), size_(n) {
    if (!data_) throw std::bad_alloc();
    advise_huge_pages(data_.get(), n * sizeof(T));
  }
  T* data() { return data_.get(); }
  const T* data() const { return data_.get(); }
  T& operator[](size_t i) { return data_.get()[i]; }
  const T& operator[](size_t i) const { return data_.get()[i]; }
  size_t size() const { return size_; }

 private:
  struct Free {
    void operator()(T* p) const { std::free(p); }
  };
  std::unique_ptr<T, Free> data_;
  size_t size_ = 0;
};

}  // namespace particlemesh::detail
