#include "surface/candidates.h"

#include <algorithm>
#include <atomic>
#include <cstring>
#include <numeric>

#include "core/counting_sort.h"
#include "core/first_touch.h"
#include "core/parallel.h"
#include "core/uninit_allocator.h"
#include "surface/triangle_angles.h"

namespace PM_NAMESPACE::detail {

namespace {

using Keys = std::vector<uint64_t, UninitAllocator<uint64_t>>;

/// Sorts keys whose low words already ascend by their high words, stably: three counting
/// passes of 11 bits (a pass where every key has the same digit is skipped). Linear, where a
/// comparison sort of the candidates was the ranking's largest cost; TBB and the standard
/// library have no radix sort.
void sort_by_high_word(Keys& key) {
  Keys tmp(key.size());
  for (int shift = 32; shift < 64; shift += 11) {
    const std::vector<size_t> start = counting_place(
        key.size(), 2048, [&](size_t i) { return (key[i] >> shift) & 2047; },
        [&](size_t i, size_t pos) { tmp[pos] = key[i]; }, true);
    if (!one_bucket(start, key.size())) key.swap(tmp);  // else nothing was placed, and the order stands
  }
}

/// A float's bits, turned so that they order as the float does (-0 taken as +0, so that equal
/// qualities tie on what follows them in a key).
uint32_t sortable_bits(float f) {
  f += 0.0f;
  uint32_t bits;
  std::memcpy(&bits, &f, sizeof bits);
  return (bits & 0x80000000u) ? ~bits : (bits | 0x80000000u);
}

}  // namespace

std::vector<Frame> tangent_frames(const std::vector<Vec3>& normals) {
  std::vector<Frame> frame;
  resize_touched(frame, normals.size());  // (48 bytes a point: its pages faulted in on all cores)
  parallel_blocks(normals.size(), 4096, [&](size_t b, size_t e) {
    for (size_t i = b; i < e; ++i)
      if (squared_norm(normals[i]) > 0) frame[i] = tangent_frame(normals[i]);
  });
  return frame;
}

CandidateSet rank_candidates(const std::vector<Vec3>& P, const std::vector<Vec3>& N,
                             const std::vector<Frame>& frame, const std::vector<uint8_t>& active,
                             const std::vector<Triangle>& raw, double cos_normal_angle, ProgressTracker& tracker,
                             const ViewRays& view) {
  CandidateSet out;
  // Per raw triangle: kept or not, turned or not (to face along its normals), its quality.
  // Eight bytes, not a copy of the triangle: the list is as long as the raw test's output.
  struct Oriented {
    float quality;
    uint8_t ok, turned;
  };
  // The per-triangle arrays below are written before they are read (o's ok and turned for
  // every triangle, the rest only where ok): left uninitialised, not zeroed on one core.
  std::vector<Oriented, UninitAllocator<Oriented>> o(raw.size());
  auto oriented = [&](size_t i) {
    Triangle t = raw[i];
    if (o[i].turned) std::swap(t[1], t[2]);
    return t;
  };
  const double cosa = cos_normal_angle, cosf = std::max(cosa, 0.0);
  const size_t n = P.size();
  auto& vc_off = out.corner_offset;
  vc_off.assign(n + 1, 0);  // each vertex's corners, counted here
  std::atomic<size_t> kept_sum{0}, shadow_sum{0};
  parallel_blocks(raw.size(), 4096, [&](size_t b, size_t e) {
    size_t block_kept = 0, block_shadow = 0;
    for (size_t i = b; i < e; ++i) {
      Triangle t = raw[i];
      o[i].ok = o[i].turned = 0;
      if (!active[t[0]] || !active[t[1]] || !active[t[2]]) continue;
      const Vec3 &na = N[t[0]], &nb = N[t[1]], &nc = N[t[2]];
      if (!(squared_norm(na) > 0 && squared_norm(nb) > 0 && squared_norm(nc) > 0)) continue;
      Vec3 f = cross(P[t[1]] - P[t[0]], P[t[2]] - P[t[0]]);
      const bool turned = dot(f, na + nb + nc) < 0;
      if (turned) {
        std::swap(t[1], t[2]);
        f = -f;
      }
      const Vec3 fu = normalized(f);
      if (dot(na, nb) < cosa || dot(nb, nc) < cosa || dot(na, nc) < cosa) continue;
      if (dot(fu, na) < cosf || dot(fu, nb) < cosf || dot(fu, nc) < cosf) continue;
      if (view.shadows(P[t[0]], P[t[1]], P[t[2]])) {
        ++block_shadow;
        continue;
      }
      o[i].quality = float(-min_corner_cosine(P[t[0]], P[t[1]], P[t[2]]));  // ~ the largest angle
      o[i].ok = 1;
      o[i].turned = turned;
      ++block_kept;
      for (uint32_t v : t) std::atomic_ref<uint32_t>(vc_off[v + 1]).fetch_add(1, std::memory_order_relaxed);
    }
    kept_sum.fetch_add(block_kept, std::memory_order_relaxed);
    shadow_sum.fetch_add(block_shadow, std::memory_order_relaxed);
  });
  tracker.check();
  const size_t kept = kept_sum.load();
  out.rejected_shadow = shadow_sum.load();
  out.rejected_conormal = raw.size() - kept - out.rejected_shadow;
  // Sorted as (quality, index) keys: a float's bits, with the sign folded, order as the float.
  Keys key(kept);
  counting_place(o.size(), 2, [&](size_t i) { return o[i].ok ? 0 : 1; }, [&](size_t i, size_t pos) {
    if (o[i].ok) key[pos] = (uint64_t(sortable_bits(o[i].quality)) << 32) | i;
  });
  sort_by_high_word(key);
  // The quality order puts the flat candidates last.
  out.flat_from = uint32_t(std::partition_point(key.begin(), key.end(), [](uint64_t k) {
                             return uint32_t(k >> 32) <= sortable_bits(kFlatQuality);
                           }) - key.begin());
  tracker.check();
  resize_touched(out.cand, kept);
  parallel_blocks(kept, 8192, [&](size_t b, size_t e) {
    for (size_t c = b; c < e; ++c) out.cand[c] = oriented(uint32_t(key[c]));
  });
  tracker.check();
  // Vertex -> its corners, with their arcs. Counted (above) and placed in parallel: a corner's
  // slot comes from its vertex's atomic cursor, so the order within a list depends on the
  // threads. No result does: growth reads a list as a set (its checks and the edge scan answer
  // the same in any order, and the front is a set of ranks), the boundary is sorted and the
  // triangles are put in order explicitly. Placed in the raw order, not the candidate order:
  // raw triangles come vertex by vertex, so neighbouring writes land near each other (in
  // quality order they scatter over the whole list, and cache misses dominate).
  std::vector<uint32_t, UninitAllocator<uint32_t>> rank(o.size());
  parallel_blocks(kept, 8192, [&](size_t b, size_t e) {
    for (size_t c = b; c < e; ++c) rank[uint32_t(key[c])] = uint32_t(c);
  });
  Keys().swap(key);
  std::partial_sum(vc_off.begin(), vc_off.end(), vc_off.begin());
  out.corners.resize(vc_off[n]);
  std::vector<uint32_t> fill(vc_off.begin(), vc_off.end() - 1);
  parallel_blocks(o.size(), 8192, [&](size_t b, size_t e) {
    for (size_t i = b; i < e; ++i) {
      if (!o[i].ok) continue;
      const Triangle t = oriented(i);
      for (int k = 0; k < 3; ++k) {
        const uint32_t v = t[k], succ = t[(k + 1) % 3], pred = t[(k + 2) % 3];
        const uint32_t slot = std::atomic_ref<uint32_t>(fill[v]).fetch_add(1, std::memory_order_relaxed);
        out.corners[slot] = {rank[i], succ, pred, make_arc(frame[v], P[v], P[succ], P[pred])};
      }
    }
  });
  tracker.check();
  return out;
}

}  // namespace particlemesh::detail
