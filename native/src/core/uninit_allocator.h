// Internal: an allocator whose resize leaves trivial elements uninitialised.
#pragma once

#include "particlemesh/core/config.h"

#include <memory>
#include <utility>

namespace PM_NAMESPACE::detail {

/// An allocator whose resize leaves trivial elements uninitialised (default-initialised: a
/// type without member initialisers keeps whatever the memory holds). For large arrays that a
/// parallel pass fills whole: their pages are then first touched by that pass, not zeroed by
/// a serial one before (the surface's corner lists, 150 MB at 1M points; a grid's entries).
template <class T>
struct UninitAllocator : std::allocator<T> {
  template <class U>
  struct rebind {
    using other = UninitAllocator<U>;
  };
  template <class U, class... Args>
  void construct(U* p, Args&&... args) {
    if constexpr (sizeof...(Args) == 0) ::new (static_cast<void*>(p)) U;
    else ::new (static_cast<void*>(p)) U(std::forward<Args>(args)...);
  }
};

}  // namespace PM_NAMESPACE::detail
