#include "particlemesh/surface/reconstruct.h"

#include <chrono>
#include <cmath>
#include <numbers>
#include <numeric>
#include <string>

#include <tbb/parallel_sort.h>

#include "core/parallel.h"
#include "core/progress_tracker.h"
#include "particlemesh/core/error.h"
#include "surface/normals_impl.h"
#include "surface/raw_triangulation.h"
#include "surface/surface_builder.h"

namespace particlemesh {

namespace {

using Clock = std::chrono::steady_clock;
double seconds_since(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }

void check_surface_options(const SurfaceOptions& o) {
  if (!(o.normal_angle > 0 && o.normal_angle <= 180))
    throw Error(Status::InvalidArgument, "normal_angle must be in (0, 180] degrees, got " + std::to_string(o.normal_angle));
  if (!(o.fill_edge_factor > 0 && o.fill_edge_factor <= 10))
    throw Error(Status::InvalidArgument, "fill_edge_factor must be in (0, 10], got " + std::to_string(o.fill_edge_factor));
  if (o.fill_holes > 100000)
    throw Error(Status::InvalidArgument, "fill_holes must be at most 100000 edges, got " + std::to_string(o.fill_holes));
}

// Angle-weighted vertex normals of the surface; particles in no triangle keep `fallback`.
std::vector<Vec3> surface_normals(const std::vector<Vec3>& P, const std::vector<Triangle>& T,
                                  const std::vector<Vec3>& fallback) {
  // The corners' weighted normals in parallel (the arc-cosines are the cost), then summed
  // per vertex in triangle order: the same sums for any thread count.
  std::vector<Vec3> corner(3 * T.size());
  detail::parallel_blocks(T.size(), 8192, [&](size_t b, size_t e) {
    for (size_t i = b; i < e; ++i) {
      const Triangle& t = T[i];
      const Vec3 f = normalized(cross(P[t[1]] - P[t[0]], P[t[2]] - P[t[0]]));
      for (int k = 0; k < 3; ++k) {
        const Vec3 u = P[t[(k + 1) % 3]] - P[t[k]], v = P[t[(k + 2) % 3]] - P[t[k]];
        const double c = dot(u, v) / std::sqrt(squared_norm(u) * squared_norm(v));
        corner[3 * i + size_t(k)] = f * std::acos(std::clamp(c, -1.0, 1.0));
      }
    }
  });
  std::vector<Vec3> n(P.size());
  std::vector<uint8_t> touched(P.size(), 0);
  for (size_t i = 0; i < T.size(); ++i)
    for (int k = 0; k < 3; ++k) {
      n[T[i][k]] += corner[3 * i + size_t(k)];
      touched[T[i][k]] = 1;
    }
  detail::parallel_blocks(P.size(), 8192, [&](size_t b, size_t e) {
    for (size_t i = b; i < e; ++i) n[i] = touched[i] ? normalized(n[i]) : fallback[i];
  });
  return n;
}

}  // namespace

SurfaceResult reconstruct_surface(const PointCloud& cloud, const SurfaceOptions& options) {
  check_surface_options(options);
  detail::ProgressTracker tracker(options.progress);
  SurfaceResult result;
  SurfaceStats& st = result.surface;
  std::vector<Triangle> tris;
  detail::with_threads(options.threads, [&] {
    detail::RawTriangulation raw = detail::run_raw_triangulation(cloud, options, tracker, 0.0, 0.55);
    result.triangulation = raw.stats;
    const NeighborGrid& grid = *raw.grid;
    const size_t n = cloud.size();

    auto t0 = Clock::now();
    using Source = SurfaceOptions::NormalSource;
    if (options.normals == Source::Input && !cloud.has_normals())
      throw Error(Status::InvalidArgument, "normals = input, but the cloud has no normals");
    // The finishing stages work on the points in the grid's cell order (sorted indices), as
    // the raw test does: points near in space are near in memory whatever order the input
    // lists them in (in input order, a shuffled million points took 2.4x longer).
    std::vector<Vec3> P(n);
    std::vector<uint32_t> original(n), sorted_of(n);
    std::vector<uint8_t> active(n);
    detail::parallel_blocks(n, 8192, [&](size_t b, size_t e) {
      for (size_t s = b; s < e; ++s) {
        P[s] = grid.sorted_point(uint32_t(s));
        original[s] = grid.original_index(uint32_t(s));
        sorted_of[original[s]] = uint32_t(s);
        active[s] = raw.rep[s] == s;
      }
    });
    std::vector<Vec3> normals;
    if (options.normals == Source::Input) {
      normals.resize(n);
      detail::parallel_blocks(n, 8192, [&](size_t b, size_t e) {
        for (size_t s = b; s < e; ++s) normals[s] = normalized(cloud.normals[original[s]]);
      });
    } else {
      tracker.stage("estimating normals", 0.55, 0.65, n);
      normals = detail::pca_normals_sorted(grid, raw.rep, raw.neighbors, raw.stats.max_edge, tracker, &raw.triangles);
      std::vector<Vec3> reference;
      if (options.normals == Source::Auto && cloud.has_normals()) {
        reference.resize(n);
        for (uint32_t s = 0; s < n; ++s) reference[s] = cloud.normals[original[s]];
      }
      tracker.stage("orienting normals", 0.65, 0.7);
      // The cloud's normals orient directly when they are consistent; otherwise (or without
      // them) the spanning tree orients, and they only vote which way each piece faces.
      if (reference.empty() ||
          !detail::orient_normals_by_reference(grid, raw.rep, raw.neighbors, raw.stats.max_edge, normals, reference, tracker))
        detail::orient_normals_mst(grid, raw.rep, raw.neighbors, raw.stats.max_edge, normals, reference, tracker);
      st.normals_estimated = true;
    }
    st.seconds_normals = seconds_since(t0);
    raw.grid.reset();
    raw.neighbors = {};
    // The raw triangles in sorted indices, in their order (which breaks the builder's ties).
    std::vector<Triangle> candidates(raw.triangles.size());
    detail::parallel_blocks(candidates.size(), 8192, [&](size_t b, size_t e) {
      for (size_t i = b; i < e; ++i)
        for (int k = 0; k < 3; ++k) candidates[i][k] = sorted_of[raw.triangles[i][k]];
    });
    std::vector<Triangle>().swap(raw.triangles);

    tracker.check();
    t0 = Clock::now();
    detail::BuilderOptions bo;
    bo.cos_normal_angle = std::cos(options.normal_angle * std::numbers::pi / 180.0);
    bo.max_edge = raw.stats.max_edge;
    bo.max_hole = options.fill_holes;
    bo.small_hole = std::min<size_t>(6, options.fill_holes);
    bo.fill_edge_factor = options.fill_edge_factor;
    detail::BuilderStats bs;
    tris = detail::build_surface(P, normals, active, candidates, bo, options.repair, bs, tracker);
    std::vector<Triangle>().swap(candidates);
    tracker.check();  // the steps below take up to a second at 1M points: let a cancel request in
    st.seconds_extraction = bs.seconds_candidates + bs.seconds_growth;
    st.seconds_repair = bs.seconds_repair;
    t0 = Clock::now();
    if (options.orient) {
      if (!bs.boundary_known) {  // no repair: find the boundary half-edges here
        std::vector<uint64_t> half;
        half.reserve(3 * tris.size());
        for (const Triangle& t : tris)
          for (int k = 0; k < 3; ++k) half.push_back((uint64_t(t[k]) << 32) | t[(k + 1) % 3]);
        tbb::parallel_sort(half.begin(), half.end());
        for (const Triangle& t : tris)
          for (int k = 0; k < 3; ++k) {
            const uint64_t rev = (uint64_t(t[(k + 1) % 3]) << 32) | t[k];
            if (!std::binary_search(half.begin(), half.end(), rev)) bs.boundary.push_back((uint64_t(t[k]) << 32) | t[(k + 1) % 3]);
          }
      }
      bs.components_flipped = detail::orient_closed_components_outward(P, tris, bs.boundary);
    }
    st.seconds_orient = seconds_since(t0);
    tracker.check();
    std::vector<uint8_t> used(n, 0);
    for (const Triangle& t : tris)
      for (uint32_t v : t) used[v] = 1;
    for (size_t i = 0; i < n; ++i) bs.unused_points += active[i] && !used[i];
    st.candidates = bs.candidates;
    st.rejected_conormal = bs.rejected_conormal;
    st.grown = bs.grown;
    st.seeds = bs.seeds;
    st.pinches_resolved = bs.pinches_resolved;
    st.holes_filled = bs.holes_filled;
    st.hole_triangles = bs.hole_triangles;
    st.holes_left = bs.holes_left;
    st.largest_hole_left = bs.largest_hole_left;
    st.components_flipped = bs.components_flipped;
    st.unused_points = bs.unused_points;
    for (const auto& [edges, width] : bs.open_loops) st.open_loops.push_back({edges, width});
    tracker.check();
    t0 = Clock::now();
    // Back to the input's indices.
    const std::vector<Vec3> vertex_normals = surface_normals(P, tris, normals);
    result.mesh.normals.resize(n);
    detail::parallel_blocks(n, 8192, [&](size_t b, size_t e) {
      for (size_t s = b; s < e; ++s) result.mesh.normals[original[s]] = vertex_normals[s];
    });
    detail::parallel_blocks(tris.size(), 8192, [&](size_t b, size_t e) {
      for (size_t i = b; i < e; ++i)
        for (uint32_t& v : tris[i]) v = original[v];
    });
  });
  tracker.check();
  result.mesh.positions = cloud.positions;
  result.mesh.triangles = std::move(tris);
  result.mesh.attributes = cloud.attributes;
  tracker.finish();
  return result;
}

}  // namespace particlemesh
