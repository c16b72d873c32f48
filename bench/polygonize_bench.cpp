// Polygonization of volume particles beside OpenVDB's particle meshing pipeline
// (tools::ParticlesToLevelSet + tools::volumeToMesh), on the same particles, same grid
// resolution, same run. Prints a table; numbers and machine go to bench/RESULTS.md.
//
//   build/bench/polygonize_bench [--sizes 10000,100000,1000000] [--threads N] [--reps R]
//                                [--no-openvdb] [--sph DIR]
//   build/bench/polygonize_bench --anisotropic [--sizes ...] [--frames A.ply,B.ply] [--reps R]
//
// --anisotropic: anisotropic kernels beside spherical ones instead of OpenVDB: the library's
// defaults both ways (PolygonizeOptions{} and the same with anisotropy.enabled), on the blocks
// and on the given particle files (.ply; bench/bgeo_to_ply.py converts Houdini .bgeo frames),
// each pair measured interleaved, with the ratio of the times.
//
// Input: a dam-break-like block: k x 2k x k particles on a simple cubic lattice of spacing
// s = 0.02 with every coordinate jittered by up to +-5 % of s (fixed seed), k = cbrt(N / 2).
// particlemesh: default kernel (Wyvill), R = 2s, cell h = s/2, default threshold.
// OpenVDB: voxel size s/2, narrow band 3 voxels, every particle a sphere of radius s (the
// smallest radius at which the spheres of a lattice of spacing s fill its volume is
// s sqrt(3)/2), iso-value 0, adaptivity 0.
// --sph DIR: the three SPH frames of ../shared/data/particles (particle radius r = 0.025,
// rest spacing 2r) with splashsurf's parameters mapped to ours (R = 4r, h = r/2,
// T = 0.6 x lattice_field(4r, 2r)), and OpenVDB with spheres of radius 2r, voxel r/2.
//
// Each measurement runs in a child process forked from the parent that generated the
// particles: time = wall clock of the call (best of R), cpu = that run's CPU time (all
// threads: on a shared machine the steadier figure), memory = the child's peak resident
// set (getrusage) minus its resident set just before the call (input paged in), so each
// pipeline's peak is measured alone.
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <functional>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include <tbb/global_control.h>

#include "particlemesh/io/mesh_io.h"
#include "particlemesh/mesh/topology_report.h"
#include "particlemesh/volume/polygonize.h"
#include "peer_openvdb.h"

using namespace particlemesh;

namespace {

struct Measure {
  double seconds = 0;
  double cpu_seconds = 0;  // user + system time of the call, all threads (--anisotropic only)
  double peak_mib = 0;
  uint64_t vertices = 0, triangles = 0;
  int closed = -1;  // 1 / 0 when checked, -1 when not
  bool ok = false;
};

double rss_mib() {
  std::ifstream f("/proc/self/statm");
  long pages = 0, resident = 0;
  f >> pages >> resident;
  return double(resident) * double(sysconf(_SC_PAGESIZE)) / (1024.0 * 1024.0);
}

double cpu_seconds() {
  rusage ru{};
  getrusage(RUSAGE_SELF, &ru);
  return double(ru.ru_utime.tv_sec + ru.ru_stime.tv_sec) + 1e-6 * double(ru.ru_utime.tv_usec + ru.ru_stime.tv_usec);
}

// Run `body` in a forked child: returns what it measured (time and peak memory of the call;
// its CPU time, all threads, unless the body measured that itself).
Measure in_child(int threads, const std::function<void(Measure&)>& body) {
  int fd[2];
  if (pipe(fd) != 0) return {};
  const pid_t pid = fork();
  if (pid == 0) {
    close(fd[0]);
    Measure m;
    {
      std::unique_ptr<tbb::global_control> limit;
      if (threads > 0)
        limit = std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism, threads);
      const double before = rss_mib();
      const double cpu0 = cpu_seconds();
      body(m);
      if (m.cpu_seconds == 0) m.cpu_seconds = cpu_seconds() - cpu0;
      rusage ru{};
      getrusage(RUSAGE_SELF, &ru);
      m.peak_mib = double(ru.ru_maxrss) / 1024.0 - before;
      m.ok = true;
    }
    if (write(fd[1], &m, sizeof m) != ssize_t(sizeof m)) _exit(2);
    _exit(0);
  }
  close(fd[1]);
  Measure m;
  if (read(fd[0], &m, sizeof m) != ssize_t(sizeof m)) m.ok = false;
  close(fd[0]);
  int status = 0;
  waitpid(pid, &status, 0);
  return m;
}

