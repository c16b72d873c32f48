// Ray casting of particle iso-surfaces beside POV-Ray's blob primitive, rendering
// the same particles, same surface, same camera and image size, in the same run. Prints a
// table; numbers and machine go to bench/RESULTS.md.
//
//   build/bench/raycast_bench [--sizes 1000,10000,100000] [--threads 2] [--reps 2]
//                             [--width 640] [--height 480] [--no-povray] [--keep DIR]
//
// Input: a dam-break-like block: k x 2k x k particles on a simple cubic lattice of spacing
// s = 0.02 with every coordinate jittered by up to +-5 % of s (fixed seed), k = cbrt(N / 2).
// Surface: the Poly4 kernel (1 - r^2/R^2)^2, R = 2s, strength 1, the default threshold (half
// the field inside the packed block): exactly POV-Ray's blob, whose components have density
// strength x (1 - r^2/radius^2)^2 and whose surface is where the sum reaches `threshold`.
// Camera: particlemesh's default framing (render.h) at width x height, one primary ray per
// pixel, no anti-aliasing, one light without shadows (POV-Ray: `shadowless`, +A off).
//
// particlemesh: time of render() (best of reps; the hierarchy's build is listed apart), on
// `threads` threads. Also the Wyvill kernel (degree 6 per interval, Bernstein isolation).
// POV-Ray 3.7 (Debian's povray): `povray +WT<threads> -D` on a generated scene; its own
// "Trace Time" and the wall clock of the whole process (parsing the components and building
// its bounding hierarchy included). Skipped with a message when povray is not installed.
// "agree" is the share of pixels on which both say surface / background alike. "cpu s" is
// the CPU time of particlemesh's render (all threads, best of reps) and "pov cpu" that of the
// whole povray process (parsing included): on a shared machine, compare those.
//
// From scratch (built with Debian's libembree-dev and libopenvdb-dev; without them this table
// is left out with a message at configure time): a new frame as a renderer meets it, the
// field (the particles' grid), the caster's hierarchy and the image, timed together, beside
// OpenVDB's ParticlesToLevelSet (spheres of radius s, voxels of s/2) + volumeToMesh, an Embree
// BVH of that mesh and one primary ray per pixel through the same camera, interleaved in the
// same run (best of reps each). "cpu r" is the ratio of the CPU times (all threads), the fair
// one on a loaded machine; "agree" the share of pixels both call surface / background alike
// (the peer's surface is a union of spheres, not the blob: a few silhouette pixels differ).
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <numbers>
#include <random>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include "particlemesh/io/png.h"
#include "particlemesh/volume/render.h"
#include "peer_embree.h"
#include "peer_openvdb.h"

using namespace particlemesh;
namespace fs = std::filesystem;

