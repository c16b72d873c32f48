// `particlemesh smooth` as a user runs it (the whole CLI process: start, read, Loop to the
// limit, write; with its summary also the topology report of the result, taken while the mesh
// is written; with -q and no --report none) beside bare OpenSubdiv refinement of the same mesh
// in the same run: Far::TopologyRefinerFactory + RefineUniform + PrimvarRefiner::Interpolate
// of the positions level by level, nothing else (no checks, no limit, no normals, no I/O).
// Prints a table; numbers and machine go to bench/RESULTS.md.
//
//   build/bench/smooth_cli_bench [--cli build/cli/particlemesh] [--points 41000] [--levels 2]
//                                [--reps 7] [--threads N]
//
// Input: the finished surface of a Fibonacci sphere of `points` particles (82k triangles for
// 41 000), written once as binary PLY. The three (-q, with the summary, bare) are run in turn,
// `reps` times each; the table gives medians. The CLI's summary goes to /dev/null. CLI time:
// wall clock of fork + exec + wait; its CPU time from wait4.
#include <fcntl.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <filesystem>
#include <string>
#include <vector>

#include <opensubdiv/far/primvarRefiner.h>
#include <opensubdiv/far/topologyDescriptor.h>
#include <opensubdiv/far/topologyRefinerFactory.h>
#include <tbb/global_control.h>

#include "particlemesh/io/mesh_io.h"
#include "particlemesh/sample/shapes.h"
#include "particlemesh/surface/reconstruct.h"

using namespace particlemesh;
namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