double now_since(std::chrono::steady_clock::time_point t) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t).count();
}

PointCloud dam_block(size_t n, double s) {
  const int k = std::max(1, int(std::lround(std::cbrt(double(n) / 2.0))));
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(-0.05, 0.05);
  PointCloud c;
  c.positions.reserve(size_t(k) * 2 * k * k);
  for (int z = 0; z < k; ++z)
    for (int y = 0; y < 2 * k; ++y)
      for (int x = 0; x < k; ++x) c.positions.push_back({(x + u(rng)) * s, (y + u(rng)) * s, (z + u(rng)) * s});
  return c;
}

void touch(const PointCloud& c) {
  volatile double sum = 0;
  for (const Vec3& p : c.positions) sum = sum + p.x;
}

Measure best_of(int reps, int threads, const std::function<void(Measure&)>& body) {
  Measure best;
  for (int r = 0; r < reps; ++r) {
    const Measure m = in_child(threads, body);
    if (!m.ok) return m;
    if (!best.ok || m.seconds < best.seconds) {
      const double peak = std::max(best.peak_mib, m.peak_mib);
      best = m;
      best.peak_mib = peak;
    } else {
      best.peak_mib = std::max(best.peak_mib, m.peak_mib);
    }
  }
  return best;
}

void row(const char* input, size_t n, const char* method, const Measure& m) {
  if (!m.ok) {
    std::printf("| %-28s | %9zu | %-34s | failed |\n", input, n, method);
    return;
  }
  std::printf("| %-28s | %9zu | %-34s | %8.3f | %8.3f | %8.1f | %9llu | %9llu | %-6s |\n", input, n, method, m.seconds,
              m.cpu_seconds, m.peak_mib, (unsigned long long)m.vertices, (unsigned long long)m.triangles,
              m.closed < 0 ? "-" : (m.closed ? "yes" : "NO"));
  std::fflush(stdout);
}

std::vector<size_t> parse_sizes(const std::string& s) {
  std::vector<size_t> out;
  std::stringstream ss(s);
  std::string item;
  while (std::getline(ss, item, ',')) out.push_back(size_t(std::stoull(item)));
  return out;
}


// Spherical and anisotropic kernels at the library's defaults on the same particles, measured
// interleaved (iso, aniso, iso, aniso, ...) so that a change in the machine's load hits both.
Measure polygonize_defaults(const PointCloud& c, bool anisotropic, int threads, PolygonizeStats* stats) {
  return in_child(threads, [&](Measure& m) {
    PolygonizeOptions o;
    o.threads = threads;
    o.anisotropy.enabled = anisotropic;
    const double cpu0 = cpu_seconds();
    const auto t0 = std::chrono::steady_clock::now();
    const PolygonizeResult r = polygonize(c, o);
    m.seconds = now_since(t0);
    m.cpu_seconds = cpu_seconds() - cpu0;
    m.vertices = r.mesh.positions.size();
    m.triangles = r.mesh.triangles.size();
    if (c.size() <= 200000) m.closed = topology_report(r.mesh).closed;
    if (stats) *stats = r.stats;  // (in the child: only the timing split below is printed from it)
    std::printf("|   %s: setup %.3f s, sampling %.3f s, meshing %.3f s\n", anisotropic ? "anisotropic" : "spherical  ",
                r.stats.seconds_setup, r.stats.seconds_sampling, r.stats.seconds_meshing);
    std::fflush(stdout);
  });
}