namespace {

using Clock = std::chrono::steady_clock;

// CPU seconds (user + system, all threads) of this process, or of its waited-for children.
double cpu_seconds(int who) {
  rusage ru{};
  getrusage(who, &ru);
  return double(ru.ru_utime.tv_sec + ru.ru_stime.tv_sec) + 1e-6 * double(ru.ru_utime.tv_usec + ru.ru_stime.tv_usec);
}

PointCloud dam_block(size_t n, double s) {
  const int k = std::max(1, int(std::lround(std::cbrt(double(n) / 2.0))));
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(-0.05, 0.05);
  PointCloud c;
  for (int z = 0; z < k; ++z)
    for (int y = 0; y < 2 * k; ++y)
      for (int x = 0; x < k; ++x) c.positions.push_back({(x + u(rng)) * s, (y + u(rng)) * s, (z + u(rng)) * s});
  return c;
}

bool have_povray() { return std::system("command -v povray >/dev/null 2>&1") == 0; }

struct PovResult {
  bool ok = false;
  double wall = 0, cpu = 0, parse = 0, trace = 0;
  std::string message;
};

std::string vec(const Vec3& v) {
  char buf[128];
  std::snprintf(buf, sizeof buf, "<%.9g, %.9g, %.9g>", v.x, v.y, v.z);
  return buf;
}

double seconds_in(const std::string& log, const std::string& label) {
  const std::regex re(label + R"(:\s+\d+ hours\s+\d+ minutes\s+\d+ seconds \(([0-9.]+) seconds\))");
  std::smatch m;
  return std::regex_search(log, m, re) ? std::stod(m[1]) : -1;
}

PovResult run_povray(const ParticleField& f, const Camera& cam, int w, int h, int threads, const fs::path& dir) {
  PovResult r;
  const fs::path scene = dir / "scene.pov";
  {
    std::ofstream o(scene);
    o << "#version 3.7;\nglobal_settings { assumed_gamma 1.0 }\n";
    // POV-Ray is left-handed: a negative `right` makes the camera right-handed like ours.
    const double aspect = double(w) / double(h);
    const double hfov = 2 * std::atan(std::tan(0.5 * cam.fov_degrees * std::numbers::pi / 180) * aspect) * 180 /
                        std::numbers::pi;
    o << "camera { perspective location " << vec(cam.eye) << " sky " << vec(cam.up) << " right <" << -aspect
      << ", 0, 0> up <0, 1, 0> angle " << hfov << " look_at " << vec(cam.target) << " }\n";
    const Vec3 fwd = normalized(cam.target - cam.eye), right = normalized(cross(fwd, cam.up)),
               up = cross(right, fwd);
    const Vec3 light = cam.target + (fwd * -1.0 + up * 0.7 - right * 0.5) * (10 * norm(cam.eye - cam.target));
    o << "light_source { " << vec(light) << " color rgb 1 parallel point_at " << vec(cam.target)
      << " shadowless }\n";
    o << "background { color rgb <0.93, 0.94, 0.96> }\n";
    o << "blob { threshold " << std::setprecision(17) << f.threshold() << "\n";
    char buf[160];
    for (uint32_t k = 0; k < uint32_t(f.size()); ++k) {
      const size_t i = f.grid().original_index(k);
      const Vec3& p = f.grid().sorted_point(k);
      std::snprintf(buf, sizeof buf, "sphere { <%.9g, %.9g, %.9g>, %.9g, %.9g }\n", p.x, p.y, p.z, f.radius(i),
                    f.strength(i));
      o << buf;
    }
    o << "pigment { color rgb <0.85, 0.70, 0.52> } finish { ambient 0.18 diffuse 0.82 } }\n";
  }
  char cmd[1024];
  std::snprintf(cmd, sizeof cmd,
                "cd '%s' && timeout 900 povray +Iscene.pov +Opov.png +FN +W%d +H%d -D -A +WT%d -GR -GW "
                "> pov.log 2>&1",
                dir.c_str(), w, h, threads);
  const auto t0 = Clock::now();
  const double c0 = cpu_seconds(RUSAGE_CHILDREN);
  const int rc = std::system(cmd);
  r.wall = std::chrono::duration<double>(Clock::now() - t0).count();
  r.cpu = cpu_seconds(RUSAGE_CHILDREN) - c0;
  std::ifstream lf(dir / "pov.log");
  const std::string log((std::istreambuf_iterator<char>(lf)), std::istreambuf_iterator<char>());
  if (rc != 0) {
    r.message = "povray failed (status " + std::to_string(rc) + "), see " + (dir / "pov.log").string();
    return r;
  }
  r.parse = seconds_in(log, "Parse Time") + std::max(0.0, seconds_in(log, "Bounding Time"));
  r.trace = seconds_in(log, "Trace Time");
  r.ok = true;
  return r;
}

bool is_background(const uint8_t* p) {
  // Background (0.93, 0.94, 0.96) encoded with gamma 2.2 by both renderers, +-3 levels.
  const int want[3] = {247, 247, 251};
  for (int c = 0; c < 3; ++c)
    if (std::abs(int(p[c]) - want[c]) > 3) return false;
  return true;
}

}  // namespace

