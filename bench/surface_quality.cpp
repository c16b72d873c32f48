// Surface quality and cost table: the finished surface on synthetic and resampled real
// shapes, with and without jitter, beside the bare triangulation time.
//   build/bench/surface_quality [--data ../shared/data] [--big] [--filter NAME]
// Expected topology per shape is printed next to what came out.
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <functional>
#include <random>
#include <string>
#include <vector>

#include "particlemesh/io/mesh_io.h"
#include "particlemesh/mesh/topology_report.h"
#include "particlemesh/sample/shapes.h"
#include "particlemesh/surface/reconstruct.h"

using namespace particlemesh;

namespace {

struct Case {
  std::string name;
  std::function<PointCloud()> make;
  int components;       // expected
  int genus;            // expected per component (-1: don't care)
  int boundary_loops;   // expected (-1: don't care)
};

PointCloud jitter(PointCloud c, double sigma, uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> g(0.0, sigma);
  for (auto& p : c.positions) p += Vec3{g(rng), g(rng), g(rng)};
  return c;
}

double mean_edge(const TriMesh& m) {
  double s = 0;
  for (const auto& t : m.triangles) s += distance(m.positions[t[0]], m.positions[t[1]]);
  return s / double(m.triangles.size());
}

}  // namespace

int main(int argc, char** argv) {
  std::string data = "../shared/data", filter;
  bool big = false, estimate = false;
  for (int i = 1; i < argc; ++i) {
    if (!std::strcmp(argv[i], "--data") && i + 1 < argc) data = argv[++i];
    else if (!std::strcmp(argv[i], "--big")) big = true;
    else if (!std::strcmp(argv[i], "--estimate-normals")) estimate = true;
    else if (!std::strcmp(argv[i], "--filter") && i + 1 < argc) filter = argv[++i];
  }
  std::vector<Case> cases;
  auto add_mesh = [&](const std::string& name, const std::string& file, double r0_over_edge, int genus, int loops) {
    const std::string path = data + "/" + file;
    if (!std::filesystem::exists(path)) return;
    auto make = [path, r0_over_edge] {
      const TriMesh m = read_mesh(path);
      return poisson_disk_sample(m, r0_over_edge * mean_edge(m), 7);
    };
    cases.push_back({name, make, 1, genus, loops});
    cases.push_back({name + "+jitter", [make] {
                       PointCloud c = make();
                       double r0 = 0;  // jitter of 0.1 r0, r0 from the sample itself
                       TriangulateOptions o;
                       r0 = triangulate_raw(c, o).stats.spacing;
                       return jitter(c, 0.1 * r0, 3);
                     }, 1, genus, loops});
  };
  cases.push_back({"sphere-10k", [] { return fibonacci_sphere(10000); }, 1, 0, 0});
  cases.push_back({"sphere-poisson", [] { return poisson_disk_sample(icosphere_mesh(6), 0.02, 1); }, 1, 0, 0});
  cases.push_back({"sphere-poisson+jitter", [] { return jitter(poisson_disk_sample(icosphere_mesh(6), 0.02, 1), 0.1 * 0.021, 2); }, 1, 0, 0});
  cases.push_back({"torus", [] { return poisson_disk_sample(torus_mesh(1.0, 0.35, 200, 80), 0.03, 1); }, 1, 1, 0});
  cases.push_back({"thin-torus", [] { return poisson_disk_sample(torus_mesh(1.0, 0.08, 400, 40), 0.025, 1); }, 1, 1, 0});
  cases.push_back({"trefoil", [] { return poisson_disk_sample(trefoil_tube_mesh(1.0, 0.35, 720, 64), 0.05, 1); }, 1, 1, 0});
  cases.push_back({"two-spheres-gap", [] {
                     PointCloud a = poisson_disk_sample(icosphere_mesh(5), 0.05, 1);
                     PointCloud b = poisson_disk_sample(icosphere_mesh(5), 0.05, 2);
                     for (auto& p : b.positions) a.positions.push_back(p + Vec3{2.06, 0, 0});
                     a.normals.insert(a.normals.end(), b.normals.begin(), b.normals.end());
                     return a;
                   }, 2, 0, 0});
  // Sharp creases and corners (machined parts): a box (90 degrees), a cone (a 63-degree rim
  // and an apex), prisms whose sides meet at 75 / 52.5 / 52.5 and 60 degrees.
  auto add_sharp = [&](const std::string& name, std::function<TriMesh()> mesh, double r0) {
    cases.push_back({name, [mesh, r0] { return poisson_disk_sample(mesh(), r0, 3); }, 1, 0, 0});
    cases.push_back({name + "+jitter", [mesh, r0] { return jitter(poisson_disk_sample(mesh(), r0, 3), 0.1 * r0, 5); }, 1, 0, 0});
  };
  add_sharp("box", [] { return box_mesh({1, 1, 1}); }, 0.02);
  add_sharp("cone", [] { return cone_mesh(0.5, 1.0, 256); }, 0.02);
  add_sharp("prism-75", [] { return prism_mesh(75); }, 0.02);
  add_sharp("prism-60", [] { return prism_mesh(60); }, 0.02);
  add_mesh("spot", "meshes/spot.obj", 0.45, 0, 0);
  add_mesh("bunny-coarse", "meshes/bunny_coarse.ply", 0.3, 0, 0);
  add_mesh("rocker-arm", "meshes/rocker_arm.obj", 1.0, 1, 0);
  add_mesh("bunny-open", "meshes/bunny.obj", 1.5, 0, 5);
  if (big) cases.push_back({"sphere-1M", [] { return fibonacci_sphere(1000000); }, 1, 0, 0});
  if (big) cases.push_back({"sphere-100k", [] { return fibonacci_sphere(100000); }, 1, 0, 0});

  std::printf("| shape | N | raw s | surface s | F | comp | closed | chi | genus | loops | nm-e | nm-v | confl | outward | unused | filled | left (largest) | ok |\n");
  std::printf("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n");
  int failures = 0;
  for (const Case& c : cases) {
    if (!filter.empty() && c.name.find(filter) == std::string::npos) continue;
    const PointCloud cloud = c.make();
    SurfaceOptions o;
    o.normals = estimate ? SurfaceOptions::NormalSource::Estimate : SurfaceOptions::NormalSource::Auto;
    if (std::getenv("PM_INPUT_NORMALS")) o.normals = SurfaceOptions::NormalSource::Input;
    if (const char* f = std::getenv("PM_FILL_FACTOR")) o.fill_edge_factor = std::atof(f);
    if (const char* a = std::getenv("PM_NORMAL_ANGLE")) o.normal_angle = std::atof(a);
    auto t0 = std::chrono::steady_clock::now();
    const TriangulateResult raw = triangulate_raw(cloud, o);
    const double traw = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    t0 = std::chrono::steady_clock::now();
    const SurfaceResult s = reconstruct_surface(cloud, o);
    const double tsurf = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    const TopologyReport r = topology_report(s.mesh);
    std::string genus;
    bool genus_ok = true;
    for (const auto& pc : r.per_component) {
      genus += (genus.empty() ? "" : ",") + std::to_string(pc.genus);
      if (c.genus >= 0 && pc.genus != c.genus) genus_ok = false;
    }
    const bool ok = int(r.components) == c.components && genus_ok && r.nonmanifold_edges == 0 &&
                    r.nonmanifold_vertices == 0 && r.orientation_conflicts == 0 &&
                    (c.boundary_loops < 0 || int(r.boundary_loops) == c.boundary_loops) &&
                    s.surface.unused_points == 0 && (c.boundary_loops != 0 || r.outward);
    failures += !ok;
    std::printf("| %s | %zu | %.3f | %.3f | %zu | %zu | %zu | %lld | %s | %zu | %zu | %zu | %zu | %s | %zu | %zu | %zu (%zu) | %s |\n",
                c.name.c_str(), cloud.size(), traw, tsurf, r.triangles, r.components, r.closed_components,
                (long long)r.euler_characteristic, genus.c_str(), r.boundary_loops, r.nonmanifold_edges,
                r.nonmanifold_vertices, r.orientation_conflicts, r.outward ? "yes" : "no", s.surface.unused_points,
                s.surface.holes_filled, s.surface.holes_left, s.surface.largest_hole_left, ok ? "yes" : "NO");
    std::fflush(stdout);
  }
  return failures == 0 ? 0 : 1;
}
