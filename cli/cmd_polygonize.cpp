// particlemesh polygonize IN -o OUT: volume particles to the mesh of their implicit surface.
#include <chrono>
#include <cmath>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "commands.h"
#include "particlemesh/core/error.h"
#include "particlemesh/io/mesh_io.h"
#include "particlemesh/mesh/topology_report.h"
#include "particlemesh/volume/field.h"
#include "particlemesh/volume/polygonize.h"
#include "attribute_selection.h"
#include "frame_sequence.h"
#include "particle_input.h"
#include "progress_line.h"
#include "report_json.h"
#include "volume_options.h"
#include "run_outputs.h"

namespace particlemesh::cli {

namespace {

struct PolygonizeArgs {
  std::string input, output, report, kernel = "wyvill";
  double radius = 0, threshold = 0, cell = 0;
  std::string radius_channel;
  double radius_scale = 4;
  double max_grid_mib = double(kDefaultMaxGridBytes >> 20);
  int threads = 0;
  bool ascii = false, quiet = false;
  AnisotropyOptions anisotropy;
  double min_component_volume = 0, min_component_particles = 0;
  double collapse_edges = 0;
  int taubin = 0;
  double taubin_lambda = TaubinOptions{}.lambda, taubin_mu = TaubinOptions{}.mu;
  std::vector<double> crop;  ///< --crop
  std::string attributes = "all";
  std::string lattice_anchor = "space";
  SequenceArgs sequence;
};

nlohmann::json stats_json(const PolygonizeStats& s) {
  return {{"particles", s.particles},
          {"kernel", kernel_name(s.kernel)},
          {"radius", s.radius},
          {"max_radius", s.max_radius},
          {"threshold", s.threshold},
          {"cell_size", s.cell_size},
          {"spacing", s.spacing},
          {"radius_defaulted", s.radius_defaulted},
          {"threshold_defaulted", s.threshold_defaulted},
          {"cell_size_defaulted", s.cell_size_defaulted},
          {"anisotropic", s.anisotropic},
          {"anisotropic_particles", s.anisotropic_particles},
          {"calibration_ratio", s.calibration_ratio},
          {"enclosed_fraction", s.enclosed_fraction},
          {"density_radius", s.density_radius},
          {"min_component_volume", s.min_component_volume},
          {"components_removed", s.components_removed},
          {"edges_collapsed", s.edges_collapsed},
          {"smoothing_iterations", s.smoothing_iterations},
          {"candidate_blocks", s.candidate_blocks},
          {"sampled_blocks", s.sampled_blocks},
          {"surface_blocks", s.surface_blocks},
          {"sampled_nodes", s.sampled_nodes},
          {"bounding_box_nodes", s.bounding_box_nodes},
          {"grid_bytes", s.grid_bytes},
          {"vertices", s.vertices},
          {"triangles", s.triangles},
          {"field_evaluations", s.field_evaluations},
          {"seconds", {{"setup", s.seconds_setup}, {"sampling", s.seconds_sampling}, {"meshing", s.seconds_meshing},
                       {"finishing", s.seconds_finishing}}}};
}

std::vector<OutputSpec> output_specs(const PolygonizeArgs& a) {
  return {{"-o", a.output, OutputKind::Mesh, a.ascii ? MeshFormat::PlyAscii : MeshFormat::Auto},
          {"--report", a.report, OutputKind::Text}};
}

/// Mesh one file; `frame` is null for a single file, the sequence's context for a frame.
int run_polygonize(const PolygonizeArgs& a, FrameContext* frame = nullptr) {
  using Clock = std::chrono::steady_clock;
  RunOutputs outputs(with_frame_outputs(output_specs(a), frame), {a.input});
  const auto t0 = Clock::now();
  ProgressLine progress(a.quiet);
  ParticleInputArgs input_args;
  input_args.crop = a.crop;
  ParticleInput input = read_particles(a.input, input_args, a.threads);
  // Per-particle radii from a channel, taken before --attributes chooses what the mesh carries.
  std::vector<double> radii;
  if (!a.radius_channel.empty()) radii = radii_from_channel(input.cloud, a.radius_channel, a.radius_scale, a.input);
  settle_attributes(input.cloud, a.attributes, frame);
  const PointCloud& cloud = input.cloud;
  const double t_read = std::chrono::duration<double>(Clock::now() - t0).count();

  PolygonizeOptions opt;
  opt.kernel = kernel_from_name(a.kernel);
  opt.radius = a.radius;
  opt.radii = std::move(radii);
  opt.threshold = a.threshold;
  // Radii from sizes: the default threshold for sizes (volume_options.h).
  const bool from_sizes = !a.radius_channel.empty() && a.threshold == 0 && !a.anisotropy.enabled;
  if (from_sizes) opt.threshold = sized_threshold(opt.kernel, a.radius_scale);
  opt.cell_size = a.cell;
  opt.threads = a.threads;
  opt.max_grid_bytes = uint64_t(a.max_grid_mib * double(1 << 20));
  opt.anisotropy = a.anisotropy;
  opt.min_component_volume = a.min_component_volume;
  opt.min_component_particles = a.min_component_particles;
  opt.collapse_edges = a.collapse_edges;
  opt.surface_smoothing.iterations = a.taubin;
  opt.surface_smoothing.lambda = a.taubin_lambda;
  opt.surface_smoothing.mu = a.taubin_mu;
  opt.lattice_anchor = a.lattice_anchor == "particles" ? LatticeAnchor::Particles : LatticeAnchor::Space;
  opt.progress = progress.callback();
  const auto t1 = Clock::now();
  set_phase(Phase::Computing);
  throw_if_interrupted();
  PolygonizeResult result = [&] {
    try {
      return polygonize(cloud, opt);
    } catch (const Error& e) {
      // The library names its own option (max_grid_bytes); say the command line's.
      std::string m = e.what();
      const std::string lib = "(max_grid_bytes; use a larger cell size or raise the budget)";
      if (const size_t at = m.find(lib); at != std::string::npos) {
        m.replace(at, lib.size(), "(use a larger --cell or raise --max-grid-mib)");
        throw Error(e.status(), m);
      }
      // Strays far from the rest (a simulation's particle flung away): keep the rest.
      if (const std::string advised = with_far_outlier_advice(e, false); !advised.empty())
        throw Error(e.status(), advised);
      throw;
    }
  }();
  const double t_poly = std::chrono::duration<double>(Clock::now() - t1).count();
  progress.clear();
  throw_if_interrupted();

  const WrittenMesh written = write_with_report(result.mesh, !a.quiet || !a.report.empty(),
                                                [&] { outputs.write_mesh("-o", result.mesh); });
  // No surface at all: the field never reaches the threshold where it was sampled. The empty
  // mesh is still written (a frame of a sequence may well be empty), with a warning.
  // Most particles outside the surface, or a radius far larger than their packing asks for:
  // said, with the radius their packing suggests.
  const PolygonizeStats& st = result.stats;
  std::string warning =
      radius_warning(st.enclosed_fraction, st.density_radius, st.radius, st.threshold, true);
  // A surface in about as many pieces as particles (taken from the topology report, so not
  // with -q and no --report, nor per frame of a sequence): one layer of particles, blobs
  // around them.
  if (const std::string pieces = pieces_warning(written.report.components, st.particles); !pieces.empty())
    warning = warning.empty() ? pieces : warning + "; " + pieces;
  if (result.mesh.triangles.empty()) {
    char w[400];
    std::snprintf(w, sizeof w,
                  "no surface: the field reaches the threshold T = %g nowhere (T above the field's largest value, or "
                  "particles too far apart for the radius R = %g): lower --threshold or raise --radius",
                  st.threshold, st.radius);
    warning = w;
  }
  if (!warning.empty()) {
    if (frame)
      frame->warn(warning);
    else
      std::fprintf(stderr, "particlemesh polygonize: warning: %s\n", warning.c_str());
  }

  if (!a.report.empty()) {
    nlohmann::json j{{"input", a.input},
                     {"output", a.output},
                     {"read", input.report},
                     {"polygonize", stats_json(result.stats)},
                     {"topology", to_json(written.report)},
                     {"seconds", {{"read", t_read}, {"polygonize", t_poly}, {"write", written.seconds}}}};
    if (!warning.empty()) j["warning"] = warning;
    if (const auto nw = outputs.channels_not_written("-o", result.mesh); !nw.empty()) j["not_written"] = nw;
    outputs.open("--report").write(json_text(j));
  }
  commit_outputs(outputs, frame);
  if (!a.quiet && !frame) {
    const auto& s = result.stats;
    std::printf("particlemesh polygonize: %s -> %s\n", a.input.c_str(), a.output.c_str());
    std::printf("  particles     %zu\n", s.particles);
    if (!input.summary.empty()) std::printf("%s", input.summary.c_str());
    std::printf("%s", not_written_lines(outputs, result.mesh).c_str());
    if (s.spacing > 0) std::printf("  spacing       %.6g (median nearest-neighbour distance)\n", s.spacing);
    std::printf("  kernel        %s (C%d at R)\n", kernel_name(s.kernel), kernel_continuity(s.kernel));
    if (!a.radius_channel.empty())
      std::printf("  radius R      per particle: %g x '%s' (median %.6g, largest %.6g)\n", a.radius_scale,
                  a.radius_channel.c_str(), s.radius, s.max_radius);
    else
      std::printf("  radius R      %.6g (%s)\n", s.radius,
                  s.radius_defaulted ? default_radius_note(s.radius, s.spacing).c_str() : "given");
    if (s.threshold_defaulted && s.anisotropic)
      std::printf("  threshold T   %.6g (default: a packed face half a spacing out, calibrated at R = %.3g spacings)\n",
                  s.threshold, s.calibration_ratio);
    else if (from_sizes)
      std::printf("  threshold T   %.6g (default: half the field inside touching particles at R = %g x size)\n",
                  s.threshold, a.radius_scale);
    else
      std::printf("  threshold T   %.6g (%s)\n", s.threshold,
                  s.threshold_defaulted ? "default: half the field inside a packed volume at R = 2 spacings" : "given");
    std::printf("  cell h        %.6g (%s)\n", s.cell_size, s.cell_size_defaulted ? "default: R / 4" : "given");
    std::printf("  enclosed      %.0f%% of the particles (F >= T at their centres)\n", 100.0 * s.enclosed_fraction);
    if (s.anisotropic)
      std::printf("  anisotropic   %zu of %zu particles got an ellipsoid (the others: too few neighbours)\n",
                  s.anisotropic_particles, s.particles);
    if (s.min_component_volume > 0)
      std::printf("  small pieces  %zu dropped (enclosing less than %.6g)\n", s.components_removed,
                  s.min_component_volume);
    if (a.collapse_edges > 0)
      std::printf("  slivers       %zu edges shorter than %.3g h collapsed\n", s.edges_collapsed, a.collapse_edges);
    if (s.smoothing_iterations > 0)
      std::printf("  smoothing     %d Taubin iterations (lambda %.3g, mu %.3g)\n", s.smoothing_iterations,
                  a.taubin_lambda, a.taubin_mu);
    std::printf("  grid          %zu blocks of 8^3 sampled (%.1f MiB), %zu with surface\n", s.sampled_blocks,
                double(s.grid_bytes) / double(1 << 20), s.surface_blocks);
    print_mesh_and_times(written.report, "polygonize", t_read, t_poly, written.seconds);
  }
  return 0;
}

}  // namespace

void add_polygonize(CLI::App& root, std::vector<Command>& commands) {
  auto args = std::make_shared<PolygonizeArgs>();
  CLI::App* app = root.add_subcommand(
      "polygonize", "Volume particles to the mesh of their implicit surface (summed kernels, marching cubes)");
  app->add_option("input", args->input,
                  "Particles: " + kParticleFormats +
                      "; a path with a frame field ({} or {:04d}, e.g. sim/fluid_{:04d}.vtk) is a sequence: every "
                      "frame is meshed; so is a ParaView collection (.pvd, .series), frame n its n-th file by time")
      ->required();
  app->add_option("-o,--output", args->output,
                  "Output mesh with normals: .ply (binary; --ascii for text), .obj, .vtk, .vtu or .vtp; - (or a "
                  "device, a FIFO) for PLY on standard output. With a sequence input, a pattern too "
                  "(out/fluid_{:04d}.ply)")
      ->required();
  app->add_option("--radius", args->radius, kRadiusHelp)
      ->check(positive_number())
      ->check(finite_number());
  add_radius_channel_options(*app, args->radius_channel, args->radius_scale);
  app->add_option("--threshold", args->threshold,
                  "Iso level T of the summed field (default: half the field inside an evenly packed volume at "
                  "R = 2 spacings: 3.33 wyvill, 3.94 poly4, 2.58 poly6, 1.23 blinn)")
      ->check(positive_number())
      ->check(finite_number());
  app->add_option("--kernel", args->kernel, "Field kernel: wyvill (C1), poly4 (C1), poly6 (C2), blinn (C0)")
      ->check(CLI::IsMember({"wyvill", "poly4", "poly6", "blinn"}, CLI::ignore_case))
      ->capture_default_str();
  app->add_option("--cell", args->cell, "Grid cell size h, world units (default: R / 4)")->check(positive_number())->check(finite_number());
  add_crop_option(*app, args->crop);
  app->add_option("--threads", args->threads, "Worker threads, 0 = all cores (the output does not depend on it)")
      ->check(non_negative_number())
      ->capture_default_str();
  app->add_option("--max-grid-mib", args->max_grid_mib,
                  "Fail before the block search, the sparse grid or the grid with the mesh would need more memory "
                  "than this, MiB (0 = no limit; at least one byte, 1e-6 MiB, otherwise)")
      ->check(non_negative_number())
      ->check(finite_number())
      ->check(CLI::Validator(
          [](std::string& s) -> std::string {
            // Below one byte the budget would round to 0, which means "no limit".
            const double v = std::strtod(s.c_str(), nullptr);
            if (v > 0 && v * double(1 << 20) < 1) return "value " + s + " MiB is less than one byte (0 = no limit)";
            if (v * double(1 << 20) >= 1.8e19) return "value " + s + " MiB is beyond 2^64 bytes (0 = no limit)";
            return {};
          },
          "BYTES"))
      ->capture_default_str();
  add_anisotropy_options(*app, args->anisotropy);
  app->add_option("--min-component-volume", args->min_component_volume,
                  "Drop the pieces of the surface that enclose less than this volume, world units cubed "
                  "(splashes, droplets; default 0: keep all)")
      ->check(non_negative_number())
      ->check(finite_number());
  app->add_option("--min-component-particles", args->min_component_particles,
                  "Drop the pieces that enclose less than N particles' worth of volume, N x spacing^3 "
                  "(default 0: keep all)")
      ->check(non_negative_number())
      ->check(finite_number());
  app->add_option("--collapse-edges", args->collapse_edges,
                  "Collapse every edge shorter than F x the cell h into one vertex on the surface, where the surface "
                  "stays closed and manifold and no triangle turns by more than 60 degrees: marching cubes' slivers "
                  "(thin triangles where the surface passes near a lattice node) become ordinary triangles "
                  "(0 <= F <= 0.5; 0.3 takes out nine in ten of the triangles with an angle under 10 degrees; "
                  "default 0: off)")
      ->check(in_range(0.0, 0.5))
      ->check(finite_number());
  app->add_option("--taubin", args->taubin,
                  "Smooth the mesh with N iterations of Taubin's volume-keeping lambda|mu filter (default 0: off; "
                  "10 takes out bumps a few cells across)")
      ->check(in_range(0, 10000));
  app->add_option("--taubin-lambda", args->taubin_lambda, "With --taubin: the shrinking step, 0 < lambda <= 1")
      ->check(in_range(1e-9, 1.0))
      ->check(finite_number())
      ->capture_default_str();
  app->add_option("--taubin-mu", args->taubin_mu, "With --taubin: the inflating step, -1 <= mu < -lambda")
      ->check(in_range(-1.0, -1e-9))
      ->check(finite_number())
      ->capture_default_str();
  app->add_option("--lattice-anchor", args->lattice_anchor,
                  "space: the marching-cubes lattice's nodes lie at multiples of the cell h in world coordinates, "
                  "so the frames of a simulation are sampled at the same points and do not shimmer; particles: the "
                  "lattice starts at the particles' box (what the Python polygonize does by default)")
      ->check(CLI::IsMember({"space", "particles"}))
      ->capture_default_str();
  add_attributes_option(*app, args->attributes);
  app->add_option("--report", args->report, "Also write statistics and the topology report as JSON (with a sequence input: a pattern too)");
  app->add_flag("--ascii", args->ascii, "Write ASCII PLY instead of binary");
  app->add_flag("-q,--quiet", args->quiet, "No summary and no progress line");
  add_sequence_options(*app, args->sequence);
  commands.push_back({app, [args, app] {
                        auto for_frame = [](PolygonizeArgs& a, const std::vector<OutputSpec>& outs) {
                          a.output = outs[0].path;
                          a.report = outs[1].path;
                        };
                        return run_file_or_sequence("polygonize", *app, *args, output_specs, for_frame, run_polygonize);
                      }});
}

}  // namespace particlemesh::cli
