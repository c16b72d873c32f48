// particlemesh triangulate IN -o OUT: surface particles to a mesh.
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "commands.h"
#include "particle_input.h"
#include "particlemesh/core/error.h"
#include "particlemesh/io/mesh_io.h"
#include "particlemesh/mesh/topology_report.h"
#include "particlemesh/sample/thin.h"
#include "particlemesh/surface/spacing.h"
#include "particlemesh/surface/reconstruct.h"
#include "particlemesh/surface/triangulate.h"
#include "progress_line.h"
#include "report_json.h"
#include "smooth_chain.h"

namespace particlemesh::cli {

namespace {

struct TriangulateArgs {
  std::string input, output, report;
  double spacing = 0;
  double max_edge_factor = 2.0;
  double thin = 1.0;
  bool raw = false;
  bool no_orient = false;
  bool no_repair = false;
  std::string normals = "auto";
  size_t fill_holes = 100;
  double fill_edge_factor = 1.5;
  double normal_angle = 120.0;
  bool ascii = false;
  bool quiet = false;
  int threads = 0;
  size_t max_neighbors = 256;
  size_t max_triplets_per_point = TriangulateOptions{}.max_triplets_per_point;
  ParticleInputArgs input_options;  // .pcd, PCL preprocessing, --pcl-mesh
  SmoothChainArgs smooth;  // --smooth loop|butterfly --levels K
};

/// When over 5 % of the particles are in no triangle of the surface, their spacing varies more
/// than one longest edge L allows (mesh vertices, scans): say what helps. Empty otherwise.
std::string uneven_spacing_hint(const SurfaceResult& r, double thin) {
  const size_t points = r.triangulation.points, unused = r.surface.unused_points;
  if (points == 0 || unused * 20 <= points) return {};
  char s[320];
  std::snprintf(s, sizeof s,
                "%.0f%% of the particles are in no triangle: they are unevenly spaced for L; try --thin %g "
                "(an even subset) or a larger --max-edge-factor",
                100.0 * double(unused) / double(points), thin > 1 ? thin + 1 : 2.0);
  return s;
}

/// When the co-normality test dropped over a third of the seed's triangles (triangles across
/// particles facing opposite ways) and the surface did not close, the particles probably fill
/// a volume (a fluid simulation's) rather than sample a surface: say which command meshes
/// those. Surfaces drop at most ~15 % (noisy scans; 0-3 % on clean samples); SPH frames
/// 48-76 %; thin parts 1-1.5 spacings thick drop ~60 % too, but they close (or, thinner, leave
/// loops, where the "if" of the hint applies). Empty otherwise.
std::string volume_particles_hint(const SurfaceResult& r) {
  const size_t kept = r.triangulation.kept, dropped = r.surface.rejected_conormal;
  if (kept == 0 || dropped * 20 <= kept * 7 || r.surface.holes_left == 0) return {};
  char s[320];
  std::snprintf(s, sizeof s,
                "%.0f%% of the seed's triangles were dropped for joining particles that face opposite ways: if "
                "these particles fill a volume (e.g. a fluid simulation's), `particlemesh polygonize` meshes its "
                "surface",
                100.0 * double(dropped) / double(kept));
  return s;
}

/// Every hint that applies, most important first.
std::vector<std::string> surface_hints(const SurfaceResult& r, double thin) {
  std::vector<std::string> out;
  for (std::string h : {volume_particles_hint(r), uneven_spacing_hint(r, thin)})
    if (!h.empty()) out.push_back(std::move(h));
  return out;
}

int run_triangulate(const TriangulateArgs& a) {
  using Clock = std::chrono::steady_clock;
  const auto t0 = Clock::now();
  ProgressLine progress(a.quiet);
  const ParticleInput input = read_particles(a.input, a.input_options, a.threads);
  const double t_read = std::chrono::duration<double>(Clock::now() - t0).count();

  // --thin: an even subset, no two particles closer than thin x r0 (r0 given or estimated).
  // Its spacing is estimated afresh: the subset's gaps run from d to 2d.
  PointCloud thinned;
  double thin_distance = 0;
  if (a.thin > 1) {
    if (interrupted()) throw Error(Status::Cancelled, "cancelled (interrupted)");
    const double r0 = a.spacing > 0           ? a.spacing
                      : input.spacing_hint > 0 ? input.spacing_hint
                                               : estimate_spacing(input.cloud.positions.data(), input.cloud.size(), a.threads).spacing;
    thin_distance = a.thin * r0;
    thinned = thin_cloud(input.cloud, thin_distance);
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
  opt.orient = !a.no_orient;
  opt.progress = progress.callback();
  const auto t1 = Clock::now();
  set_phase(Phase::Computing);
  if (interrupted()) throw Error(Status::Cancelled, "cancelled (interrupted)");
  SurfaceResult result;
  if (a.raw) {
    TriangulateResult r = triangulate_raw(cloud, opt);
    result.mesh = std::move(r.mesh);
    result.triangulation = r.stats;
  } else {
    result = reconstruct_surface(cloud, opt);
  }
  const double t_tri = std::chrono::duration<double>(Clock::now() - t1).count();
  progress.clear();
  if (interrupted()) throw Error(Status::Cancelled, "cancelled (interrupted)");

  apply_smooth_chain(result.mesh, a.smooth, a.threads, progress);  // --smooth: after the mesh is made

  WriteMeshOptions wo;
  if (a.ascii) wo.format = MeshFormat::PlyAscii;
  TopologyReport report;
  const double t_write = write_outputs(
      [&] {
        write_mesh(result.mesh, a.output, wo);
        write_pcl_mesh(result.mesh, a.input_options);
      },
      {a.output, a.input_options.pcl_mesh}, [&] { report = topology_report(result.mesh); });
  if (!a.report.empty()) {
    nlohmann::json j{{"input", a.input},
                     {"output", a.output},
                     {"mode", a.raw ? "raw" : "surface"},
                     {"triangulation", to_json(result.triangulation)},
                     {"surface", a.raw ? nlohmann::json(nullptr) : to_json(result.surface)},
                     {"topology", to_json(report)},
                     {"seconds", {{"read", t_read}, {"triangulate", t_tri}, {"write", t_write}}}};
    if (!input.report.is_null()) j["input_cloud"] = input.report;
    if (a.thin > 1)
      j["thin"] = {{"factor", a.thin}, {"distance", thin_distance}, {"kept", cloud.size()}, {"of", input.cloud.size()}};
    if (!a.raw) {
      std::string joined;  // one string, as the report has always had
      for (const std::string& h : surface_hints(result, a.thin)) joined += (joined.empty() ? "" : " / ") + h;
      if (!joined.empty()) j["hint"] = joined;
    }
    write_json_file(j, a.report);
  }
  if (!a.quiet) {
    const auto& s = result.triangulation;
    std::printf("particlemesh triangulate: %s -> %s\n", a.input.c_str(), a.output.c_str());
    std::printf("%s", input.summary.c_str());
    if (a.thin > 1)
      std::printf("  thinned       %zu of %zu particles kept, none closer than %.6g (%g x r0)\n", cloud.size(),
                  input.cloud.size(), thin_distance, a.thin);
    std::printf("  points        %zu%s\n", s.points,
                s.duplicate_points ? (" (" + std::to_string(s.duplicate_points) + " exact duplicates set aside)").c_str() : "");
    std::printf("  spacing r0    %.6g (%s)\n", s.spacing, s.spacing_estimated ? "estimated: median nearest-neighbour distance" : "given");
    std::printf("  max edge L    %.6g (%g x r0)\n", s.max_edge, a.max_edge_factor);
    std::printf("  seed's test   %zu candidate triplets, %zu kept%s\n", s.candidates, s.kept,
                s.ties ? (", " + std::to_string(s.ties) + " ties broken").c_str() : "");
    if (!a.raw) {
      const auto& f = result.surface;
      std::printf("  normals       %s\n", f.normals_estimated ? (cloud.has_normals() && a.normals == "auto" ? "plane fits, facing as the input's normals" : "plane fits, oriented by a spanning tree") : "the input's");
      std::printf("  surface       %zu co-normal candidates (%zu dropped), %zu grown from %zu seeds\n", f.candidates,
                  f.rejected_conormal, f.grown, f.seeds);
      std::printf("  repair        %zu holes filled (%zu triangles), %zu pinches resolved, %zu loops left open%s\n",
                  f.holes_filled, f.hole_triangles, f.pinches_resolved, f.holes_left,
                  f.holes_left ? (" (largest " + std::to_string(f.largest_hole_left) + " edges)").c_str() : "");
      if (f.unused_points) std::printf("  unused        %zu particles in no triangle\n", f.unused_points);
      for (const std::string& h : surface_hints(result, a.thin)) std::printf("  hint          %s\n", h.c_str());
    }
    std::printf("%s", describe(report).c_str());
    std::printf("  time          %.2f s (read %.2f, triangulate %.2f, write %.2f)\n",
                t_read + t_tri + t_write, t_read, t_tri, t_write);
  }
  return 0;
}

}  // namespace

void add_triangulate(CLI::App& root, std::vector<Command>& commands) {
  auto args = std::make_shared<TriangulateArgs>();
  CLI::App* app = root.add_subcommand("triangulate", "Surface particles to a triangle mesh (seed section 5.2.3)");
  app->add_option("input", args->input, "Particles: .ply (x y z [nx ny nz]), .xyz (x y z [nx ny nz] per line) or .pcd (PCL: ascii, binary, binary_compressed)")
      ->required();
  app->add_option("-o,--output", args->output, "Output mesh: .ply (binary; --ascii for text) or .obj")->required();
  app->add_option("--spacing", args->spacing,
                  "Particle spacing r0 in world units (default: estimated as the median nearest-neighbour distance)")
      ->check(CLI::PositiveNumber)
      ->check(finite_number());
  app->add_option("--max-edge-factor", args->max_edge_factor, "Longest triangle edge L = factor x r0")
      ->check(CLI::Range(1e-6, 100.0))
      ->check(finite_number())
      ->capture_default_str();
  app->add_option("--thin", args->thin,
                  "Mesh an even subset of the particles, none closer than FACTOR x r0 (r0 from --spacing or "
                  "estimated; the subset's own spacing is then estimated): a coarse preview, and evener input "
                  "from unevenly sampled clouds. 1 = every particle")
      ->check(CLI::Range(1.0, 1000.0))
      ->check(finite_number())
      ->capture_default_str();
  app->add_flag("--raw", args->raw, "Return the seed's exact triangle set (not a surface: overlapping pairs on quads)");
  app->add_option("--normal-angle", args->normal_angle,
                  "Co-normality: drop triangles whose corner normals differ by more than this, or whose face normal differs from a corner's by more than min(this, 90) (degrees)")
      ->check(CLI::Range(1.0, 180.0))
      ->check(finite_number())
      ->capture_default_str();
  app->add_option("--normals", args->normals,
                  "auto: plane-fit directions, facing as the input's normals say (if any); "
                  "input: the input's normals as they are; estimate: ignore the input's normals")
      ->check(CLI::IsMember({"auto", "input", "estimate"}))
      ->capture_default_str();
  app->add_flag("--no-repair", args->no_repair, "Skip the repair stage (hole filling, unpinching)");
  app->add_option("--fill-holes", args->fill_holes, "Fill boundary loops of up to N edges (0 = none)")
      ->check(CLI::Range(size_t(0), size_t(100000)))
      ->capture_default_str();
  app->add_option("--fill-edge-factor", args->fill_edge_factor,
                  "Fill triangles' edges at most this x L: wider openings are real and stay open")
      ->check(CLI::Range(0.1, 10.0))
      ->check(finite_number())
      ->capture_default_str();
  app->add_flag("--no-orient", args->no_orient, "Do not turn closed components to face outward");
  app->add_option("--threads", args->threads, "Worker threads, 0 = all cores (the output does not depend on it)")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  app->add_option("--max-neighbors", args->max_neighbors,
                  "Fail if a point has more neighbours within L than this (points far denser than the spacing)")
      ->check(CLI::Range(size_t(2), size_t(100000)))
      ->capture_default_str();
  app->add_option("--max-triplets-per-point", args->max_triplets_per_point,
                  "Fail before the triangle test if its candidate triplets would average more than this per point "
                  "(L far too large for the spacing; 0 = no limit)")
      ->check(CLI::Range(size_t(0), size_t(UINT32_MAX)))
      ->capture_default_str();
  app->add_option("--report", args->report, "Also write statistics and the topology report as JSON");
  app->add_flag("--ascii", args->ascii, "Write ASCII PLY instead of binary");
  app->add_flag("-q,--quiet", args->quiet, "No summary and no progress line");
  add_particle_input_options(*app, args->input_options);
  add_smooth_chain_options(app, args->smooth);
  commands.push_back({app, [args] { return run_triangulate(*args); }});
}

}  // namespace particlemesh::cli
