// Internal: a stable, parallel counting sort with positions independent of the thread count
// (TBB and the standard library have no radix sort). Used by the surface extraction and the
// neighbour grid.
#pragma once

#include "particlemesh/core/config.h"

#include <algorithm>
#include <cstddef>
#include <vector>

#include "core/parallel.h"

namespace PM_NAMESPACE::detail {

/// A stable counting sort in parallel: item i of n goes to bucket bucket_of(i) < buckets, and
/// place(i, pos) is called with its position in bucket order (the buckets in turn, the items
/// of each in order). Counted and placed per fixed chunk of items, so the positions are the
/// same for any thread count. Returns the buckets' starts (buckets + 1 entries). With
/// `skip_single`, nothing is placed when one bucket holds every item.
template <class BucketOf, class Place>
std::vector<size_t> counting_place(size_t n, size_t buckets, BucketOf&& bucket_of, Place&& place,
                                   bool skip_single = false) {
  const size_t chunk = 65536, chunks = (n + chunk - 1) / chunk;
  std::vector<size_t> at(chunks * buckets, 0);  // per chunk and bucket: its count, then its slot
  parallel_blocks(chunks, 1, [&](size_t hb, size_t he) {
    for (size_t h = hb; h < he; ++h)
      for (size_t i = h * chunk; i < std::min(n, (h + 1) * chunk); ++i) ++at[h * buckets + bucket_of(i)];
  });
  std::vector<size_t> start(buckets + 1, 0);
  bool single = false;
  for (size_t b = 0; b < buckets; ++b) {
    start[b + 1] = start[b];
    for (size_t h = 0; h < chunks; ++h) {
      const size_t count = at[h * buckets + b];
      at[h * buckets + b] = start[b + 1];
      start[b + 1] += count;
    }
    single = single || start[b + 1] - start[b] == n;
  }
  if (skip_single && single) return start;
  parallel_blocks(chunks, 1, [&](size_t hb, size_t he) {
    for (size_t h = hb; h < he; ++h)
      for (size_t i = h * chunk; i < std::min(n, (h + 1) * chunk); ++i) place(i, at[h * buckets + bucket_of(i)]++);
  });
  return start;
}

/// Whether counting_place's bucket starts put all n items in one bucket (with skip_single,
/// nothing was then placed: the order stands).
inline bool one_bucket(const std::vector<size_t>& start, size_t n) {
  return std::adjacent_find(start.begin(), start.end(), [&](size_t a, size_t b) { return b - a == n; }) != start.end();
}

}  // namespace particlemesh::detail
