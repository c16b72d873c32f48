// particlemesh triangulate IN -o OUT: surface particles to a mesh.
#include <algorithm>
#include <cfloat>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "commands.h"
#include "attribute_selection.h"
#include "frame_sequence.h"
#include "particle_input.h"
#include "sampling_shape.h"
#include "particlemesh/core/error.h"
#include "particlemesh/io/mesh_io.h"
#include "particlemesh/mesh/topology_report.h"
#include "particlemesh/sample/thin.h"
#include "particlemesh/spatial/local_spacing.h"
#include "particlemesh/spatial/spacing.h"
#include "particlemesh/surface/reconstruct.h"
#include "particlemesh/surface/triangulate.h"
#include "progress_line.h"
#include "report_json.h"
#include "run_outputs.h"
#include "smooth_chain.h"

namespace particlemesh::cli {

namespace {

struct TriangulateArgs {
  std::string input, output, report;
  double spacing = 0;
  double max_edge_factor = 2.0;
  double thin = 1.0;
  bool raw = false;
  bool global_spacing = false;
  bool no_viewpoint = false;
  bool no_orient = false;
  bool no_repair = false;
  std::string normals = "auto";
  size_t fill_holes = 100;
  double fill_edge_factor = 1.5;
  size_t min_component_triangles = 0;
  double normal_angle = 120.0;
  bool ascii = false;
  bool quiet = false;
  int threads = 0;
  size_t max_neighbors = 256;
  size_t max_triplets_per_point = TriangulateOptions{}.max_triplets_per_point;
  ParticleInputArgs input_options;  // .pcd, PCL preprocessing, --pcl-mesh
  SmoothChainArgs smooth;  // --smooth loop|butterfly --levels K
  std::string attributes = "all";
  SequenceArgs sequence;
};

/// When over 5 % of the particles are in no triangle of the surface, their spacing varies more
/// than the edge limits follow: with one limit for the whole cloud (--global-spacing), any
/// unevenness does; with each particle's own, sparser than 3 r0 or clusters too small for a
/// surface. Say what helps. Empty otherwise.
std::string uneven_spacing_hint(const SurfaceResult& r, double thin, bool global_spacing) {
  const size_t points = r.triangulation.points, unused = r.surface.unused_points;
  if (points == 0 || unused * 20 <= points) return {};
  char s[400];
  std::snprintf(s, sizeof s,
                "%.0f%% of the particles are in no triangle: they are unevenly spaced for %s; %stry --thin %g "
                "(an even subset) or a larger --max-edge-factor",
                100.0 * double(unused) / double(points), global_spacing ? "one L" : "their local L",
                global_spacing ? "leave out --global-spacing (each particle's own L), or " : "",
                thin > 1 ? thin + 1 : 2.0);
  return s;
}

/// The loops left open by their edges: the small ones (holes of a few edges) one by one, the
/// larger ones in ranges.
nlohmann::json holes_by_size(const std::vector<size_t>& edges) {
  const std::pair<size_t, const char*> bins[] = {{3, "3"},      {4, "4"},       {5, "5"},        {6, "6"},
                                                 {9, "7-9"},    {19, "10-19"},  {99, "20-99"},   {SIZE_MAX, "100+"}};
  nlohmann::json out = nlohmann::json::object();
  for (const auto& [top, name] : bins) out[name] = 0;
  for (size_t e : edges)
    for (const auto& [top, name] : bins)
      if (e <= top) {
        out[name] = out[name].get<size_t>() + 1;
        break;
      }
  return out;
}

/// When the particles look like a volume's (SurfaceStats::looks_like_volume: co-normality
/// dropped most raw triangles and loops stayed open), say which command meshes those. Empty
/// otherwise.
std::string volume_particles_hint(const SurfaceResult& r) {
  if (!r.surface.looks_like_volume) return {};
  const size_t kept = r.triangulation.kept, dropped = r.surface.rejected_conormal;
  char s[320];
  std::snprintf(s, sizeof s,
                "%.0f%% of the smallest-sphere test's triangles were dropped for joining particles that face opposite ways: if "
                "these particles fill a volume (e.g. a fluid simulation's), `particlemesh polygonize` meshes its "
                "surface",
                100.0 * double(dropped) / double(kept));
  return s;
}

/// When loops are left open and the particles scatter across their surface (a scan's noise,
/// TriangulateStats::sampling_thickness: noisy_sampling),
/// say that smoothing them first may hold the surface together (--mls, with the PCL
/// preprocessing). Empty otherwise.
std::string noisy_surface_hint(const SurfaceResult& r, const TriangulateArgs& a) {
  const double t = r.triangulation.sampling_thickness;
  if (!has_pcl_preprocessing() || r.surface.holes_left == 0 || !noisy_sampling(t))
    return {};
  // Smoothing over about 3 local spacings held the noisy spheres and scans measured together.
  const double radius = 3.0 * r.surface.local_spacing.median * r.triangulation.spacing;
  const double given = a.input_options.mls_radius;
  char advice[160];
  if (given > 0)
    std::snprintf(advice, sizeof advice, "a larger --mls radius than %.3g may hold it together", given);
  else
    std::snprintf(advice, sizeof advice, "smoothing them first, --mls %.3g (3 x their spacing), may hold it together",
                  radius);
  char s[480];
  std::snprintf(s, sizeof s,
                "the particles scatter across their surface (thickness %.2f: their neighbours spread off the plane "
                "fitted to them by %.0f%% of their spread along it; clean surfaces measure under 0.2): if they sample "
                "a noisy surface (a scan), %s",
                t, 100 * t, advice);
  return s;
}

/// When a --spacing was given and over 5 % of the particles are in no triangle: is it well
/// below their median nearest-neighbour distance (edges too short to reach their neighbours)?
/// Then that is the cause to name. Empty otherwise.
std::string given_spacing_hint(const SurfaceResult& r, const PointCloud& cloud, double given, int threads) {
  const size_t points = r.triangulation.points, unused = r.surface.unused_points;
  if (!(given > 0) || points == 0 || unused * 20 <= points || cloud.size() < 2) return {};
  double measured = 0;
  try {
    measured = estimate_spacing_sampled(cloud.positions.data(), cloud.size(), 200000, threads).spacing;
  } catch (const Error&) {
    return {};
  }
  if (!(given < 0.75 * measured)) return {};
  char s[320];
  std::snprintf(s, sizeof s,
                "the given --spacing %g is %.0f%% of the particles' median nearest-neighbour distance %.4g: edges of "
                "%g x it do not reach their neighbours; leave --spacing out (estimated) or raise it",
                given, 100.0 * given / measured, measured, r.triangulation.max_edge / given);
  return s;
}

/// When loops are left open that the fill did not try and a patch of edges at most
/// kNarrowLoopWidth x L spans (SurfaceStats::narrow_loops), say which settings reach them.
/// Empty otherwise.
std::string narrow_loops_hint(const SurfaceResult& r, const TriangulateArgs& a) {
  const SurfaceStats::NarrowLoops& n = r.surface.narrow_loops;
  if (n.count == 0) return {};
  const double factor = std::max(a.fill_edge_factor, std::ceil(n.width * 10.0 + 1e-9) / 10.0);
  char which[80];
  if (r.surface.holes_left == 1)
    std::snprintf(which, sizeof which, "the loop left open is narrow (a patch across it");
  else if (n.count == r.surface.holes_left)
    std::snprintf(which, sizeof which, "all %zu loops left open are narrow (a patch across each", n.count);
  else
    std::snprintf(which, sizeof which, "%zu of the %zu loops left open are narrow (a patch across each", n.count,
                  r.surface.holes_left);
  char s[400];
  std::snprintf(s, sizeof s,
                "%s needs edges of at most %.2f x L): gaps in the sampling, or small openings; try "
                "--fill-edge-factor %g%s (wider loops stay open)",
                which, n.width, factor, n.edges > a.fill_holes ? (" --fill-holes " + std::to_string(n.edges)).c_str() : "");
  return s;
}

/// When --max-edge-factor was given below the default and loops are left open: edges that
/// short reach a particle's nearest neighbours but not the next ones, which the smallest
/// sphere test needs wherever the particles are not on a grid. Empty otherwise.
std::string short_edges_hint(const SurfaceResult& r, const TriangulateArgs& a) {
  const double standard = TriangulateOptions{}.max_edge_factor;
  if (!(a.max_edge_factor < standard) || r.surface.holes_left == 0) return {};
  char s[300];
  std::snprintf(s, sizeof s,
                "--max-edge-factor %g is below the default %g: edges of %g x r0 leave %zu loops open where the particles "
                "are not on a grid; raise it (or leave it out)",
                a.max_edge_factor, standard, a.max_edge_factor, r.surface.holes_left);
  return s;
}

/// When loops are left open and at least a tenth of the particles' edge limits stop at the
/// local spacing's cap (3 r0, kMaxLocalSpacing), past which their spacing lies
/// (TriangulateStats::uncapped_spacing_p90). Either the sampling is far sparser across than
/// along (a scanner's rows, a mesh's rings of vertices along its curves: the spacing there is
/// several times the nearest neighbours' distance, TriangulateStats::capped_spacing_over_nn 2
/// and more), and the surface needs the spacing across to join the rows; or parts of the
/// cloud are sampled sparser all round (a scan merged with a much finer one, a model's coarse
/// body beside fine details). Names the --max-edge-factor whose edges reach them; where that is
/// several times the one given and the parts are sparse all round, the ways that do not
/// lengthen the dense particles' limits: meshing the parts apart, or thinning the denser parts
/// to about half the sparse parts' spacing first. Empty otherwise.
std::string capped_spacing_hint(const SurfaceResult& r, const TriangulateArgs& a) {
  constexpr double kCap = 3.0;  // the library's kMaxLocalSpacing, in r0
  const SurfaceStats::Spread& h = r.surface.local_spacing;
  if (a.global_spacing || r.surface.holes_left == 0 || !(h.p90 >= 0.999 * kCap * r.triangulation.reach_factor))
    return {};
  const double across = r.triangulation.uncapped_spacing_p90;
  if (!(across > 1.05 * kCap)) return {};
  // The factor whose capped limits reach as far as the one given (at most the default) would
  // over the uncapped spacing, a little farther; none when the one given already does (a
  // factor named here and taken, whose surface still has loops open: an open sheet's rim).
  const double base = std::min(a.max_edge_factor, TriangulateOptions{}.max_edge_factor);
  const double factor = std::ceil(base * across / kCap * 1.05 * 10.0) / 10.0;
  if (a.max_edge_factor >= factor) return {};
  // The factor lengthens every particle's limit, the dense ones' too, where the smallest-sphere
  // test then meets many more triplets: a lidar sweep's 115k points took 32 s at 20.6 x, 1.1 s
  // at the default (bench/RESULTS.md). Said when the factor is several times the one given.
  const bool slow = factor > 3.0 * a.max_edge_factor;
  const char* longer = " (it lengthens the dense particles' limits too: expect the run to take many times longer)";
  char s[800];
  if (r.triangulation.capped_spacing_over_nn >= 2.0) {
    std::snprintf(s, sizeof s,
                  "the particles lie far closer along lines than across them (a scanner's rows, a mesh's rings of "
                  "vertices): 10%% of them are %.1f x r0 or more from the next line, past the %g r0 their edge "
                  "limits stop at; --max-edge-factor %g may let the edges cross%s",
                  across, kCap, factor, slow ? longer : "");
  } else if (!slow) {
    std::snprintf(s, sizeof s,
                  "parts of the cloud are sampled sparser all round than its median spacing r0: 10%% of the "
                  "particles are %.1f x r0 or more from their neighbours, past the %g r0 their edge limits stop "
                  "at; --max-edge-factor %g may reach them",
                  across, kCap, factor);
  } else {
    // Thinned to half the sparse parts' spacing, the denser parts no longer set r0.
    const double thin = std::floor(across * 0.5 * 10.0) / 10.0;
    std::snprintf(s, sizeof s,
                  "parts of the cloud are sampled far sparser all round than its median spacing r0 (a scan merged "
                  "with a much finer one?): 10%% of the particles are %.1f x r0 or more from their neighbours, past "
                  "the %g r0 their edge limits stop at, and stay out of the mesh; mesh the parts apart (--crop), or "
                  "all of it at the sparser spacing with --thin %g --global-spacing (the denser parts thinned to "
                  "it); --max-edge-factor %g would reach them too%s",
                  across, kCap, thin, factor, longer);
  }
  return s;
}

/// When at least 5 pieces of fewer than 10 triangles lie apart from the rest and hold under
/// 5 % of the triangles (the library's stray_pieces: a scan's stray triangles among its rows),
/// the --min-component-triangles that removes just them. Empty otherwise, or when pieces are
/// removed already.
std::string stray_pieces_hint(const SurfaceResult& r, const TriangulateArgs& a) {
  const auto& [pieces, triangles, largest] = r.surface.stray_pieces;
  if (a.min_component_triangles > 0 || pieces < 5 || triangles * 20 > r.mesh.triangles.size()) return {};
  char text[200];
  if (largest == 1)
    std::snprintf(text, sizeof text, "%zu lone triangles lie apart from the rest: --min-component-triangles 2 removes them",
                  pieces);
  else
    std::snprintf(text, sizeof text,
                  "%zu pieces of at most %zu triangles lie apart from the rest (%zu triangles): "
                  "--min-component-triangles %zu removes them",
                  pieces, largest, triangles, largest + 1);
  return text;
}

/// Every hint that applies, most important first.
std::vector<std::string> surface_hints(const SurfaceResult& r, const TriangulateArgs& a, const PointCloud& cloud) {
  std::vector<std::string> out;
  std::string given = given_spacing_hint(r, cloud, a.thin > 1 ? 0.0 : a.spacing, a.threads);  // (thinning: its own)
  const bool spacing_named = !given.empty();
  const std::string short_edges = short_edges_hint(r, a);
  // (Where the capped spacing says why particles stay out, and what reaches them, the general
  // advice for unused particles is left out.)
  std::string capped = spacing_named ? std::string() : capped_spacing_hint(r, a);
  const bool explained = !capped.empty();
  for (std::string h : {volume_particles_hint(r), noisy_surface_hint(r, a), std::move(given), std::move(capped),
                        spacing_named || explained ? std::string() : uneven_spacing_hint(r, a.thin, a.global_spacing),
                        short_edges,
                        short_edges.empty() ? narrow_loops_hint(r, a) : std::string(), stray_pieces_hint(r, a)})
    if (!h.empty()) out.push_back(std::move(h));
  return out;
}

/// The largest --max-neighbors.
constexpr size_t kMaxNeighborsOption = 100000;

/// Runs `work`; a limit the library names gets the switch that lifts it: a grid too large for
/// the points' extent (far outliers) --crop, and --remove-outliers where this build has it; more
/// neighbours within a point's radius than the limit (a cloud thicker than a surface, e.g.
/// noise across it) --max-neighbors with the count the library gives, when the spacing was
/// measured (`measured_spacing`): above a --spacing the caller gave, the spacing is what is
/// wrong, and the triplet limit would stop the next run.
template <class Work>
auto with_limit_advice(Work&& work, bool measured_spacing = false) {
  try {
    return work();
  } catch (const Error& e) {
    if (const std::string advised = with_far_outlier_advice(e, true); !advised.empty())
      throw Error(e.status(), advised);
    const std::string what = e.what();
    if (e.status() != Status::LimitExceeded) throw;
    const std::string key = "raise the neighbour limit to at least ";
    const size_t at = what.find(key);
    if (at != std::string::npos && measured_spacing) {
      const size_t from = at + key.size(), to = what.find_first_not_of("0123456789", from);
      const std::string most = what.substr(from, to - from);
      if (!most.empty() && most.size() <= 6 && std::stoul(most) <= kMaxNeighborsOption)
        throw Error(e.status(), what + " (--max-neighbors " + most + ")");
    }
    throw;
  }
}

std::vector<OutputSpec> output_specs(const TriangulateArgs& a) {
  return {{"-o", a.output, OutputKind::Mesh, a.ascii ? MeshFormat::PlyAscii : MeshFormat::Auto},
          {"--report", a.report, OutputKind::Text},
          {"--pcl-mesh", a.input_options.pcl_mesh, OutputKind::PlyOnly}};
}

/// Mesh one file; `frame` is null for a single file, the sequence's context for a frame.
int run_triangulate(const TriangulateArgs& a, FrameContext* frame = nullptr) {
  using Clock = std::chrono::steady_clock;
  RunOutputs outputs(with_frame_outputs(output_specs(a), frame), {a.input});
  const auto t0 = Clock::now();
  ProgressLine progress(a.quiet);
  ParticleInput input = read_particles(a.input, a.input_options, a.threads);
  settle_attributes(input.cloud, a.attributes, frame);
  const double t_read = std::chrono::duration<double>(Clock::now() - t0).count();

  // --thin: an even subset, no particle within thin x r0 of a kept one (r0 given or
  // estimated), or within thin x its local spacing (scaled to r0) unless --global-spacing:
  // an uneven cloud stays as uneven as it was, only coarser. Its spacing is estimated afresh:
  // the subset's gaps run from d to 2d.
  PointCloud thinned;
  double thin_distance = 0;
  if (a.thin > 1) {
    throw_if_interrupted();
    const Vec3* pts = input.cloud.positions.data();
    const size_t n = input.cloud.size();
    const double given = a.spacing > 0 ? a.spacing : input.spacing_hint;
    if (a.global_spacing) {
      thin_distance = a.thin * (given > 0 ? given : estimate_spacing(pts, n, a.threads).spacing);
      thinned = with_limit_advice([&] { return thin_cloud(input.cloud, thin_distance); });
    } else {
      LocalSpacing ls = with_limit_advice([&] { return estimate_local_spacing(pts, n, a.threads); });
      const double scale = a.thin * (given > 0 ? given / ls.median_nn : 1.0);
      for (double& h : ls.spacing) h *= scale;
      thin_distance = a.thin * (given > 0 ? given : ls.median_nn);
      thinned = with_limit_advice([&] { return thin_cloud(input.cloud, ls.spacing); });
    }
  }
  const PointCloud& cloud = a.thin > 1 ? thinned : input.cloud;

  SurfaceOptions opt;
  opt.spacing = a.thin > 1 ? 0.0 : a.spacing > 0 ? a.spacing : input.spacing_hint;
  opt.max_edge_factor = a.max_edge_factor;
  opt.threads = a.threads;
  opt.max_neighbors = a.max_neighbors;
  opt.max_triplets_per_point = a.max_triplets_per_point;
  opt.normal_angle = a.normal_angle;
  opt.normals = a.normals == "input" ? SurfaceOptions::NormalSource::Input
                : a.normals == "estimate" ? SurfaceOptions::NormalSource::Estimate
                                          : SurfaceOptions::NormalSource::Auto;
  opt.repair = !a.no_repair;
  opt.fill_holes = a.fill_holes;
  opt.fill_edge_factor = a.fill_edge_factor;
  opt.min_component_triangles = a.min_component_triangles;
  opt.orient = !a.no_orient;
  opt.local_spacing = !a.global_spacing;
  opt.has_viewpoint = input.has_viewpoint && !a.no_viewpoint;
  opt.viewpoint = input.viewpoint;
  opt.progress = progress.callback();
  const auto t1 = Clock::now();
  set_phase(Phase::Computing);
  throw_if_interrupted();
  SurfaceResult result;
  std::vector<std::string> hints;  // what the summary and the report say might help
  if (a.raw) {
    TriangulateResult r = with_limit_advice([&] { return triangulate_raw(cloud, opt); }, opt.spacing == 0);
    result.mesh = std::move(r.mesh);
    result.triangulation = r.stats;
  } else {
    result = with_limit_advice([&] { return reconstruct_surface(cloud, opt); }, opt.spacing == 0);
    hints = surface_hints(result, a, cloud);
  }
  const double t_tri = std::chrono::duration<double>(Clock::now() - t1).count();
  progress.clear();
  throw_if_interrupted();

  apply_smooth_chain(result.mesh, a.smooth, a.threads, progress);  // --smooth: after the mesh is made

  const WrittenMesh written = write_with_report(result.mesh, !a.quiet || !a.report.empty(), [&] {
    outputs.write_mesh("-o", result.mesh);
    if (outputs.has("--pcl-mesh")) write_pcl_mesh(result.mesh, outputs.open("--pcl-mesh"));
  });

  if (!a.report.empty()) {
    nlohmann::json j{{"input", a.input},
                     {"output", a.output},
                     {"mode", a.raw ? "raw" : "surface"},
                     {"triangulation", to_json(result.triangulation)},
                     {"surface", a.raw ? nlohmann::json(nullptr) : to_json(result.surface)},
                     {"spacing", a.raw || a.global_spacing ? "global" : "local"},
                     {"topology", to_json(written.report)},
                     {"seconds", {{"read", t_read}, {"triangulate", t_tri}, {"write", written.seconds}}}};
    if (!input.report.is_null()) j["input_cloud"] = input.report;
    if (const auto nw = outputs.channels_not_written("-o", result.mesh); !nw.empty()) j["not_written"] = nw;
    if (const auto nw = outputs.channels_not_written("--pcl-mesh", result.mesh); !nw.empty())
      j["pcl_mesh_not_written"] = nw;
    if (a.thin > 1)
      j["thin"] = {{"factor", a.thin}, {"local", !a.global_spacing}, {"distance", thin_distance}, {"kept", cloud.size()}, {"of", input.cloud.size()}};
    if (!a.raw) {
      j["surface"]["holes_left_by_size"] = holes_by_size(result.surface.holes_left_edges);
      std::string joined;  // one string, as the report has always had
      for (const std::string& h : hints)
        joined += (joined.empty() ? "" : " / ") + h;
      if (!joined.empty()) j["hint"] = joined;
    }
    outputs.open("--report").write(json_text(j));
  }
  commit_outputs(outputs, frame);
  if (!a.quiet && !frame) {
    const auto& s = result.triangulation;
    std::printf("particlemesh triangulate: %s -> %s\n", a.input.c_str(), a.output.c_str());
    std::printf("%s", input.summary.c_str());
    std::printf("%s", not_written_lines(outputs, result.mesh).c_str());
    if (a.thin > 1)
      std::printf("  thinned       %zu of %zu particles kept, none closer than %g x %s\n", cloud.size(),
                  input.cloud.size(), a.thin, a.global_spacing ? ("r0 = " + std::to_string(thin_distance)).c_str() : "its local spacing");
    std::string aside;
    if (s.duplicate_points) aside = std::to_string(s.duplicate_points) + " exact duplicates";
    if (s.near_duplicates)
      aside += (aside.empty() ? "" : ", ") + std::to_string(s.near_duplicates) +
               " near copies (a neighbour ten times nearer than every other)";
    std::printf("  points        %zu%s\n", s.points, aside.empty() ? "" : (" (" + aside + " set aside)").c_str());
    std::printf("  spacing r0    %.6g (%s)\n", s.spacing, s.spacing_estimated ? "estimated: median nearest-neighbour distance" : "given");
    std::printf("  max edge L    %.6g (%g x r0)\n", s.max_edge, a.max_edge_factor);
    if (!a.raw && !a.global_spacing) {
      const auto& h = result.surface.local_spacing;
      std::printf("  local spacing %.2g-%.2g r0 (10%%-90%%: %.2g-%.2g, median %.2g): each particle's L = %g x its own\n",
                  h.min, h.max, h.p10, h.p90, h.median, a.max_edge_factor);
      if (s.shortened_limits)
        std::printf("  crowded       %zu particles' L shortened so that each reaches at most %zu others (--max-neighbors)\n",
                    s.shortened_limits, a.max_neighbors);
      if (s.reach_factor > 1)
        std::printf("  sampling      irregular (nearest-neighbour distances vary by %.0f %%, as where particles lie at "
                    "random): the local spacings above are %.2g x the sampling's, so that triangles reach across its gaps\n",
                    100 * s.sampling_irregularity, s.reach_factor);
    }
    std::printf("  raw test      %zu candidate triplets, %zu kept%s\n", s.candidates, s.kept,
                s.ties ? (", " + std::to_string(s.ties) + " ties broken").c_str() : "");
    if (!a.raw) {
      const auto& f = result.surface;
      // Input normals that are all zero (no direction) are no normals: the tree orients.
      bool directions = false;
      for (const Vec3& n : cloud.normals)
        directions = directions || std::max({std::abs(n.x), std::abs(n.y), std::abs(n.z)}) >= double(FLT_MIN);
      // (A noisy sampling's tree joins sheets only where nothing within one does: normals_impl.h.)
      const bool noisy = noisy_sampling(result.triangulation.sampling_thickness);
      std::printf("  normals       %s\n", !f.normals_estimated                  ? "the input's"
                                         : directions && a.normals == "auto" ? "plane fits, facing as the input's normals"
                                         : noisy ? "plane fits, oriented by a spanning tree (a noisy sampling: within each sheet first)"
                                                 : "plane fits, oriented by a spanning tree");
      std::printf("  surface       %zu co-normal candidates (%zu dropped), %zu grown from %zu seeds\n", f.candidates,
                  f.rejected_conormal, f.grown, f.seeds);
      const size_t small = size_t(std::count_if(f.holes_left_edges.begin(), f.holes_left_edges.end(),
                                                 [](size_t e) { return e < 10; }));
      std::string handles = f.small_handles_removed == 0 ? std::string()
                            : std::to_string(f.small_handles_removed) + " small handle" +
                                  (f.small_handles_removed == 1 ? "" : "s") + " removed, ";
      if (f.flat_pieces_opened)
        handles += std::to_string(f.flat_pieces_opened) + " flat closed piece" + (f.flat_pieces_opened == 1 ? "" : "s") +
                   " opened, ";
      if (f.nearly_closed_turned)
        handles += std::to_string(f.nearly_closed_turned) + " part" + (f.nearly_closed_turned == 1 ? "" : "s") +
                   " closed but for small openings turned outward, ";
      if (f.folded_triangles)
        handles += std::to_string(f.folded_triangles) + " triangles facing into the solid (a fold) built again, ";
      std::printf("  repair        %zu holes filled (%zu triangles), %zu pinches resolved, %s%zu loops left open%s\n",
                  f.holes_filled, f.hole_triangles, f.pinches_resolved, handles.c_str(), f.holes_left,
                  f.holes_left ? (" (largest " + std::to_string(f.largest_hole_left) + " edges, " +
                                  std::to_string(small) + " under 10)").c_str()
                               : "");
      if (opt.has_viewpoint)
        std::printf("  viewpoint     %.6g %.6g %.6g: %s\n", opt.viewpoint.x, opt.viewpoint.y, opt.viewpoint.z,
                    f.viewpoint_used ? (std::to_string(f.rejected_shadow) + " triangles across depth jumps dropped").c_str()
                                     : "not taken (the particles do not look scanned from there)");
      if (f.components_removed)
        std::printf("  removed       %zu piece%s of fewer than %zu triangles (%zu triangles)\n", f.components_removed,
                    f.components_removed == 1 ? "" : "s", a.min_component_triangles, f.component_triangles_removed);
      if (f.unused_points) std::printf("  unused        %zu particles in no triangle\n", f.unused_points);
      for (const std::string& h : hints)
        std::printf("  hint          %s\n", h.c_str());
    }
    print_mesh_and_times(written.report, "triangulate", t_read, t_tri, written.seconds);
  }
  return 0;
}

}  // namespace

void add_triangulate(CLI::App& root, std::vector<Command>& commands) {
  auto args = std::make_shared<TriangulateArgs>();
  CLI::App* app = root.add_subcommand("triangulate", "Surface particles to a triangle mesh (Tonnesen's smallest-sphere test, made into a finished surface)");
  app->add_option("input", args->input,
                  "Particles: " + kParticleFormats +
                      "; a path with a frame field ({} or {:04d}, e.g. scan_{:04d}.ply) is a sequence: every frame is "
                      "meshed; so is a ParaView collection (.pvd, .series), frame n its n-th file by time")
      ->required();
  app->add_option("-o,--output", args->output,
                  "Output mesh: .ply (binary; --ascii for text), .obj, .vtk, .vtu or .vtp; - (or a device, a FIFO) "
                  "for PLY on standard output. With a sequence input, a pattern too (out/mesh_{:04d}.ply)")
      ->required();
  app->add_option("--spacing", args->spacing,
                  "Particle spacing r0 in world units (default: estimated as the median nearest-neighbour distance); "
                  "the local spacings are scaled to it, unless --global-spacing")
      ->check(positive_number())
      ->check(finite_number());
  app->add_option("--max-edge-factor", args->max_edge_factor,
                  "Longest triangle edge L = factor x r0 (x each particle's local spacing unless --global-spacing; "
                  "where the particles lie at random, up to 1.75 x longer)")
      ->check(in_range(1e-6, 100.0))
      ->check(finite_number())
      ->capture_default_str();
  app->add_option("--thin", args->thin,
                  "Mesh a subset of the particles, none within FACTOR x its local spacing of a kept one (FACTOR x "
                  "r0 with --global-spacing; r0 from --spacing or estimated; the subset's own spacing is then "
                  "estimated): a coarse preview, and evener input from unevenly sampled clouds. 1 = every particle")
      ->check(in_range(1.0, 1000.0))
      ->check(finite_number())
      ->capture_default_str();
  app->add_flag("--raw", args->raw,
                "Return the smallest-sphere test's exact triangle set (not a surface: overlapping pairs on quads), with one L for the "
                "whole cloud");
  app->add_flag("--global-spacing", args->global_spacing,
                "One longest edge L = factor x r0 for the whole cloud, instead of each particle's own from the "
                "sampling around it (local spacing: within 15% of r0 it is r0, at most 3 r0; up to 1.75 x that where "
                "the particles lie at random)");
  app->add_flag("--no-viewpoint", args->no_viewpoint,
                "Ignore a .pcd's VIEWPOINT (and --viewpoint): without it, triangles along the sensor's rays (across "
                "depth jumps) are not told apart");
  app->add_option("--normal-angle", args->normal_angle,
                  "Co-normality: drop triangles whose corner normals differ by more than this, or whose face normal differs from a corner's by more than min(this, 90) (degrees)")
      ->check(in_range(1.0, 180.0))
      ->check(finite_number())
      ->capture_default_str();
  app->add_option("--normals", args->normals,
                  "auto: plane-fit directions, facing as the input's normals say (if any); "
                  "input: the input's normals as they are; estimate: ignore the input's normals")
      ->check(CLI::IsMember({"auto", "input", "estimate"}))
      ->capture_default_str();
  app->add_flag("--no-repair", args->no_repair, "Skip the repair stage (hole filling, unpinching)");
  app->add_option("--fill-holes", args->fill_holes, "Fill boundary loops of up to N edges (0 = none)")
      ->check(in_range(size_t(0), size_t(100000)))
      ->capture_default_str();
  app->add_option("--fill-edge-factor", args->fill_edge_factor,
                  "Fill triangles' edges at most this x L: wider openings are real and stay open (above 1.5, "
                  "only the loops left after every other repair step are filled that wide)")
      ->check(in_range(0.1, 10.0))
      ->check(finite_number())
      ->capture_default_str();
  app->add_option("--min-component-triangles", args->min_component_triangles,
                  "Remove every piece of the surface of fewer than N triangles (the stray triangles a scan leaves "
                  "among its rows or at its fringe); their particles are then in no triangle. 0 = keep every piece")
      ->check(in_range(size_t(0), size_t(UINT32_MAX)))
      ->capture_default_str();
  app->add_flag("--no-orient", args->no_orient, "Do not turn closed components to face outward (away from the solid each bounds: a hollow object's inner wall into its cavity), nor open ones closed but for small openings, nor build again a part found folded over to face into its solid (both where the normals were estimated without input normals or viewpoint)");
  app->add_option("--threads", args->threads, "Worker threads, 0 = all cores (the output does not depend on it)")
      ->check(non_negative_number())
      ->capture_default_str();
  app->add_option("--max-neighbors", args->max_neighbors,
                  "Fail if a point has more neighbours within 2L/sqrt(3) than this (points far denser than the spacing "
                  "given); with the spacing estimated and each particle's own L, such a point's L is shortened instead")
      ->check(in_range(size_t(2), kMaxNeighborsOption))
      ->capture_default_str();
  app->add_option("--max-triplets-per-point", args->max_triplets_per_point,
                  "Fail before the triangle test if its candidate triplets would average more than this per point "
                  "(L far too large for the spacing; 0 = no limit)")
      ->check(in_range(size_t(0), size_t(UINT32_MAX)))
      ->capture_default_str();
  app->add_option("--report", args->report, "Also write statistics and the topology report as JSON");
  app->add_flag("--ascii", args->ascii, "Write ASCII PLY instead of binary");
  app->add_flag("-q,--quiet", args->quiet, "No summary and no progress line");
  add_particle_input_options(*app, args->input_options);
  add_crop_option(*app, args->input_options.crop);
  add_smooth_chain_options(app, args->smooth);
  add_attributes_option(*app, args->attributes);
  add_sequence_options(*app, args->sequence);
  commands.push_back({app, [args, app] {
                        auto for_frame = [](TriangulateArgs& a, const std::vector<OutputSpec>& outs) {
                          a.output = outs[0].path;
                          a.report = outs[1].path;
                          a.input_options.pcl_mesh = outs[2].path;
                        };
                        return run_file_or_sequence("triangulate", *app, *args, output_specs, for_frame, run_triangulate);
                      }});
}

}  // namespace particlemesh::cli
