#include "particlemesh/surface/reconstruct.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <limits>
#include <numbers>
#include <numeric>
#include <string>


#include "core/first_touch.h"
#include "core/parallel.h"
#include "core/progress_tracker.h"
#include "particlemesh/core/error.h"
#include "particlemesh/spatial/local_spacing.h"
#include "spatial/spacing_impl.h"
#include "surface/normals_impl.h"
#include "surface/raw_triangulation.h"
#include "surface/orient_outward.h"
#include "surface/surface_builder.h"
#include "surface/view_rays.h"

namespace PM_NAMESPACE {

namespace {

using Clock = std::chrono::steady_clock;
double seconds_since(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }

/// The distribution of the distinct particles' local spacings, in units of r0.
SurfaceStats::Spread spacing_spread(const detail::RawTriangulation& raw) {
  std::vector<double> h;
  h.reserve(raw.max_edge.size());
  for (size_t s = 0; s < raw.max_edge.size(); ++s)
    if (raw.rep[s] == s) h.push_back(raw.max_edge[s] / raw.stats.max_edge);
  SurfaceStats::Spread out;
  if (h.empty()) return out;
  // The sorted order's elements at the quantiles' ranks, by selection (a sort of a million
  // spacings took ~70 ms, on one core, at the end of the run).
  auto rank = [&](double f) { return h.begin() + ptrdiff_t(f * double(h.size() - 1) + 0.5); };
  const auto p10 = rank(0.1), median = rank(0.5), p90 = rank(0.9);
  std::nth_element(h.begin(), median, h.end());
  if (p10 < median) std::nth_element(h.begin(), p10, median);
  if (p90 > median) std::nth_element(median + 1, p90, h.end());
  out.min = *std::min_element(h.begin(), p10 + 1);
  out.p10 = *p10;
  out.median = *median;
  out.p90 = *p90;
  out.max = *std::max_element(p90, h.end());
  return out;
}

void check_surface_options(const SurfaceOptions& o) {
  if (!(o.normal_angle > 0 && o.normal_angle <= 180))
    throw Error(Status::InvalidArgument, "normal_angle must be in (0, 180] degrees, got " + std::to_string(o.normal_angle));
  if (!(o.fill_edge_factor > 0 && o.fill_edge_factor <= 10))
    throw Error(Status::InvalidArgument, "fill_edge_factor must be in (0, 10], got " + std::to_string(o.fill_edge_factor));
  if (o.fill_holes > 100000)
    throw Error(Status::InvalidArgument, "fill_holes must be at most 100000 edges, got " + std::to_string(o.fill_holes));
}

/// Whether a particle's normal has a direction: finite, and not zero or so short (below
/// float32's smallest normal number, 1.2e-38) that it is noise: a file's "0 0 0" or a
/// subnormal float is a particle without a normal.
bool usable_normal(const Vec3& n) {
  const double m = std::max({std::abs(n.x), std::abs(n.y), std::abs(n.z)});
  return std::isfinite(m) && m >= double(std::numeric_limits<float>::min());
}

/// The surface of `cloud` (the steps after the options' check), in the caller's arena;
/// `known`: the cloud's spacing estimate when already taken.
SurfaceResult reconstruct(const PointCloud& cloud, const SurfaceOptions& options, detail::ProgressTracker& tracker,
                          const SpacingEstimate* known) {
  SurfaceResult result;
  SurfaceStats& st = result.surface;
  std::vector<Triangle> tris;
  {
    detail::RawTriangulation raw = detail::run_raw_triangulation(cloud, options, tracker, 0.0, 0.55,
                                                                   detail::TriangleIndices::Sorted, options.local_spacing, known);
    result.triangulation = raw.stats;
    const NeighborGrid& grid = *raw.grid;
    const size_t n = cloud.size();
    if (options.local_spacing) st.local_spacing = spacing_spread(raw);

    auto t0 = Clock::now();
    using Source = SurfaceOptions::NormalSource;
    if (options.normals == Source::Input && !cloud.has_normals())
      throw Error(Status::InvalidArgument, "normals = input, but the cloud has no normals");
    // The finishing stages work on the points in the grid's cell order (sorted indices), as
    // the raw test does: points near in space are near in memory whatever order the input
    // lists them in (in input order, a shuffled cloud would be meshed much slower).
    // (Their pages, and those of the other large fresh arrays below, faulted in on all cores
    // rather than while resize() zeroes them on this one: first_touch.h.)
    std::vector<Vec3> P;
    std::vector<uint32_t> original;
    std::vector<uint8_t> active;
    detail::resize_touched(P, n);
    detail::resize_touched(original, n);
    detail::resize_touched(active, n);
    detail::parallel_blocks(n, 8192, [&](size_t b, size_t e) {
      for (size_t s = b; s < e; ++s) {
        P[s] = grid.sorted_point(uint32_t(s));
        original[s] = grid.original_index(uint32_t(s));
        active[s] = raw.rep[s] == s;
      }
    });
    std::vector<Vec3> normals;
    bool tree_chose = false;  // which way the normals face was the spanning tree's choice alone
    if (options.normals == Source::Input) {
      for (size_t i = 0; i < n; ++i)
        if (!usable_normal(cloud.normals[i]))
          throw Error(Status::InvalidInput,
                      "normals = input, but normals[" + std::to_string(i) +
                          "] has no direction (zero, or shorter than 1.2e-38): give every particle a normal, or let "
                          "normals = auto estimate the missing ones");
      normals.resize(n);
      detail::parallel_blocks(n, 8192, [&](size_t b, size_t e) {
        for (size_t s = b; s < e; ++s) normals[s] = normalized(cloud.normals[original[s]]);
      });
    } else {
      tracker.stage("estimating normals", 0.55, 0.65, n);
      normals = detail::pca_normals_sorted(grid, raw.rep, raw.neighbors, raw.max_edge, tracker, &raw.triangles);
      std::vector<Vec3> reference;
      if (options.normals == Source::Auto && cloud.has_normals()) {
        // A normal without a direction (zero, or subnormal) is a particle without a normal:
        // it does not vote, its neighbours decide. None with a direction: no reference at all.
        detail::resize_touched(reference, n);
        std::atomic<bool> usable{false};
        detail::parallel_blocks(n, 8192, [&](size_t b, size_t e) {
          bool any = false;
          for (size_t s = b; s < e; ++s) {
            const Vec3& r = cloud.normals[original[s]];
            reference[s] = usable_normal(r) ? r : Vec3{};
            any = any || usable_normal(r);
          }
          if (any) usable.store(true, std::memory_order_relaxed);
        });
        if (!usable.load()) reference.clear();
      }
      tracker.stage("orienting normals", 0.65, 0.7);
      // The cloud's normals orient directly when they are consistent; otherwise (or without
      // them) the spanning tree orients, and they only vote which way each piece faces.
      if (reference.empty() ||
          !detail::orient_normals_by_reference(grid, raw.rep, raw.neighbors, raw.max_edge, normals, reference, tracker))
        detail::orient_normals_mst(grid, raw.rep, raw.neighbors, raw.max_edge, normals, reference, tracker,
                                   noisy_sampling(raw.stats.sampling_thickness));
      st.normals_estimated = true;
      tree_chose = reference.empty();
    }
    st.seconds_normals = seconds_since(t0);
    raw.grid.reset();
    raw.neighbors = {};
    // The raw triangles (sorted indices), in their order, which breaks the builder's ties.
    std::vector<Triangle> candidates = std::move(raw.triangles);

    tracker.check();
    detail::BuilderOptions bo;
    if (options.has_viewpoint) {
      if (!is_finite(options.viewpoint)) throw Error(Status::InvalidArgument, "the viewpoint is not finite");
      st.viewpoint_used = detail::plausible_viewpoint(P, normals, active, options.viewpoint);
      bo.view.active = st.viewpoint_used;
      bo.view.origin = options.viewpoint;
    }
    bo.cos_normal_angle = std::cos(options.normal_angle * std::numbers::pi / 180.0);
    bo.max_edge = &raw.max_edge;
    bo.edge_cap = raw.edge_cap;
    bo.max_hole = options.fill_holes;
    bo.small_hole = std::min<size_t>(6, options.fill_holes);
    bo.fill_edge_factor = options.fill_edge_factor;
    bo.min_component_triangles = options.min_component_triangles;
    // Open parts closed but for small openings are turned as closed ones are, judged by their
    // loops, where nothing but the tree said which way they face (a scanner's viewpoint or
    // normals say which way rightly, inside a room too).
    bo.trace_loops = options.orient && tree_chose && !st.viewpoint_used;
    // The surface built over the normals N and its closed parts turned outward (and, where
    // the tree alone chose which way the normals face, its parts looked at for folds).
    struct Built {
      std::vector<Triangle> tris;
      detail::BuilderStats bs;
      std::vector<Vec3> vertex_normals;
      detail::FlatPieces flat;
      detail::NearlyClosed nearly;
      detail::Folds folds;
      double seconds_orient = 0;
    };
    auto build = [&](const std::vector<Vec3>& N, Built& b) {
      b.tris = detail::build_surface(P, N, active, candidates, bo, options.repair, b.bs, tracker, b.vertex_normals);
      tracker.check();  // the steps below take up to a second at 1M points: let a cancel request in
      const auto t = Clock::now();
      // Flat closed pieces (a patch and its reversed copy) opened, whichever way the rest faces.
      b.flat.sides = &N;
      b.nearly.loops = &b.bs.loops;
      b.bs.components_flipped = detail::orient_closed_components_outward(
          P, b.tris, b.bs.boundary, &b.vertex_normals, options.orient, &b.flat, &b.nearly,
          bo.trace_loops ? &b.folds : nullptr);
      b.seconds_orient = seconds_since(t);
      tracker.check();
    };
    Built first, second;
    build(normals, first);
    Built* kept = &first;
    if (!first.folds.inward.empty()) {
      // Folded parts: the normals turned to agree with the sides their faces were found to
      // face (summed over a particle's triangles, by area, those facing inward negated), and
      // the surface built again over them.
      std::vector<Vec3> vote(n, Vec3{});
      for (size_t i = 0; i < first.tris.size(); ++i) {
        const Triangle& t = first.tris[i];
        const Vec3 face = cross(P[t[1]] - P[t[0]], P[t[2]] - P[t[0]]);
        for (uint32_t v : t) vote[v] = vote[v] + (first.folds.inward[i] ? Vec3{} - face : face);
      }
      std::vector<Vec3> turned = normals;
      detail::parallel_blocks(n, 8192, [&](size_t b, size_t e) {
        for (size_t s = b; s < e; ++s)
          if (dot(normals[raw.rep[s]], vote[raw.rep[s]]) < 0) turned[s] = Vec3{} - normals[s];
      });
      second.folds.samples = 0;  // every triangle judged
      build(turned, second);
      // Kept where at most half as much of it faces inward and it is hardly more broken: at
      // most a few more pieces, loops left open or particles left out (2, or a tenth more).
      const auto few_more = [](size_t second, size_t first) { return second <= first + std::max<size_t>(2, first / 10); };
      if (second.flat.pieces == 0 && second.folds.judged_area > 0 &&
          second.folds.inward_area / second.folds.judged_area <=
              0.5 * first.folds.inward_area / first.folds.judged_area &&
          few_more(second.folds.pieces, first.folds.pieces) && few_more(second.bs.holes_left, first.bs.holes_left) &&
          few_more(second.bs.unused_points, first.bs.unused_points)) {
        kept = &second;
        st.folded_triangles = size_t(std::count(first.folds.inward.begin(), first.folds.inward.end(), uint8_t(1)));
        normals = std::move(turned);
      }
    }
    std::vector<Triangle>().swap(candidates);
    tris = std::move(kept->tris);
    detail::BuilderStats& bs = kept->bs;
    std::vector<Vec3>& vertex_normals = kept->vertex_normals;
    detail::FlatPieces& flat = kept->flat;
    detail::NearlyClosed& nearly = kept->nearly;
    st.seconds_extraction = first.bs.seconds_candidates + first.bs.seconds_growth + second.bs.seconds_candidates +
                            second.bs.seconds_growth;  // (a second build's zero when there was none)
    st.seconds_repair = first.bs.seconds_repair + second.bs.seconds_repair;
    st.flat_pieces_opened = flat.pieces;
    st.nearly_closed_turned = nearly.turned;
    st.seconds_orient = first.seconds_orient + second.seconds_orient;
    st.candidates = bs.candidates;
    st.rejected_conormal = bs.rejected_conormal;
    st.rejected_shadow = bs.rejected_shadow;
    st.grown = bs.grown;
    st.seeds = bs.seeds;
    st.pinches_resolved = bs.pinches_resolved;
    st.small_handles_removed = bs.small_handles_removed;
    st.holes_filled = bs.holes_filled;
    st.hole_triangles = bs.hole_triangles;
    // A flat piece's kept side is open: its outlines are loops left open too.
    st.holes_left = bs.holes_left + flat.loops.size();
    // Most raw triangles dropped for facing opposite ways (normals that no orientation makes
    // agree: particles all through a volume), or samples as thick as a thin layer of them.
    st.looks_like_volume = st.holes_left > 0 && (st.rejected_conormal * 20 > result.triangulation.kept * 7 ||
                                                 result.triangulation.sampling_thickness >= kThinLayerSamplingThickness);
    st.largest_hole_left = bs.largest_hole_left;
    for (size_t edges : flat.loops) {
      st.largest_hole_left = std::max(st.largest_hole_left, edges);
      bs.holes_left_edges.push_back(edges);
      if (bs.open_loops.size() < 1000) bs.open_loops.push_back({edges, INFINITY});  // width not measured
    }
    std::sort(bs.holes_left_edges.begin(), bs.holes_left_edges.end());
    st.components_flipped = bs.components_flipped;
    st.unused_points = bs.unused_points + flat.points;
    st.components_removed = bs.pieces.removed;
    st.component_triangles_removed = bs.pieces.removed_triangles;
    st.stray_pieces = bs.pieces.strays;
    for (const auto& [edges, width] : bs.open_loops) {
      st.open_loops.push_back({edges, width});
      if (options.repair && options.fill_holes > 0 && std::isfinite(width) && width <= kNarrowLoopWidth &&
          (width > options.fill_edge_factor || edges > options.fill_holes)) {
        ++st.narrow_loops.count;
        st.narrow_loops.width = std::max(st.narrow_loops.width, width);
        st.narrow_loops.edges = std::max(st.narrow_loops.edges, edges);
      }
    }
    st.holes_left_edges = std::move(bs.holes_left_edges);
    tracker.check();
    // Back to the input's indices.
    detail::resize_touched(result.mesh.normals, n);
    detail::parallel_blocks(n, 8192, [&](size_t b, size_t e) {
      for (size_t s = b; s < e; ++s) result.mesh.normals[original[s]] = vertex_normals[s];
    });
    detail::parallel_blocks(tris.size(), 8192, [&](size_t b, size_t e) {
      for (size_t i = b; i < e; ++i)
        for (uint32_t& v : tris[i]) v = original[v];
    });
  }
  tracker.check();
  // The cloud's positions copied in parallel into pages faulted in on all cores.
  detail::resize_touched(result.mesh.positions, cloud.positions.size());
  detail::parallel_blocks(cloud.positions.size(), 65536, [&](size_t b, size_t e) {
    std::copy(cloud.positions.begin() + ptrdiff_t(b), cloud.positions.begin() + ptrdiff_t(e),
              result.mesh.positions.begin() + ptrdiff_t(b));
  });
  result.mesh.triangles = std::move(tris);
  result.mesh.attributes = cloud.attributes;
  return result;
}

}  // namespace

SurfaceResult reconstruct_surface(const PointCloud& cloud, const SurfaceOptions& options) {
  check_surface_options(options);
  detail::ProgressTracker tracker(options.progress);
  SurfaceResult result = detail::with_threads(options.threads, [&] {
    if (!options.local_spacing) return reconstruct(cloud, options, tracker, nullptr);
    // The spacing estimate first (with a spacing given too: the local spacings are measured
    // against it), to see whether the cloud is twinned: many of its points have a near copy
    // (detail::kTwinRatio), so its median nearest-neighbour distance is the copies' offset
    // and every point's neighbourhood ends at its copy (nothing would be meshed). Then the
    // copies are set aside as exact duplicates are, and the cloud of the rest is meshed.
    validate_point_cloud(cloud);
    if (cloud.size() < 3) return reconstruct(cloud, options, tracker, nullptr);  // its error
    const size_t n = cloud.size();
    std::vector<uint32_t> twin_of;
    SpacingEstimate est = detail::estimate_spacing_impl(cloud.positions.data(), n, tracker, 0.0, 0.15, 1, &twin_of);
    if (twin_of.empty()) return reconstruct(cloud, options, tracker, &est);
    // kept: the input index of each particle meshed; at: per input index, the place in `kept`
    // of the particle that stands for it. Copies of copies (a second offset, ten times the
    // first) are merged round by round, as long as the rest is twinned.
    std::vector<uint32_t> kept(n), at(n);
    std::iota(kept.begin(), kept.end(), 0u);
    std::iota(at.begin(), at.end(), 0u);
    size_t exact = 0;
    PointCloud reduced;
    for (int round = 0; round < 8 && !twin_of.empty(); ++round) {
      exact += est.duplicate_points;
      // twin_of[k] (a place in this round's cloud) is the lowest of k's group, which stands
      // for it; `moved`: each standing particle's place in the next round's cloud.
      std::vector<uint32_t> next_kept, moved(twin_of.size());
      for (size_t k = 0; k < twin_of.size(); ++k)
        if (twin_of[k] == k) {
          moved[k] = uint32_t(next_kept.size());
          next_kept.push_back(kept[k]);
        }
      for (uint32_t& k : at) k = moved[twin_of[k]];
      kept = std::move(next_kept);
      reduced = select_points(cloud, kept);
      if (reduced.size() < 3) break;
      est = detail::estimate_spacing_impl(reduced.positions.data(), reduced.size(), tracker, 0.0, 0.15, 1, &twin_of);
    }
    SurfaceResult r = reconstruct(reduced, options, tracker, reduced.size() < 3 ? nullptr : &est);
    for (Triangle& t : r.mesh.triangles)
      for (uint32_t& v : t) v = kept[v];
    std::vector<Vec3> normals(n);
    for (uint32_t i = 0; i < n; ++i) normals[i] = r.mesh.normals[at[i]];
    r.mesh.normals = std::move(normals);
    r.mesh.positions = cloud.positions;
    r.mesh.attributes = cloud.attributes;
    // The exact copies merged count as the exact duplicates they are (those the estimates
    // found: every one but among stray points they left out, which the last run counts).
    r.triangulation.points = n;
    r.triangulation.duplicate_points += exact;
    r.triangulation.near_duplicates = n - kept.size() - exact;
    return r;
  });
  tracker.finish();
  return result;
}

}  // namespace particlemesh