void compare(const char* input, const PointCloud& c, int threads, int reps) {
  Measure iso, an;
  double iso_cpu = 1e300, an_cpu = 1e300;
  for (int r = 0; r < reps; ++r) {
    const Measure a = polygonize_defaults(c, false, threads, nullptr);
    const Measure b = polygonize_defaults(c, true, threads, nullptr);
    if (a.ok && (!iso.ok || a.seconds < iso.seconds)) iso = a;
    if (b.ok && (!an.ok || b.seconds < an.seconds)) an = b;
    if (a.ok) iso_cpu = std::min(iso_cpu, a.cpu_seconds);
    if (b.ok) an_cpu = std::min(an_cpu, b.cpu_seconds);
  }
  row(input, c.size(), "polygonize, spherical (default)", iso);
  row(input, c.size(), "polygonize --anisotropic", an);
  if (iso.ok && an.ok)
    std::printf("|   -> anisotropic / spherical: wall %.2fx (%.3f / %.3f s), CPU %.2fx (%.3f / %.3f s)\n",
                an.seconds / iso.seconds, an.seconds, iso.seconds, an_cpu / iso_cpu, an_cpu, iso_cpu);
  std::fflush(stdout);
}

int anisotropic_bench(const std::vector<size_t>& sizes, const std::vector<std::string>& frames, int threads, int reps) {
  std::printf("polygonize_bench --anisotropic: %ld hardware threads, using %s, best of %d\n",
              sysconf(_SC_NPROCESSORS_ONLN), threads > 0 ? (std::to_string(threads) + " threads").c_str() : "all",
              reps);
  std::printf("| %-28s | %9s | %-34s | %8s | %8s | %8s | %9s | %9s | %-6s |\n", "input", "particles", "method", "time s",
              "cpu s", "peak MiB", "vertices", "triangles", "closed");
  std::fflush(stdout);  // before the children fork: they would print the buffer again
  for (const std::string& f : frames) {
    PointCloud c;
    try {
      c = read_point_cloud(f);
    } catch (const std::exception& e) {
      std::printf("| %s: %s\n", f.c_str(), e.what());
      continue;
    }
    touch(c);
    std::string name = f.substr(f.find_last_of('/') + 1);
    name = name.substr(0, name.find("_particles"));
    compare(name.c_str(), c, threads, reps);
  }
  for (size_t n : sizes) {
    const PointCloud c = dam_block(n, 0.02);
    touch(c);
    compare("dam-break block", c, threads, reps);
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  std::vector<size_t> sizes = {10000, 100000, 1000000};
  int threads = 0, reps = 3;
  bool vdb = peer::openvdb_available();
  std::string sph;
  bool aniso = false;
  std::vector<std::string> frames;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto next = [&]() -> std::string {
      if (i + 1 >= argc) {
        std::fprintf(stderr, "%s needs a value\n", a.c_str());
        std::exit(2);
      }
      return argv[++i];
    };
    if (a == "--sizes") sizes = parse_sizes(next());
    else if (a == "--threads") threads = std::stoi(next());
    else if (a == "--reps") reps = std::max(1, std::stoi(next()));
    else if (a == "--no-openvdb") vdb = false;
    else if (a == "--sph") sph = next();
    else if (a == "--anisotropic") aniso = true;
    else if (a == "--frames") {
      std::stringstream ss(next());
      std::string item;
      while (std::getline(ss, item, ',')) frames.push_back(item);
    } else {
      std::fprintf(stderr,
                   "usage: polygonize_bench [--sizes N,N,...] [--threads N] [--reps R] [--no-openvdb] [--sph DIR]\n"
                   "       polygonize_bench --anisotropic [--sizes N,N,...] [--frames A.ply,B.ply] [--threads N] "
                   "[--reps R]\n");
      return 2;
    }
  }
  if (aniso) return anisotropic_bench(sizes, frames, threads, reps);
  std::printf("polygonize_bench: %ld hardware threads, using %s, best of %d\n", sysconf(_SC_NPROCESSORS_ONLN),
              threads > 0 ? (std::to_string(threads) + " threads").c_str() : "all", reps);
  if (!peer::openvdb_available()) std::printf("(built without OpenVDB: peer column absent)\n");
  std::printf("| %-28s | %9s | %-34s | %8s | %8s | %8s | %9s | %9s | %-6s |\n", "input", "particles", "method", "time s",
              "cpu s", "peak MiB", "vertices", "triangles", "closed");
  std::printf("|%s|%s|%s|%s|%s|%s|%s|%s|%s|\n", std::string(30, '-').c_str(), std::string(11, '-').c_str(),
              std::string(36, '-').c_str(), std::string(10, '-').c_str(), std::string(10, '-').c_str(),
              std::string(10, '-').c_str(), std::string(11, '-').c_str(), std::string(11, '-').c_str(),
              std::string(8, '-').c_str());

  const double s = 0.02;
  for (size_t n : sizes) {
    const PointCloud c = dam_block(n, s);
    touch(c);
    const Measure ours = best_of(reps, threads, [&](Measure& m) {
      PolygonizeOptions o;
      o.radius = 2 * s;
      o.cell_size = s / 2;
      o.threads = threads;
      const auto t0 = std::chrono::steady_clock::now();
      const PolygonizeResult r = polygonize(c, o);
      m.seconds = now_since(t0);
      m.vertices = r.mesh.positions.size();
      m.triangles = r.mesh.triangles.size();
      if (c.size() <= 200000) m.closed = topology_report(r.mesh).closed;
    });
    row("dam-break block", c.size(), "particlemesh polygonize", ours);
    if (vdb) {
      const Measure peer = best_of(reps, threads, [&](Measure& m) {
        const peer::VdbResult r = peer::openvdb_particles_to_mesh(c.positions, s, s / 2);
        m.seconds = r.seconds;
        m.vertices = r.vertices;
        m.triangles = r.triangles;
      });
      row("dam-break block", c.size(), "OpenVDB ParticlesToLevelSet+VolToMesh", peer);
      if (ours.ok && peer.ok)
        std::printf("|   -> particlemesh / OpenVDB: time %.3f (%.1fx faster), CPU %.3f, peak memory %.2f\n",
                    ours.seconds / peer.seconds, peer.seconds / ours.seconds,
                    ours.cpu_seconds / std::max(peer.cpu_seconds, 1e-9), ours.peak_mib / std::max(peer.peak_mib, 1e-9));
    }
  }

  if (!sph.empty()) {
    // splashsurf's parameters for these frames (particle radius r = 0.025): compact support 4r,
    // cube size r/2, iso 0.6 of the rest density -> T = 0.6 x lattice_field(4r, rest spacing 2r).
    const double r = 0.025;
    for (const char* name : {"double_dam_break_frame_26_4732_particles.ply", "bunny_frame_14_7705_particles.ply",
                             "cube_2366_particles.ply"}) {
      const std::string path = sph + "/" + name;
      PointCloud c;
      try {
        c = read_point_cloud(path);
      } catch (const std::exception& e) {
        std::printf("| %s: %s\n", name, e.what());
        continue;
      }
      touch(c);
      const Measure ours = best_of(reps, threads, [&](Measure& m) {
        PolygonizeOptions o;
        o.radius = 4 * r;
        o.cell_size = 0.5 * r;
        o.threshold = 0.6 * lattice_field(Kernel::Wyvill, 4 * r, 2 * r);
        o.threads = threads;
        const auto t0 = std::chrono::steady_clock::now();
        const PolygonizeResult res = polygonize(c, o);
        m.seconds = now_since(t0);
        m.vertices = res.mesh.positions.size();
        m.triangles = res.mesh.triangles.size();
        m.closed = topology_report(res.mesh).closed;
      });
      std::string shortname(name);
      shortname = shortname.substr(0, shortname.find("_particles"));
      row(shortname.c_str(), c.size(), "particlemesh (splashsurf params)", ours);
      if (vdb) {
        const Measure peer = best_of(reps, threads, [&](Measure& m) {
          // Spheres of the rest spacing 2r (as for the block: radius = spacing), voxel r/2.
          const peer::VdbResult res = peer::openvdb_particles_to_mesh(c.positions, 2 * r, 0.5 * r);
          m.seconds = res.seconds;
          m.vertices = res.vertices;
          m.triangles = res.triangles;
        });
        row(shortname.c_str(), c.size(), "OpenVDB (spheres 2r, voxel r/2)", peer);
      }
    }
  }
  return 0;
}
