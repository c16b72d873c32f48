// particlemesh render IN -o IMAGE.png: the exact iso-surface of volume particles, ray cast.
#include <chrono>
#include <cstdio>
#include <memory>

#include "commands.h"
#include "particlemesh/core/error.h"
#include "particlemesh/io/png.h"
#include "particlemesh/volume/render.h"
#include "particle_input.h"
#include "progress_line.h"
#include "volume_options.h"
#include "run_outputs.h"

namespace particlemesh::cli {

namespace {

struct RenderArgs {
  std::string input, output, kernel = "wyvill", shading = "lambert";
  double radius = 0, threshold = 0, fov = 40;
  std::string radius_channel;  ///< --radius-channel
  double radius_scale = 4;     ///< --radius-scale
  int width = 640, height = 480, threads = 0;
  std::vector<double> camera, up{0, 1, 0};
  bool quiet = false;
  AnisotropyOptions anisotropy;
  std::vector<double> crop;  ///< --crop
};

int run_render(const RenderArgs& a) {
  using Clock = std::chrono::steady_clock;
  RunOutputs outputs({{"-o", a.output, OutputKind::Png}}, {a.input});
  const auto t0 = Clock::now();
  ProgressLine progress(a.quiet);
  set_phase(Phase::Reading);
  ParticleInputArgs input_args;
  input_args.crop = a.crop;
  const ParticleInput input = read_particles(a.input, input_args, a.threads);
  const PointCloud& cloud = input.cloud;
  set_phase(Phase::Computing);
  FieldParams p;
  p.kernel = kernel_from_name(a.kernel);
  p.radius = a.radius;
  p.threshold = a.threshold;
  p.anisotropy = a.anisotropy;
  // Per-particle radii from a channel, with polygonize's default threshold for sizes: the
  // image of the surface polygonize meshes from the same options.
  if (!a.radius_channel.empty()) p.radii = radii_from_channel(cloud, a.radius_channel, a.radius_scale, a.input);
  const bool from_sizes = !a.radius_channel.empty() && a.threshold == 0 && !a.anisotropy.enabled;
  if (from_sizes) p.threshold = sized_threshold(p.kernel, a.radius_scale);
  const auto t1 = Clock::now();
  RayCaster caster = [&] {
    try {
      return RayCaster(ParticleField(cloud, p, a.threads, progress.callback()));
    } catch (const Error& e) {
      // Strays far from the rest (a simulation's particle flung away): keep the rest.
      if (const std::string advised = with_far_outlier_advice(e, false); !advised.empty())
        throw Error(e.status(), advised);
      throw;
    }
  }();
  const double t_build = std::chrono::duration<double>(Clock::now() - t1).count();
  RenderOptions o;
  o.width = a.width;
  o.height = a.height;
  o.shading = shading_from_name(a.shading);
  o.threads = a.threads;
  o.progress = progress.callback();
  const Vec3 up{a.up[0], a.up[1], a.up[2]};
  if (!a.camera.empty()) {
    Camera c;
    c.eye = {a.camera[0], a.camera[1], a.camera[2]};
    c.target = {a.camera[3], a.camera[4], a.camera[5]};
    c.up = up;
    c.fov_degrees = a.fov;
    o.camera = c;
  } else {
    o.camera = default_camera(caster.field(), double(a.width) / double(a.height), up, a.fov);
  }
  const RenderResult r = render(caster, o);
  progress.clear();
  throw_if_interrupted();
  set_phase(Phase::Writing);
  write_png(r.image, outputs.open("-o"));
  outputs.commit_all();
  // No pixel on the surface: the image is written (a frame of a sequence may be empty), with
  // a word on why it is blank.
  if (r.hits == 0) {
    std::fprintf(stderr,
                 "particlemesh render: warning: the surface appears in no pixel: the field may reach the threshold "
                 "T = %g nowhere (lower --threshold or raise --radius), or the camera looks away from it\n",
                 caster.field().threshold());
  } else {
    // Most particles outside the surface (an SPH frame at a radius too small for it), or a
    // radius far larger than the particles' packing asks for: said.
    const FieldAtParticles at = field_at_particles(caster.field());
    const std::string w = radius_warning(at.enclosed_fraction, at.density_radius, caster.field().params().radius,
                                            caster.field().threshold());
    if (!w.empty()) std::fprintf(stderr, "particlemesh render: warning: %s\n", w.c_str());
  }
  if (!a.quiet) {
    const auto& f = caster.field();
    const Camera& c = r.camera;
    std::printf("particlemesh render: %s -> %s\n", a.input.c_str(), a.output.c_str());
    std::printf("  particles     %zu\n", f.size());
    if (!input.summary.empty()) std::printf("%s", input.summary.c_str());
    std::printf("  kernel        %s%s\n", kernel_name(f.kernel()), f.anisotropic() ? ", anisotropic" : "");
    if (f.anisotropic())
      std::printf("  anisotropic   %zu of %zu particles got an ellipsoid (the others: too few neighbours)\n",
                  f.anisotropic_count(), f.size());
    if (!a.radius_channel.empty())
      std::printf("  radius R      per particle: %g x '%s' (median %.6g, largest %.6g)\n", a.radius_scale,
                  a.radius_channel.c_str(), f.params().radius, f.max_radius());
    else
      std::printf("  radius R      %.6g (%s)\n", f.params().radius,
                  f.radius_defaulted() ? default_radius_note(f.params().radius, f.spacing()).c_str() : "given");
    if (from_sizes)
      std::printf("  threshold T   %.6g (default: half the field inside touching particles at R = %g x size)\n",
                  f.threshold(), a.radius_scale);
    else if (f.threshold_defaulted() && f.anisotropic())
      std::printf("  threshold T   %.6g (default: a packed face half a spacing out, calibrated at R = %.3g spacings)\n",
                  f.threshold(), f.calibration_ratio());
    else
      std::printf("  threshold T   %.6g (%s)\n", f.threshold(),
                  f.threshold_defaulted() ? "default: half the field inside a packed volume" : "given");
    std::printf("  camera        eye %.6g %.6g %.6g  target %.6g %.6g %.6g  fov %.4g%s\n", c.eye.x, c.eye.y, c.eye.z,
                c.target.x, c.target.y, c.target.z, c.fov_degrees, a.camera.empty() ? " (default framing)" : "");
    std::printf("  image         %d x %d, %s shading, %llu of %llu pixels on the surface\n", a.width, a.height,
                a.shading.c_str(), (unsigned long long)r.hits, (unsigned long long)r.rays);
    std::printf("  time          %.2f s (hierarchy %.2f, rays %.2f: %.0f rays/s)\n",
                std::chrono::duration<double>(Clock::now() - t0).count(), t_build, r.seconds,
                r.seconds > 0 ? double(r.rays) / r.seconds : 0.0);
  }
  return 0;
}

}  // namespace

void add_render(CLI::App& root, std::vector<Command>& commands) {
  auto args = std::make_shared<RenderArgs>();
  CLI::App* app = root.add_subcommand(
      "render", "Ray cast the exact iso-surface of volume particles into a PNG");
  app->add_option("input", args->input,
                  "Particles: " + kParticleFormats)
      ->required();
  app->add_option("-o,--output", args->output, "Output image (.png; - for standard output)")->required();
  app->add_option("--radius", args->radius, kRadiusHelp)
      ->check(positive_number())
      ->check(finite_number());
  add_radius_channel_options(*app, args->radius_channel, args->radius_scale);
  app->add_option("--threshold", args->threshold,
                  "Iso level T of the summed field (default: half the field inside an evenly packed volume)")
      ->check(positive_number())
      ->check(finite_number());
  app->add_option("--kernel", args->kernel, "Field kernel: wyvill (C1), poly4 (C1), poly6 (C2), blinn (C0)")
      ->check(CLI::IsMember({"wyvill", "poly4", "poly6", "blinn"}, CLI::ignore_case))
      ->capture_default_str();
  add_anisotropy_options(*app, args->anisotropy);
  app->add_option("--width", args->width, "Image width, pixels")->check(in_range(1, 16384))->capture_default_str();
  app->add_option("--height", args->height, "Image height, pixels")->check(in_range(1, 16384))->capture_default_str();
  app->add_option("--camera", args->camera,
                  "Eye and target: EX EY EZ TX TY TZ (default: framing every particle from above, front, right)")
      ->expected(6)
      ->delimiter(',')
      ->check(finite_number());
  app->add_option("--up", args->up, "Image up direction X Y Z")
      ->expected(3)
      ->delimiter(',')
      ->check(finite_number())
      ->capture_default_str();
  app->add_option("--fov", args->fov, "Vertical field of view, degrees")->check(in_range(1.0, 179.0))->check(finite_number())->capture_default_str();
  app->add_option("--shading", args->shading, "lambert (clay, key light) or normal (normal as colour)")
      ->check(CLI::IsMember({"lambert", "normal"}, CLI::ignore_case))
      ->capture_default_str();
  add_crop_option(*app, args->crop);
  app->add_option("--threads", args->threads, "Worker threads, 0 = all cores (the image does not depend on it)")
      ->check(non_negative_number())
      ->capture_default_str();
  app->add_flag("-q,--quiet", args->quiet, "No summary and no progress line");
  commands.push_back({app, [args] { return run_render(*args); }});
}

}  // namespace particlemesh::cli
