// The surface pipeline's neighbour searches timed one at a time, and the whole pipeline, on a
// sphere of evenly spaced (Fibonacci) or random points: for changes that keep every output the
// same and move one search by a few per cent, which a whole run through the command-line tool
// (its reading, writing and page faults, its two threads) hides in its noise. On one thread
// (taskset -c 0, or --threads 1) a part's median over a few runs varies by about 1 %.
//
//   surface_stages_bench [--points N] [--reps R] [--threads T] [--random] [--part NAME]...
//
// Parts (all by default): estimate (the spacing estimate, as reconstruct_surface's twin check
// takes it), local-spacing (each point's spacing: its grid, the 16 nearest, the plane fits),
// knn (the 16 nearest alone, on the local spacing's grid of 2 r0), lists (the triangle test's
// neighbour lists at an even sampling's radius, 2L / sqrt(3) with L = 2 r0), surface
// (reconstruct_surface with its defaults). Prints the median and the least of R runs per part.
// The library's private searches are linked from its own object files, as the tests do.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <random>
#include <string>
#include <vector>

#include "core/parallel.h"
#include "core/progress_tracker.h"
#include "particlemesh/sample/shapes.h"
#include "particlemesh/spatial/neighbor_grid.h"
#include "particlemesh/surface/reconstruct.h"
#include "spatial/grid_search.h"
#include "spatial/local_spacing_impl.h"
#include "spatial/nearest_neighbors.h"
#include "spatial/spacing_impl.h"
#include "surface/neighbor_lists.h"

using namespace particlemesh;

namespace {

[[noreturn]] void usage(const char* why) {
  std::fprintf(stderr,
               "surface_stages_bench: %s\nusage: surface_stages_bench [--points N] [--reps R] [--threads T] "
               "[--random] [--part estimate|local-spacing|knn|lists|surface]...\n",
               why);
  std::exit(2);
}

// Points on the unit sphere, uniformly at random (a fixed seed).
std::vector<Vec3> random_sphere(size_t n) {
  std::mt19937_64 rng(7);
  std::normal_distribution<double> g;
  std::vector<Vec3> p(n);
  for (Vec3& x : p) {
    do x = {g(rng), g(rng), g(rng)};
    while (!(squared_norm(x) > 1e-12));
    x = normalized(x);
  }
  return p;
}

}  // namespace

int main(int argc, char** argv) {
  size_t n = 1000000;
  int reps = 5, threads = 1;
  bool random = false;
  std::vector<std::string> parts;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    const auto value = [&] {
      if (i + 1 >= argc) usage(("missing value after " + a).c_str());
      return std::string(argv[++i]);
    };
    if (a == "--points") n = size_t(std::stoull(value()));
    else if (a == "--reps") reps = std::stoi(value());
    else if (a == "--threads") threads = std::stoi(value());
    else if (a == "--random") random = true;
    else if (a == "--part") parts.push_back(value());
    else usage(("unknown argument " + a).c_str());
  }
  if (n < 100 || reps < 1 || threads < 0) usage("need --points >= 100, --reps >= 1, --threads >= 0");
  if (parts.empty()) parts = {"estimate", "local-spacing", "knn", "lists", "surface"};
  for (const std::string& p : parts)
    if (p != "estimate" && p != "local-spacing" && p != "knn" && p != "lists" && p != "surface")
      usage(("unknown part " + p).c_str());

  const std::vector<Vec3> points = random ? random_sphere(n) : fibonacci_sphere(n).positions;
  const ProgressCallback none;
  detail::ProgressTracker tracker(none);
  std::printf("%zu %s points on the unit sphere, %d thread(s), %d runs per part\n", n,
              random ? "random" : "Fibonacci", threads, reps);
  detail::with_threads(threads, [&] {
    const double r0 = detail::estimate_spacing_impl(points.data(), n, tracker, 0, 1).spacing;
    const NeighborGrid spacing_grid(points.data(), n, 2 * r0);
    const double radius = 2 * r0 * (2.0 / std::sqrt(3.0)) * (1.0 + 1e-6);
    const NeighborGrid list_grid(points.data(), n, radius);
    const std::vector<uint32_t> rep = detail::find_duplicates(list_grid, nullptr);
    for (const std::string& part : parts) {
      std::vector<double> seconds;
      size_t size = 0;  // of the part's result, printed so that no run is optimised away
      for (int r = 0; r < reps; ++r) {
        const auto t0 = std::chrono::steady_clock::now();
        if (part == "estimate") {
          std::vector<uint32_t> twins;
          size += size_t(detail::estimate_spacing_impl(points.data(), n, tracker, 0, 1, 1, &twins).distinct_points);
        } else if (part == "local-spacing") {
          size += detail::local_spacing_impl(points.data(), n, r0, tracker, 0, 1, nullptr).size();
        } else if (part == "knn") {
          size += detail::nearest_neighbors(spacing_grid, 16, tracker).size();
        } else if (part == "lists") {
          size += detail::build_neighbor_lists(list_grid, rep, radius, 100000, tracker).index.size();
        } else {
          PointCloud cloud;
          cloud.positions = points;
          SurfaceOptions o;
          o.threads = threads;
          size += reconstruct_surface(cloud, o).mesh.triangles.size();
        }
        seconds.push_back(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
      }
      std::sort(seconds.begin(), seconds.end());
      std::printf("%-14s median %.4f s  least %.4f s  (%zu)\n", part.c_str(), seconds[seconds.size() / 2], seconds[0],
                  size / size_t(reps));
    }
    return 0;
  });
}
