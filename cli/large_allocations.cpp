// The program's global operator new: on request, transparent huge pages under large blocks.
//
// `particlemesh smooth` builds OpenSubdiv's refined levels (dozens of std::vectors of 1-16 MB
// for a 1M-triangle Loop result), fills them once and frees them: fresh memory, which costs
// the kernel one page fault per 4 KiB page first written (its memory-cgroup charge, its
// zeroing, its page-table locks). Where transparent huge pages are enabled "madvise" (the
// default of many distributions), madvise(MADV_HUGEPAGE) on a block before it is first touched
// turns 512 of those faults into one: the command's page faults fall from 44 000 to about 27 000 and
// its CPU time by 5-10 % (bench/RESULTS.md). glibc's own switch (the glibc.malloc.hugetlb
// tunable) is read only from the environment at start-up, and those vectors are allocated
// inside OpenSubdiv, so the advice is given here, in the operator new every library of the
// program calls (a program may replace it: C++ [replacement.functions]). It is off until a
// command asks: on `triangulate` (many short-lived blocks, only partly used) huge pages were
// measured to cost more system time than they save. The advice never changes any output.
// Under AddressSanitizer the sanitizer's operator new is kept.
#include "large_allocations.h"

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <new>

#if defined(__linux__)
#include <sys/mman.h>
#endif

#if defined(__SANITIZE_ADDRESS__)
#define PM_CLI_KEEP_OPERATOR_NEW 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define PM_CLI_KEEP_OPERATOR_NEW 1
#endif
#endif

namespace {
std::atomic<bool> g_huge_pages{false};
}  // namespace

namespace particlemesh::cli {
void huge_pages_for_large_blocks() { g_huge_pages.store(true, std::memory_order_relaxed); }
}  // namespace particlemesh::cli

#if defined(__linux__) && defined(MADV_HUGEPAGE) && !defined(PM_CLI_KEEP_OPERATOR_NEW)

namespace {

constexpr size_t kPage = 4096;
constexpr size_t kLarge = size_t(1) << 20;

void* allocate(size_t n) {
  void* p = std::malloc(n == 0 ? 1 : n);
  if (p && n >= kLarge && g_huge_pages.load(std::memory_order_relaxed)) {
    // The block's pages: the kernel backs with a huge page each 2 MiB-aligned range wholly
    // inside advised memory (malloc maps large blocks on their own, 2 MiB-aligned).
    const uintptr_t begin = reinterpret_cast<uintptr_t>(p);
    const uintptr_t lo = begin & ~uintptr_t(kPage - 1);
    const uintptr_t hi = (begin + n + kPage - 1) & ~uintptr_t(kPage - 1);
    ::madvise(reinterpret_cast<void*>(lo), hi - lo, MADV_HUGEPAGE);  // advice: failure is harmless
  }
  return p;
}

}  // namespace

// operator new[] and the nothrow forms call this one (libstdc++); the deletes call free().
void* operator new(size_t n) {
  while (true) {
    if (void* p = allocate(n)) return p;
    std::new_handler handler = std::get_new_handler();
    if (!handler) throw std::bad_alloc();
    handler();
  }
}

void operator delete(void* p) noexcept { std::free(p); }
void operator delete(void* p, size_t) noexcept { std::free(p); }

#endif