namespace {

struct Point3 {
  double p[3];
  void Clear() { p[0] = p[1] = p[2] = 0; }
  void AddWithWeight(const Point3& s, double w) {
    p[0] += w * s.p[0];
    p[1] += w * s.p[1];
    p[2] += w * s.p[2];
  }
};

double thread_cpu_seconds() {
  timespec t{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return double(t.tv_sec) + 1e-9 * double(t.tv_nsec);
}

/// Bare OpenSubdiv (one thread, as Far refines): the refined positions of `levels` Loop
/// levels. Returns wall seconds; its CPU seconds in *cpu.
double bare_opensubdiv(const TriMesh& m, int levels, size_t* out_points, double* cpu) {
  using namespace OpenSubdiv;
  const auto t0 = Clock::now();
  const double c0 = thread_cpu_seconds();
  const int nf = int(m.triangles.size());
  std::vector<int> counts(size_t(nf), 3), verts(3 * size_t(nf));
  for (size_t f = 0; f < size_t(nf); ++f)
    for (int c = 0; c < 3; ++c) verts[3 * f + size_t(c)] = int(m.triangles[f][size_t(c)]);
  Far::TopologyDescriptor desc;
  desc.numVertices = int(m.positions.size());
  desc.numFaces = nf;
  desc.numVertsPerFace = counts.data();
  desc.vertIndicesPerFace = verts.data();
  using Factory = Far::TopologyRefinerFactory<Far::TopologyDescriptor>;
  std::unique_ptr<Far::TopologyRefiner> refiner(
      Factory::Create(desc, Factory::Options(Sdc::SCHEME_LOOP, Sdc::Options())));
  refiner->RefineUniform(Far::TopologyRefiner::UniformOptions(levels));
  std::vector<Point3> src(m.positions.size()), dst;
  for (size_t i = 0; i < src.size(); ++i) src[i] = {{m.positions[i].x, m.positions[i].y, m.positions[i].z}};
  Far::PrimvarRefinerReal<double> primvar(*refiner);
  for (int l = 1; l <= levels; ++l) {
    dst.resize(size_t(refiner->GetLevel(l).GetNumVertices()));
    const Point3* s = src.data();
    Point3* d = dst.data();
    primvar.Interpolate(l, s, d);
    src.swap(dst);
  }
  *out_points = src.size();
  *cpu = thread_cpu_seconds() - c0;
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

struct Run {
  double wall = 0, cpu = 0;
  bool ok = false;
};

Run run_cli(const std::vector<std::string>& args) {
  Run r;
  const auto t0 = Clock::now();
  const pid_t pid = fork();
  if (pid == 0) {
    const int null = open("/dev/null", O_WRONLY);
    if (null >= 0) dup2(null, STDOUT_FILENO);
    std::vector<char*> argv;
    for (const auto& a : args) argv.push_back(const_cast<char*>(a.c_str()));
    argv.push_back(nullptr);
    execv(argv[0], argv.data());
    _exit(127);
  }
  int status = 0;
  rusage ru{};
  wait4(pid, &status, 0, &ru);
  r.wall = std::chrono::duration<double>(Clock::now() - t0).count();
  r.cpu = double(ru.ru_utime.tv_sec + ru.ru_stime.tv_sec) + 1e-6 * double(ru.ru_utime.tv_usec + ru.ru_stime.tv_usec);
  r.ok = WIFEXITED(status) && WEXITSTATUS(status) == 0;
  return r;
}

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v.empty() ? 0 : (v.size() % 2 ? v[v.size() / 2] : 0.5 * (v[v.size() / 2 - 1] + v[v.size() / 2]));
}

}  // namespace

int main(int argc, char** argv) {
  std::string cli = (fs::path(argv[0]).parent_path() / ".." / "cli" / "particlemesh").lexically_normal().string();
  size_t points = 41000;
  int levels = 2, reps = 7, threads = 0;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto next = [&] { return i + 1 < argc ? std::string(argv[++i]) : std::string(); };
    if (a == "--cli") cli = next();
    else if (a == "--points") points = size_t(std::stoul(next()));
    else if (a == "--levels") levels = std::stoi(next());
    else if (a == "--reps") reps = std::max(1, std::stoi(next()));
    else if (a == "--threads") threads = std::stoi(next());
    else {
      std::fprintf(stderr, "usage: smooth_cli_bench [--cli PATH] [--points N] [--levels K] [--reps R] [--threads N]\n");
      return 2;
    }
  }
  std::unique_ptr<tbb::global_control> limit;
  if (threads > 0) limit = std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism, threads);
  const fs::path dir = fs::temp_directory_path() / ("pm_smooth_cli_bench_" + std::to_string(getpid()));
  fs::create_directories(dir);
  const std::string in = (dir / "sphere.ply").string(), out = (dir / "smooth.ply").string();
  const TriMesh sphere = reconstruct_surface(fibonacci_sphere(points)).mesh;
  write_mesh(sphere, in);
  double load[3] = {0, 0, 0};
  getloadavg(load, 3);
  std::printf("smooth_cli_bench: %zu triangles, Loop level %d, %ld hardware threads, %d reps, load %.2f at start\n",
              sphere.triangles.size(), levels, sysconf(_SC_NPROCESSORS_ONLN), reps, load[0]);
  std::printf("CLI: %s smooth IN -o OUT --levels %d -q%s\n", cli.c_str(), levels,
              threads > 0 ? (" --threads " + std::to_string(threads)).c_str() : "");
  std::fflush(stdout);
  std::vector<double> cli_wall, cli_cpu, sum_wall, sum_cpu, bare, bare_cpu;
  size_t refined = 0;
  for (int r = 0; r < reps; ++r) {
    for (const bool quiet : {true, false}) {
      std::vector<std::string> args{cli, "smooth", in, "-o", out, "--levels", std::to_string(levels)};
      if (quiet) args.push_back("-q");
      if (threads > 0) {
        args.push_back("--threads");
        args.push_back(std::to_string(threads));
      }
      const Run c = run_cli(args);
      if (!c.ok) {
        std::printf("the CLI failed\n");
        return 1;
      }
      (quiet ? cli_wall : sum_wall).push_back(c.wall);
      (quiet ? cli_cpu : sum_cpu).push_back(c.cpu);
    }
    double cpu = 0;
    bare.push_back(bare_opensubdiv(sphere, levels, &refined, &cpu));
    bare_cpu.push_back(cpu);
  }
  getloadavg(load, 3);
  const TriMesh result = read_mesh(out);
  std::printf("| what | median s | all runs s |\n|---|---|---|\n");
  auto row = [](const char* what, const std::vector<double>& v) {
    std::printf("| %s | %.3f |", what, median(v));
    for (double x : v) std::printf(" %.3f", x);
    std::printf(" |\n");
  };
  row("particlemesh smooth -q (CLI, whole process, wall)", cli_wall);
  row("particlemesh smooth -q (CLI, whole process, CPU of all threads)", cli_cpu);
  row("particlemesh smooth, summary with topology report (wall)", sum_wall);
  row("particlemesh smooth, summary with topology report (CPU of all threads)", sum_cpu);
  row("bare OpenSubdiv refinement (wall, in process)", bare);
  row("bare OpenSubdiv refinement (CPU)", bare_cpu);
  std::printf("-> CLI / bare OpenSubdiv: -q %.2fx (CPU %.2fx), with the summary %.2fx (CPU %.2fx) (medians); output %zu vertices, %zu triangles; bare %zu points; "
              "load %.2f at the end\n",
              median(cli_wall) / median(bare), median(cli_cpu) / median(bare_cpu), median(sum_wall) / median(bare),
              median(sum_cpu) / median(bare_cpu), result.positions.size(), result.triangles.size(), refined, load[0]);
  fs::remove_all(dir);
  return 0;
}
