// Internal: run work on a bounded number of threads with TBB.
//
// Every parallel loop in particlemesh writes its results into slots owned by input index
// (or concatenates per-block buffers in block order), never in completion order, so the
// output is byte-identical whatever the thread count.
#pragma once

#include "particlemesh/core/config.h"

#include <algorithm>
#include <cstddef>
#include <thread>
#include <type_traits>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include "particlemesh/core/error.h"

namespace PM_NAMESPACE::detail {

/// Run f() inside a TBB arena limited to `threads` workers (0 = all hardware threads).
template <class F>
auto with_threads(int threads, F&& f) -> decltype(f()) {
  if (threads < 0) throw Error(Status::InvalidArgument, "threads must be >= 0 (0 = all cores)");
  // More workers than the machine has would only make TBB warn; the output is the same.
  const int hw = tbb::this_task_arena::max_concurrency();
  const int n = threads == 0 ? hw : std::min(threads, hw);
  tbb::task_arena arena(n);
  if constexpr (std::is_void_v<decltype(f())>) {
    arena.execute([&] { f(); });
  } else {
    return arena.execute([&] { return f(); });
  }
}

/// parallel_for over [0, n) in blocks of about `grain`; fn(begin, end) per block.
template <class F>
void parallel_blocks(size_t n, size_t grain, F&& fn) {
  if (n == 0) return;
  tbb::parallel_for(tbb::blocked_range<size_t>(0, n, grain),
                    [&](const tbb::blocked_range<size_t>& r) { fn(r.begin(), r.end()); });
}

}  // namespace particlemesh::detail
