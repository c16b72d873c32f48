#include "particlemesh/surface/triangulate.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <string>

#include <tbb/parallel_sort.h>

#include "core/parallel.h"
#include "core/progress_tracker.h"
#include "particlemesh/core/error.h"
#include "particlemesh/spatial/neighbor_grid.h"
#include "spatial/grid_search.h"
#include "surface/neighbor_lists.h"
#include "surface/smallest_sphere.h"
#include "surface/spacing_impl.h"

namespace particlemesh {

namespace {

using Clock = std::chrono::steady_clock;
double seconds_since(Clock::time_point t) {
  return std::chrono::duration<double>(Clock::now() - t).count();
}

void check_options(const TriangulateOptions& o) {
  if (!std::isfinite(o.spacing) || o.spacing < 0)
    throw Error(Status::InvalidArgument,
                "spacing must be a finite positive length (or 0 to estimate it), got " +
                    std::to_string(o.spacing));
  if (!std::isfinite(o.max_edge_factor) || o.max_edge_factor <= 0 || o.max_edge_factor > 100)
    throw Error(Status::InvalidArgument,
                "max_edge_factor must be in (0, 100], got " + std::to_string(o.max_edge_factor));
  if (o.threads < 0) throw Error(Status::InvalidArgument, "threads must be >= 0 (0 = all cores)");
  if (o.max_neighbors < 2) throw Error(Status::InvalidArgument, "max_neighbors must be at least 2");
}

struct TestCounters {
  size_t candidates = 0, degenerate = 0, ties = 0;
};

}  // namespace

TriangulateResult triangulate_raw(const PointCloud& cloud, const TriangulateOptions& options) {
  check_options(options);
  validate_point_cloud(cloud);
  const size_t n = cloud.size();
  if (n == 0) throw Error(Status::InvalidInput, "the point cloud is empty");
  if (n < 3) throw Error(Status::InvalidInput, "at least three points are needed, got " + std::to_string(n));

  detail::ProgressTracker tracker(options.progress);
  TriangulateResult result;
  TriangulateStats& st = result.stats;
  st.points = n;

  detail::with_threads(options.threads, [&] {
    // 1. Spacing.
    auto t0 = Clock::now();
    if (options.spacing > 0) {
      st.spacing = options.spacing;
    } else {
      const SpacingEstimate est = detail::estimate_spacing_impl(cloud.positions.data(), n, tracker, 0.0, 0.3);
      st.spacing = est.spacing;
      st.spacing_estimated = true;
    }
    st.max_edge = options.max_edge_factor * st.spacing;
    if (!(st.max_edge > 0) || !std::isfinite(st.max_edge))
      throw Error(Status::InvalidArgument, "the max edge length is not a positive finite number");
    st.seconds_spacing = seconds_since(t0);

    // 2. Grid of cell L and neighbour lists within L.
    t0 = Clock::now();
    tracker.stage("neighbour search", 0.3, 0.55, n);
    const NeighborGrid grid(cloud.positions.data(), n, st.max_edge);
    size_t duplicates = 0;
    const std::vector<uint32_t> rep = detail::find_duplicates(grid, &duplicates);
    st.duplicate_points = duplicates;
    if (n - duplicates < 3)
      throw Error(Status::InvalidInput, "fewer than three distinct points (all points coincide?)");
    const detail::NeighborLists nbr =
        detail::build_neighbor_lists(grid, rep, st.max_edge, options.max_neighbors, tracker);
    st.max_neighbors_seen = nbr.max_count;
    st.seconds_neighbors = seconds_since(t0);

    // 3. The test. Each triangle is generated once, from its lowest sorted index i, as a pair
    //    j < k of i's higher neighbours; blockers lie within 0.82 L of some corner (proof in
    //    docs/triangulation.md), so the three corners' lists hold every candidate blocker.
    t0 = Clock::now();
    tracker.stage("testing triangles", 0.55, 0.95, n);
    const double L2 = st.max_edge * st.max_edge;
    const auto& P = grid.sorted_points();
    const size_t block = 1024;
    const size_t blocks = (n + block - 1) / block;
    std::vector<std::vector<Triangle>> out(blocks);
    std::vector<TestCounters> counters(blocks);
    detail::parallel_blocks(blocks, 1, [&](size_t bb, size_t be) {
      for (size_t b = bb; b < be; ++b) {
        if (tracker.cancelled()) return;
        auto& tris = out[b];
        auto& cnt = counters[b];
        const uint32_t sb = uint32_t(b * block), se = uint32_t(std::min(n, (b + 1) * block));
        for (uint32_t i = sb; i < se; ++i) {
          const uint32_t* ni = nbr.begin(i);
          const uint32_t* ne = nbr.end(i);
          const uint32_t* first = std::upper_bound(ni, ne, i);
          for (const uint32_t* pj = first; pj != ne; ++pj) {
            const uint32_t j = *pj;
            for (const uint32_t* pk = pj + 1; pk != ne; ++pk) {
              const uint32_t k = *pk;
              if (squared_distance(P[j], P[k]) > L2) continue;
              const detail::SmallestSphere s = detail::smallest_sphere(P[i], P[j], P[k]);
              if (s.degenerate) {
                ++cnt.degenerate;
                continue;
              }
              ++cnt.candidates;
              bool blocked = false, tie = false;
              for (const uint32_t v : {i, j, k}) {
                for (const uint32_t* q = nbr.begin(v); q != nbr.end(v); ++q) {
                  if (*q == i || *q == j || *q == k) continue;
                  if (detail::sphere_contains(s, P[*q], &tie)) {
                    blocked = true;
                    break;
                  }
                }
                if (blocked) break;
              }
              if (tie) ++cnt.ties;
              if (blocked) continue;
              Triangle t{grid.original_index(i), grid.original_index(j), grid.original_index(k)};
              std::sort(t.begin(), t.end());
              tris.push_back(t);
            }
          }
        }
        tracker.tick(se - sb);
      }
    });
    tracker.check();

    size_t total = 0;
    for (size_t b = 0; b < blocks; ++b) {
      total += out[b].size();
      st.candidates += counters[b].candidates;
      st.degenerate += counters[b].degenerate;
      st.ties += counters[b].ties;
    }
    tracker.stage("sorting", 0.95, 1.0);
    std::vector<Triangle>& tris = result.mesh.triangles;
    tris.reserve(total);
    for (auto& v : out) {
      tris.insert(tris.end(), v.begin(), v.end());
      std::vector<Triangle>().swap(v);
    }
    tbb::parallel_sort(tris.begin(), tris.end());
    st.kept = tris.size();
    st.seconds_test = seconds_since(t0);
  });

  result.mesh.positions = cloud.positions;
  result.mesh.normals = cloud.normals;
  result.mesh.attributes = cloud.attributes;
  tracker.finish();
  return result;
}

}  // namespace particlemesh