int main(int argc, char** argv) {
  std::vector<size_t> sizes{1000, 10000, 100000};
  int threads = 2, reps = 2, width = 640, height = 480;
  bool pov = true;
  std::string keep;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto next = [&] { return i + 1 < argc ? std::string(argv[++i]) : std::string(); };
    if (a == "--sizes") {
      sizes.clear();
      std::stringstream ss(next());
      for (std::string t; std::getline(ss, t, ',');) sizes.push_back(std::stoul(t));
    } else if (a == "--threads") {
      threads = std::stoi(next());
    } else if (a == "--reps") {
      reps = std::stoi(next());
    } else if (a == "--width") {
      width = std::stoi(next());
    } else if (a == "--height") {
      height = std::stoi(next());
    } else if (a == "--no-povray") {
      pov = false;
    } else if (a == "--keep") {
      keep = next();
    } else {
      std::fprintf(stderr, "unknown argument %s\n", a.c_str());
      return 2;
    }
  }
  if (pov && !have_povray()) {
    std::printf("POV-Ray not found (Debian package povray): benchmarking particlemesh alone\n");
    pov = false;
  }
  const double s = 0.02;
  const double rays = double(width) * double(height);
  const bool embree = peer::embree_available() && peer::openvdb_available();
  std::printf("%d x %d pixels, %d threads, best of %d; Poly4 kernel = POV-Ray blob density, R = 2s\n", width,
              height, threads, reps);
  double load[3] = {0, 0, 0};
  getloadavg(load, 3);
  std::printf("load average %.2f at start\n\n", load[0]);
  if (embree)
    std::printf("%9s | %8s %8s | %8s %8s %8s %8s %8s | %6s %6s | %5s\n", "particles", "pm s", "pm cpu", "vdb+emb",
                "peer cpu", "vdb mesh", "bvh", "rays", "ratio", "cpu r", "agree");
  std::vector<std::string> from_scratch_rows;
  std::printf("%9s | %8s %9s %8s %12s %12s %6s | %9s %9s %8s %12s %12s | %6s\n", "particles", "build s",
              "render s", "cpu s", "rays/s poly4", "rays/s wyvil", "hit %", "pov parse", "pov trace", "pov cpu",
              "rays/s trace", "rays/s total", "agree");
  for (size_t n : sizes) {
    const PointCloud c = dam_block(n, s);
    FieldParams p;
    p.kernel = Kernel::Poly4;
    p.radius = 2 * s;
    // From scratch, as a renderer of a new frame runs it: the field (grid of the particles),
    // the ray hierarchy and the image; the OpenVDB + Embree peer interleaved, the same camera.
    if (embree) {
      double best_pm = 1e300, pm_cpu = 1e300, best_peer = 1e300, peer_cpu = 1e300, vdb_s = 0, bvh_s = 0, rays_s = 0;
      double agree = -1;
      for (int r = 0; r < reps; ++r) {
        const auto t0 = Clock::now();
        const double c0 = cpu_seconds(RUSAGE_SELF);
        const RayCaster fresh(ParticleField(c, p, threads));
        RenderOptions fo;
        fo.width = width;
        fo.height = height;
        fo.threads = threads;
        const RenderResult img = render(fresh, fo);
        const double pm = std::chrono::duration<double>(Clock::now() - t0).count();
        pm_cpu = std::min(pm_cpu, cpu_seconds(RUSAGE_SELF) - c0);
        best_pm = std::min(best_pm, pm);
        const Camera& cam = img.camera;
        const Vec3 fwd = normalized(cam.target - cam.eye), right = normalized(cross(fwd, cam.up)),
                   up = cross(right, fwd);
        const double tv = std::tan(0.5 * cam.fov_degrees * std::numbers::pi / 180.0);
        const double pc0 = cpu_seconds(RUSAGE_SELF);
        const peer::VdbMesh mesh = peer::openvdb_particles_mesh(c.positions, s, s / 2);
        const peer::EmbreeResult e = peer::embree_primary_rays(mesh.points, mesh.triangles, cam.eye, fwd, right, up,
                                                               tv, tv * width / height, width, height, threads);
        peer_cpu = std::min(peer_cpu, cpu_seconds(RUSAGE_SELF) - pc0);
        const double total = mesh.seconds + e.build_seconds + e.trace_seconds;
        if (total < best_peer) {
          best_peer = total;
          vdb_s = mesh.seconds;
          bvh_s = e.build_seconds;
          rays_s = e.trace_seconds;
        }
        size_t same = 0;
        for (int y = 0; y < height; ++y)
          for (int x = 0; x < width; ++x)
            same += (!is_background(img.image.pixel(x, y))) == (e.hit[size_t(y) * size_t(width) + size_t(x)] != 0);
        agree = 100.0 * double(same) / rays;
      }
      char line[256];
      std::snprintf(line, sizeof line, "%9zu | %8.3f %8.3f | %8.3f %8.3f %8.3f %8.3f %8.3f | %6.2f %6.2f | %4.1f%%",
                    c.size(), best_pm, pm_cpu, best_peer, peer_cpu, vdb_s, bvh_s, rays_s, best_pm / best_peer,
                    pm_cpu / peer_cpu, agree);
      from_scratch_rows.push_back(line);
      std::printf("%s\n", line);
      std::fflush(stdout);
    }
    const auto tb = Clock::now();
    const RayCaster caster(ParticleField(c, p, threads));
    const double build = std::chrono::duration<double>(Clock::now() - tb).count();
    RenderOptions ro;
    ro.width = width;
    ro.height = height;
    ro.threads = threads;
    ro.camera = default_camera(caster.field(), double(width) / double(height));
    RenderResult best;
    best.seconds = 1e300;
    double cpu = 1e300;
    for (int r = 0; r < reps; ++r) {
      const double c0 = cpu_seconds(RUSAGE_SELF);
      RenderResult x = render(caster, ro);
      cpu = std::min(cpu, cpu_seconds(RUSAGE_SELF) - c0);
      if (x.seconds < best.seconds) best = std::move(x);
    }
    FieldParams pw = p;
    pw.kernel = Kernel::Wyvill;
    pw.threshold = 0;  // its own default
    const RayCaster wy(ParticleField(c, pw, threads));
    double wsec = 1e300;
    for (int r = 0; r < reps; ++r) wsec = std::min(wsec, render(wy, ro).seconds);
    std::printf("%9zu | %8.3f %9.3f %8.3f %12.0f %12.0f %5.1f%% |", c.size(), build, best.seconds, cpu,
                rays / best.seconds, rays / wsec, 100.0 * double(best.hits) / rays);
    if (!pov) {
      std::printf(" %9s %9s %8s %12s %12s | %6s\n", "-", "-", "-", "-", "-", "-");
      continue;
    }
    const fs::path dir = keep.empty() ? fs::temp_directory_path() / ("pm_raycast_bench_" + std::to_string(getpid()))
                                      : fs::path(keep) / std::to_string(n);
    fs::create_directories(dir);
    PovResult pr;
    for (int r = 0; r < reps; ++r) {
      PovResult x = run_povray(caster.field(), *ro.camera, width, height, threads, dir);
      if (!x.ok) {
        pr = x;
        break;
      }
      if (!pr.ok || x.wall < pr.wall) pr = x;
    }
    if (!pr.ok) {
      std::printf(" %s\n", pr.message.c_str());
      continue;
    }
    double agree = -1;
    try {
      const Image pi = read_png((dir / "pov.png").string());
      size_t same = 0;
      for (int y = 0; y < height; ++y)
        for (int x = 0; x < width; ++x)
          same += is_background(pi.pixel(x, y)) == is_background(best.image.pixel(x, y));
      agree = 100.0 * double(same) / rays;
      if (!keep.empty()) write_png(best.image, (dir / "particlemesh.png").string());
    } catch (const Error& e) {
      std::fprintf(stderr, "cannot compare images: %s\n", e.what());
    }
    std::printf(" %9.3f %9.3f %8.3f %12.0f %12.0f | %5.1f%%\n", pr.parse, pr.trace, pr.cpu, rays / pr.trace,
                rays / pr.wall, agree);
    if (keep.empty()) fs::remove_all(dir);
    std::fflush(stdout);
  }
  if (!from_scratch_rows.empty()) {
    getloadavg(load, 3);
    std::printf("\nFrom scratch (field + hierarchy + image) beside OpenVDB (spheres of radius s, voxel s/2) + "
                "Embree BVH + primary rays; load %.2f at the end:\n", load[0]);
    std::printf("%9s | %8s %8s | %8s %8s %8s %8s %8s | %6s %6s | %5s\n", "particles", "pm s", "pm cpu", "vdb+emb",
                "peer cpu", "vdb mesh", "bvh", "rays", "ratio", "cpu r", "agree");
    for (const auto& r : from_scratch_rows) std::printf("%s\n", r.c_str());
  }
  return 0;
}
