// particlemesh smooth MESH -o OUT: Loop (OpenSubdiv) or modified butterfly (OpenMesh)
// subdivision of a triangle mesh; also the `--smooth` step other commands chain.
#include <chrono>
#include <cstdio>
#include <map>
#include <memory>
#include <sstream>

#include "commands.h"
#include "large_allocations.h"
#include "particlemesh/core/error.h"
#include "particlemesh/io/mesh_io.h"
#include "particlemesh/mesh/topology_report.h"
#include "particlemesh/smooth/subdivide.h"
#include "progress_line.h"
#include "report_json.h"
#include "run_outputs.h"
#include "smooth_chain.h"

namespace particlemesh::cli {

namespace {

const std::map<std::string, SmoothScheme> kSchemes{{"loop", SmoothScheme::Loop}, {"butterfly", SmoothScheme::Butterfly}};
const std::map<std::string, BoundaryRule> kBoundaries{{"edge-and-corner", BoundaryRule::EdgeAndCorner},
                                                      {"edge-only", BoundaryRule::EdgeOnly}};
const std::map<std::string, CreaseMethod> kCreaseMethods{{"uniform", CreaseMethod::Uniform},
                                                         {"chaikin", CreaseMethod::Chaikin}};

struct SmoothArgs {
  std::string input, output, report;
  std::string scheme = "loop";
  int levels = 1;
  bool limit = true;
  std::string boundary = "edge-and-corner";
  std::string crease_method = "uniform";
  std::vector<std::string> creases;
  uint64_t max_triangles = SmoothOptions{}.max_triangles;
  int threads = 0;
  bool ascii = false;
  bool quiet = false;
};

/// "A,B" or "A,B,SHARPNESS" -> a crease edge (sharpness: a number, or inf).
CreaseEdge parse_crease(const std::string& text) {
  std::vector<std::string> parts;
  std::stringstream ss(text);
  for (std::string p; std::getline(ss, p, ',');) parts.push_back(p);
  auto bad = [&] {
    return Error(Status::InvalidArgument,
                 "--crease '" + text + "' must be A,B or A,B,SHARPNESS (vertex indices, sharpness >= 0 or inf)");
  };
  if (parts.size() < 2 || parts.size() > 3) throw bad();
  CreaseEdge c;
  try {
    size_t used = 0;
    const long a = std::stol(parts[0], &used);
    if (used != parts[0].size() || a < 0 || a > long(UINT32_MAX)) throw bad();
    const long b = std::stol(parts[1], &used);
    if (used != parts[1].size() || b < 0 || b > long(UINT32_MAX)) throw bad();
    c.a = uint32_t(a);
    c.b = uint32_t(b);
    if (parts.size() == 3) {
      c.sharpness = std::stof(parts[2], &used);
      if (used != parts[2].size()) throw bad();
    }
  } catch (const std::logic_error&) {
    throw bad();
  }
  return c;
}

nlohmann::json smooth_stats_json(const SmoothStats& s) {
  return {{"input_vertices", s.input_vertices},
          {"dropped_vertices", s.dropped_vertices},
          {"control_vertices", s.control_vertices},
          {"control_triangles", s.control_triangles},
          {"control_edges", s.control_edges},
          {"boundary_edges", s.boundary_edges},
          {"reoriented_triangles", s.reoriented_triangles},
          {"nonmanifold_edges", s.nonmanifold_edges},
          {"nonmanifold_vertices", s.nonmanifold_vertices},
          {"creases", s.creases},
          {"vertices", s.vertices},
          {"triangles", s.triangles},
          {"levels", s.levels},
          {"limit", s.limit},
          {"seconds",
           {{"prepare", s.seconds_prepare}, {"refine", s.seconds_refine}, {"limit", s.seconds_limit}, {"output", s.seconds_output}}}};
}

int run_smooth(const SmoothArgs& a) {
  using Clock = std::chrono::steady_clock;
  RunOutputs outputs({{"-o", a.output, OutputKind::Mesh, a.ascii ? MeshFormat::PlyAscii : MeshFormat::Auto}, {"--report", a.report, OutputKind::Text}},
                     {a.input});
  huge_pages_for_large_blocks();  // OpenSubdiv's refined levels, the output, its report
  const auto t0 = Clock::now();
  ProgressLine progress(a.quiet);
  const TriMesh mesh = read_mesh(a.input);
  const double t_read = std::chrono::duration<double>(Clock::now() - t0).count();

  SmoothOptions opt;
  opt.scheme = kSchemes.at(a.scheme);
  opt.levels = a.levels;
  opt.limit = a.limit;
  opt.boundary = kBoundaries.at(a.boundary);
  opt.crease_method = kCreaseMethods.at(a.crease_method);
  for (const auto& c : a.creases) opt.creases.push_back(parse_crease(c));
  opt.max_triangles = a.max_triangles;
  opt.threads = a.threads;
  opt.progress = progress.callback();
  const auto t1 = Clock::now();
  set_phase(Phase::Computing);
  throw_if_interrupted();
  const SmoothResult result = smooth_mesh(mesh, opt);
  const double t_smooth = std::chrono::duration<double>(Clock::now() - t1).count();
  progress.clear();
  throw_if_interrupted();

  // The summary's report: a Loop result of a clean closed surface (one component, no
  // unused vertices, ...) has the topology of its control mesh, refined; then only what the
  // positions decide is measured on the output (subdivided_topology_report: the same report,
  // a fraction of the full one's time and memory). Otherwise the full report of the output
  // (without the input's first where the smoothing's counts already rule that out).
  auto report = [&] {
    const SmoothStats& s = result.stats;
    if (opt.scheme == SmoothScheme::Loop && s.boundary_edges == 0 && s.dropped_vertices == 0)
      if (auto r = subdivided_topology_report(topology_report(mesh), result.mesh, result.stats.levels)) return *r;
    return topology_report(result.mesh);
  };
  const WrittenMesh written = write_with_report(result.mesh, !a.quiet || !a.report.empty(),
                                                [&] { outputs.write_mesh("-o", result.mesh); }, report);

  if (!a.report.empty()) {
    nlohmann::json j{{"input", a.input},
                     {"output", a.output},
                     {"scheme", a.scheme},
                     {"boundary", a.boundary},
                     {"smooth", smooth_stats_json(result.stats)},
                     {"topology", to_json(written.report)},
                     {"seconds", {{"read", t_read}, {"smooth", t_smooth}, {"write", written.seconds}}}};
    if (!mesh.not_read.empty()) j["not_read"] = mesh.not_read;
    if (const auto nw = outputs.channels_not_written("-o", result.mesh); !nw.empty()) j["not_written"] = nw;
    outputs.open("--report").write(json_text(j));
  }
  outputs.commit_all();
  if (!a.quiet) {
    const auto& s = result.stats;
    std::printf("particlemesh smooth: %s -> %s\n", a.input.c_str(), a.output.c_str());
    std::printf("%s", not_read_line(mesh.not_read).c_str());
    std::printf("%s", not_written_lines(outputs, result.mesh).c_str());
    std::printf("  scheme        %s, %d level%s%s\n", a.scheme.c_str(), s.levels, s.levels == 1 ? "" : "s",
                s.limit ? ", limit positions and normals" : "");
    std::printf("  control mesh  %zu vertices, %zu triangles, %zu edges (%zu boundary)\n", s.control_vertices,
                s.control_triangles, s.control_edges, s.boundary_edges);
    if (s.dropped_vertices) std::printf("  dropped       %zu unreferenced vertices\n", s.dropped_vertices);
    if (s.reoriented_triangles) std::printf("  reoriented    %zu triangles\n", s.reoriented_triangles);
    if (s.nonmanifold_edges || s.nonmanifold_vertices)
      std::printf("  non-manifold  %zu edges in more than two triangles, %zu vertices joining several fans: kept "
                  "sharp\n", s.nonmanifold_edges, s.nonmanifold_vertices);
    if (s.creases) std::printf("  creases       %zu edges\n", s.creases);
    print_mesh_and_times(written.report, "smooth", t_read, t_smooth, written.seconds);
  }
  return 0;
}

}  // namespace

void add_smooth(CLI::App& root, std::vector<Command>& commands) {
  auto args = std::make_shared<SmoothArgs>();
  CLI::App* app = root.add_subcommand(
      "smooth", "Subdivide a triangle mesh into a smooth one: Loop (OpenSubdiv) or modified butterfly (OpenMesh)");
  app->add_option("mesh", args->input, "Input mesh: .ply, .obj, .off or .stl (a 2-manifold)")->required();
  app->add_option("-o,--output", args->output, "Output mesh: .ply (binary; --ascii for text), .obj, .vtk, .vtu or .vtp; - (or a device, a FIFO) for PLY on standard output")->required();
  app->add_option("--scheme", args->scheme,
                  "loop: approximating, exact limit surface; butterfly: interpolating, keeps every vertex")
      ->check(CLI::IsMember({"loop", "butterfly"}))
      ->capture_default_str();
  app->add_option("--levels", args->levels, "Subdivision levels; each multiplies the triangles by 4")
      ->check(in_range(0, kMaxSmoothLevels))
      ->capture_default_str();
  app->add_flag("--limit,!--no-limit", args->limit,
                "Loop: move vertices to the exact limit surface, with exact limit normals (default on)");
  app->add_option("--boundary", args->boundary,
                  "Loop boundary rule: edge-and-corner (B-spline boundary, corners pinned) or edge-only")
      ->check(CLI::IsMember({"edge-and-corner", "edge-only"}))
      ->capture_default_str();
  app->add_option("--crease", args->creases,
                  "Loop: keep edge A,B sharp (A,B,S: sharpness S, 10 or inf = infinitely sharp); repeatable")
      ->expected(1)
      ->multi_option_policy(CLI::MultiOptionPolicy::TakeAll);
  app->add_option("--crease-method", args->crease_method, "Loop: how semi-sharp creases soften: uniform or chaikin")
      ->check(CLI::IsMember({"uniform", "chaikin"}))
      ->capture_default_str();
  app->add_option("--max-triangles", args->max_triangles,
                  "Refuse (before any work) results with more triangles than this")
      ->check(in_range(uint64_t(1), uint64_t(1) << 30))
      ->capture_default_str();
  app->add_option("--threads", args->threads, "Worker threads, 0 = all cores (the output does not depend on it)")
      ->check(non_negative_number())
      ->capture_default_str();
  app->add_option("--report", args->report, "Also write statistics and the topology report as JSON");
  app->add_flag("--ascii", args->ascii, "Write ASCII PLY instead of binary");
  app->add_flag("-q,--quiet", args->quiet, "No summary and no progress line");
  commands.push_back({app, [args] { return run_smooth(*args); }});
}

void add_smooth_chain_options(CLI::App* app, SmoothChainArgs& args) {
  CLI::Option* smooth =
      app->add_option("--smooth", args.scheme,
                      "Smooth the mesh: loop (OpenSubdiv, limit surface) or butterfly (OpenMesh, keeps the particles)")
          ->check(CLI::IsMember({"loop", "butterfly"}));
  app->add_option("--levels", args.levels, "Subdivision levels for --smooth; each multiplies the triangles by 4")
      ->check(in_range(0, kMaxSmoothLevels))
      ->needs(smooth)
      ->capture_default_str();
}

void apply_smooth_chain(TriMesh& mesh, const SmoothChainArgs& args, int threads, ProgressLine& progress) {
  if (args.scheme.empty()) return;
  SmoothOptions opt;
  opt.scheme = kSchemes.at(args.scheme);
  opt.levels = args.levels;
  opt.threads = threads;
  opt.progress = progress.callback();
  try {
    mesh = smooth_mesh(mesh, opt).mesh;
  } catch (const Error& e) {
    throw Error(e.status(), "--smooth " + args.scheme + ": " + e.what());
  }
  progress.clear();
  throw_if_interrupted();
}

}  // namespace particlemesh::cli
