// Real scans: particlemesh's finished surface beside CGAL's advancing front and PCL's greedy
// projection, on the clouds a PCL user brings (depth-camera frames, turntable and range scans),
// prepared as such a user would.
//
//   scan_bench [shared/data folder] [--scan FILE.pcd|.ply]... [--runs N] [--write-prepared DIR]
//              [--no-peers] [--no-gp3] [--as-is] [--write-meshes DIR] [--viewpoint]
//
// Without --scan it runs the scans of the shared data (pcd/bun0, milk, the Kinect frame,
// colored_cloud; bunny.pcd holds bun0's points and the *_binary files re-encode others, so
// they are not run twice). Preparation, per scan:
//   remove NaN points -> pcl::VoxelGrid, leaf = 1.5 x the median nearest-neighbour distance of
//   the raw finite cloud -> pcl::StatisticalOutlierRemoval (meanK 20, stddev 2)
//   r0 = the prepared cloud's median nearest-neighbour distance; every method gets it.
// Methods (each timed as the best of --runs, default 3, all on the prepared points):
//   particlemesh   reconstruct_surface, default options (its spacing estimate is r0; all cores)
//   CGAL AF        CGAL::advancing_front_surface_reconstruction, default parameters (one core:
//                  CGAL's Delaunay triangulation is sequential); its metrics also with its
//                  triangles longer than 6 r0 cut, as they bridge depth jumps
//   PCL GP3        pcl::GreedyProjectionTriangulation with the parameters of PCL's tutorial
//                  (mu 2.5, 100 neighbours, 45 deg surface angle, 10..120 deg angles), search
//                  radius 4.16 r0 (the tutorial's 0.025 on bun0), normals by NormalEstimation
//                  with k = 20 (their time is included)
// --as-is skips the preparation (the finite points as they are, r0 their median nearest-neighbour
// distance): an evenly sampled cloud, e.g. a 1M-point sphere, meshed by each method as given.
// --no-gp3 leaves PCL's greedy projection out (CGAL's advancing front still runs).
// --viewpoint adds particlemesh given the file's sensor origin (PCD VIEWPOINT), where it is
// taken (SurfaceOptions::viewpoint). Printed per scan and method: small holes (boundary loops of fewer than 10 edges), all
// boundary loops, the pieces (connected components; in brackets those closed), the share of
// the prepared points in a triangle, the longest triangle edge
// / r0 and how many triangles have an edge over 6 r0, non-manifold edges, orientation
// conflicts, and the time; then the sums. A Markdown table (bench/RESULTS.md).
#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include <pcl/common/io.h>
#include <pcl/features/normal_3d.h>
#include <pcl/filters/filter.h>
#include <pcl/filters/statistical_outlier_removal.h>
#include <pcl/filters/voxel_grid.h>
#include <pcl/io/pcd_io.h>
#include <pcl/io/ply_io.h>
#include <pcl/point_types.h>
#include <pcl/search/kdtree.h>
#include <pcl/surface/gp3.h>

#ifdef PM_BENCH_WITH_CGAL
#include <CGAL/Advancing_front_surface_reconstruction.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#endif

#include "particlemesh/io/mesh_io.h"
#include "particlemesh/mesh/topology_report.h"
#include "particlemesh/spatial/spacing.h"
#include "particlemesh/surface/reconstruct.h"
#include "particlemesh_pcl/io.h"

namespace {

using Clock = std::chrono::steady_clock;
using XYZ = pcl::PointCloud<pcl::PointXYZ>;
constexpr int kMethods = 5;

double seconds_since(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }

/// The best wall time of `runs` calls; each call's wall and process CPU time (user + system,
/// all threads: on a loaded machine the fairer figure) to stderr, labelled `what`.
double best_of(int runs, const std::function<void()>& f, const char* what = "") {
  double best = 1e300;
  for (int i = 0; i < runs; ++i) {
    const auto t = Clock::now();
    const std::clock_t c = std::clock();
    f();
    const double wall = seconds_since(t);
    std::fprintf(stderr, "%s: wall %.3f s, CPU %.3f s\n", what, wall, double(std::clock() - c) / CLOCKS_PER_SEC);
    best = std::min(best, wall);
  }
  return best;
}

std::vector<particlemesh::Vec3> positions_of(const XYZ& c) {
  std::vector<particlemesh::Vec3> p;
  p.reserve(c.size());
  for (const auto& q : c) p.push_back({q.x, q.y, q.z});
  return p;
}

/// The median nearest-neighbour distance, of the cloud apart from near copies (a twinned
/// scan's first and last returns: particlemesh sets them aside, and their offset is no r0).
double median_nn(const XYZ& c) {
  const auto p = positions_of(c);
  return particlemesh::estimate_spacing(p.data(), p.size()).spacing_apart;
}

struct Scan {
  std::string name;
  size_t raw_points = 0;   ///< finite points read
  double raw_r0 = 0;       ///< their median NN distance
  XYZ::Ptr prepared{new XYZ};
  double r0 = 0;           ///< the prepared cloud's median NN distance
  particlemesh::Vec3 origin;  ///< the file's sensor origin (PCD VIEWPOINT)
};

/// Any file the PCL bridge reads as particles: a .pcd checked, then read by PCL (its sensor
/// origin with it), anything else through particlemesh's readers (.ply, .xyz, a mesh's
/// vertices from .obj / .off / .stl, VTK, ...). Invalid (NaN) points are dropped there.
XYZ::Ptr read_scan(const std::string& path) {
  particlemesh_pcl::LoadReport report;
  const particlemesh::PointCloud cloud = particlemesh_pcl::loadParticles(path, &report);
  XYZ::Ptr c(new XYZ);
  c->reserve(cloud.size());
  for (const particlemesh::Vec3& p : cloud.positions) c->push_back(pcl::PointXYZ(float(p.x), float(p.y), float(p.z)));
  c->sensor_origin_ = Eigen::Vector4f(report.origin[0], report.origin[1], report.origin[2], 0);
  return c;
}

Scan prepare(const std::string& name, const XYZ& input, bool as_is) {
  Scan s;
  s.name = name;
  s.origin = {input.sensor_origin_.x(), input.sensor_origin_.y(), input.sensor_origin_.z()};
  XYZ::Ptr finite(new XYZ);
  std::vector<int> kept;
  pcl::removeNaNFromPointCloud(input, *finite, kept);
  s.raw_points = finite->size();
  s.raw_r0 = median_nn(*finite);
  if (as_is) {
    s.prepared = finite;
    s.r0 = s.raw_r0;
    return s;
  }
  XYZ::Ptr voxel(new XYZ);
  pcl::VoxelGrid<pcl::PointXYZ> vg;
  vg.setInputCloud(finite);
  const float leaf = float(1.5 * s.raw_r0);
  vg.setLeafSize(leaf, leaf, leaf);
  vg.filter(*voxel);
  pcl::StatisticalOutlierRemoval<pcl::PointXYZ> sor;
  sor.setInputCloud(voxel);
  sor.setMeanK(20);
  sor.setStddevMulThresh(2.0);
  sor.filter(*s.prepared);
  s.r0 = median_nn(*s.prepared);
  return s;
}

struct Metrics {
  bool ran = false;
  double seconds = 0;
  size_t triangles = 0, small_holes = 0, loops = 0, used = 0, points = 0, over6 = 0, nonmanifold = 0, conflicts = 0, pieces = 0,
         closed_pieces = 0;
  double longest = 0;  ///< in r0
};

Metrics measure(const std::vector<particlemesh::Vec3>& P, const std::vector<particlemesh::Triangle>& tris, double r0,
                double seconds) {
  Metrics m;
  m.ran = true;
  m.seconds = seconds;
  particlemesh::TriMesh mesh;
  mesh.positions = P;
  mesh.triangles = tris;
  for (const auto& t : tris) {
    double longest = 0;
    for (int k = 0; k < 3; ++k) longest = std::max(longest, particlemesh::distance(P[t[k]], P[t[(k + 1) % 3]]));
    m.longest = std::max(m.longest, longest / r0);
    m.over6 += longest > 6 * r0;
  }
  const particlemesh::TopologyReport r = particlemesh::topology_report(mesh);
  m.triangles = r.triangles;
  m.points = P.size();
  m.used = r.vertices_used;
  m.loops = r.boundary_loops;
  m.pieces = r.components;
  m.closed_pieces = r.closed_components;
  for (size_t e : r.boundary_loop_edges) m.small_holes += e < 10;
  m.nonmanifold = r.nonmanifold_edges;
  m.conflicts = r.orientation_conflicts;
  return m;
}

/// The triangles with no edge over `limit`.
std::vector<particlemesh::Triangle> cut(const std::vector<particlemesh::Vec3>& P,
                                        const std::vector<particlemesh::Triangle>& tris, double limit) {
  std::vector<particlemesh::Triangle> out;
  for (const auto& t : tris) {
    bool ok = true;
    for (int k = 0; k < 3; ++k) ok = ok && particlemesh::distance(P[t[k]], P[t[(k + 1) % 3]]) <= limit;
    if (ok) out.push_back(t);
  }
  return out;
}

void row(const Scan& s, const char* method, const Metrics& m) {
  if (!m.ran) return;
  std::printf("| %s | %zu | %s | %zu | %zu | %zu (%zu) | %.2f %% | %.1f | %zu | %zu | %zu | %.3f |\n", s.name.c_str(),
              s.prepared->size(), method, m.small_holes, m.loops, m.pieces, m.closed_pieces,
              100.0 * double(m.used) / double(m.points), m.longest, m.over6, m.nonmanifold, m.conflicts, m.seconds);
}

void write_mesh(const std::string& dir, const std::string& name, const std::vector<particlemesh::Vec3>& P,
                const std::vector<particlemesh::Triangle>& tris) {
  if (dir.empty()) return;
  particlemesh::TriMesh m;
  m.positions = P;
  m.triangles = tris;
  particlemesh::write_mesh(m, dir + "/" + name + ".ply");
}

}  // namespace

int main(int argc, char** argv) {
  std::string data = "../shared/data", prepared_dir, meshes_dir;
  std::vector<std::string> scans;
  int runs = 3;
  bool peers = true, gp3_too = true, viewpoint = false, as_is = false;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--scan" && i + 1 < argc) scans.push_back(argv[++i]);
    else if (a == "--runs" && i + 1 < argc) runs = std::max(1, std::atoi(argv[++i]));
    else if (a == "--write-prepared" && i + 1 < argc) prepared_dir = argv[++i];
    else if (a == "--write-meshes" && i + 1 < argc) meshes_dir = argv[++i];
    else if (a == "--no-peers") peers = false;
    else if (a == "--no-gp3") gp3_too = false;
    else if (a == "--as-is") as_is = true;
    else if (a == "--viewpoint") viewpoint = true;
    else if (!a.empty() && a[0] != '-') data = a;
    else {
      std::fprintf(stderr, "usage: scan_bench [data folder] [--scan FILE]... [--runs N] [--write-prepared DIR] "
                           "[--write-meshes DIR] [--no-peers] [--no-gp3] [--as-is] [--viewpoint]\n");
      return 2;
    }
  }
  if (scans.empty())
    for (const char* rel : {"pcd/bun0.pcd", "pcd/milk.pcd", "pcd/kinect_frame_20121214T142255.814212.pcd",
                            "pcd/colored_cloud.pcd"}) {
      const std::string path = data + "/" + rel;
      if (std::filesystem::exists(path)) scans.push_back(path);
      else std::fprintf(stderr, "skipping %s (not found)\n", path.c_str());
    }
  pcl::console::setVerbosityLevel(pcl::console::L_ALWAYS);
#ifndef PM_BENCH_WITH_CGAL
  std::fprintf(stderr, "built without CGAL: the advancing front is not run\n");
#endif

  std::printf("| scan | prepared points | method | small holes (< 10 edges) | boundary loops | pieces (closed) "
              "| points in the mesh | longest edge / r0 | triangles > 6 r0 | non-manifold edges | orientation conflicts "
              "| seconds |\n");
  std::printf("|---|---|---|---|---|---|---|---|---|---|---|---|\n");
  struct Sum {
    size_t small_holes = 0;
    double worst_used = 100, longest = 0, seconds = 0;
    int scans = 0;
  } sums[kMethods];
  const char* names[kMethods] = {"particlemesh", "CGAL advancing front, > 6 r0 cut", "CGAL advancing front, uncut",
                                 "PCL greedy projection", "particlemesh, with the PCD's VIEWPOINT"};
  std::vector<std::string> notes;
  for (const std::string& path : scans) {
    const std::string name = std::filesystem::path(path).stem().string();
    XYZ::Ptr input;
    try {
      input = read_scan(path);
    } catch (const std::exception& e) {  // a file that cannot be read is skipped, as a missing one is
      std::fprintf(stderr, "skipping %s: %s\n", path.c_str(), e.what());
      continue;
    }
    Scan s = prepare(name, *input, as_is);
    char note[400];
    if (as_is)
      std::snprintf(note, sizeof note, "%s: %zu finite points, taken as they are (--as-is), r0 %.4g", name.c_str(),
                    s.raw_points, s.r0);
    else
      std::snprintf(note, sizeof note, "%s: %zu finite points, raw median NN %.4g, leaf %.4g; prepared %zu, r0 %.4g",
                    name.c_str(), s.raw_points, s.raw_r0, 1.5 * s.raw_r0, s.prepared->size(), s.r0);
    notes.push_back(note);
    if (!prepared_dir.empty()) pcl::io::savePLYFileBinary(prepared_dir + "/" + name + ".ply", *s.prepared);
    const std::vector<particlemesh::Vec3> P = positions_of(*s.prepared);
    Metrics m[kMethods];

    for (int k : {0, 4}) {
      if (k == 4 && !viewpoint) continue;
      particlemesh::PointCloud cloud;
      cloud.positions = P;
      // The defaults: the spacing estimated, which is r0 (the same estimate; a spacing given
      // would make a crowded point an error rather than a shorter edge limit).
      particlemesh::SurfaceOptions o;
      o.has_viewpoint = k == 4;
      o.viewpoint = s.origin;
      particlemesh::SurfaceResult r;
      double t = 0;
      try {
        t = best_of(runs, [&] { r = particlemesh::reconstruct_surface(cloud, o); }, "particlemesh");
      } catch (const std::exception& e) {  // the library's Error: a limit or a bad input
        std::fprintf(stderr, "%s: particlemesh failed: %s\n", name.c_str(), e.what());
        continue;
      }
      m[k] = measure(P, r.mesh.triangles, s.r0, t);
      if (k == 4 && !r.surface.viewpoint_used) m[k].ran = false;
      write_mesh(meshes_dir, name + (k == 4 ? "_particlemesh_viewpoint" : "_particlemesh"), P, r.mesh.triangles);
    }
    if (peers) {
#ifdef PM_BENCH_WITH_CGAL
      using K = CGAL::Exact_predicates_inexact_constructions_kernel;
      std::vector<K::Point_3> pts;
      for (const auto& p : P) pts.emplace_back(p.x, p.y, p.z);
      std::vector<std::array<std::size_t, 3>> facets;
      const double t = best_of(runs, [&] {
        facets.clear();
        CGAL::advancing_front_surface_reconstruction(pts.begin(), pts.end(), std::back_inserter(facets));
      }, "CGAL advancing front");
      std::vector<particlemesh::Triangle> tris;
      for (const auto& f : facets) tris.push_back({uint32_t(f[0]), uint32_t(f[1]), uint32_t(f[2])});
      const auto short_tris = cut(P, tris, 6 * s.r0);
      m[1] = measure(P, short_tris, s.r0, t);
      m[2] = measure(P, tris, s.r0, t);
      write_mesh(meshes_dir, name + "_cgal_af", P, tris);
#endif
    }
    if (peers && gp3_too) {
      pcl::PointCloud<pcl::PointNormal>::Ptr pn(new pcl::PointCloud<pcl::PointNormal>);
      std::vector<pcl::Vertices> polygons;
      const double tg = best_of(runs, [&] {
        pcl::NormalEstimation<pcl::PointXYZ, pcl::Normal> ne;
        pcl::PointCloud<pcl::Normal> normals;
        pcl::search::KdTree<pcl::PointXYZ>::Ptr tree(new pcl::search::KdTree<pcl::PointXYZ>);
        tree->setInputCloud(s.prepared);
        ne.setInputCloud(s.prepared);
        ne.setSearchMethod(tree);
        ne.setKSearch(20);
        ne.compute(normals);
        pcl::concatenateFields(*s.prepared, normals, *pn);
        pcl::search::KdTree<pcl::PointNormal>::Ptr tree2(new pcl::search::KdTree<pcl::PointNormal>);
        tree2->setInputCloud(pn);
        pcl::GreedyProjectionTriangulation<pcl::PointNormal> gp3;
        gp3.setSearchRadius(0.025 / 0.00601229 * s.r0);
        gp3.setMu(2.5);
        gp3.setMaximumNearestNeighbors(100);
        gp3.setMaximumSurfaceAngle(M_PI / 4);
        gp3.setMinimumAngle(M_PI / 18);
        gp3.setMaximumAngle(2 * M_PI / 3);
        gp3.setNormalConsistency(false);
        gp3.setInputCloud(pn);
        gp3.setSearchMethod(tree2);
        polygons.clear();
        gp3.reconstruct(polygons);
      }, "PCL greedy projection");
      std::vector<particlemesh::Triangle> gp3;
      for (const auto& p : polygons)
        if (p.vertices.size() == 3) gp3.push_back({uint32_t(p.vertices[0]), uint32_t(p.vertices[1]), uint32_t(p.vertices[2])});
      m[3] = measure(P, gp3, s.r0, tg);
      write_mesh(meshes_dir, name + "_pcl_gp3", P, gp3);
    }
    for (int k = 0; k < kMethods; ++k) {
      row(s, names[k], m[k]);
      if (!m[k].ran) continue;
      ++sums[k].scans;
      sums[k].small_holes += m[k].small_holes;
      sums[k].worst_used = std::min(sums[k].worst_used, 100.0 * double(m[k].used) / double(m[k].points));
      sums[k].longest = std::max(sums[k].longest, m[k].longest);
      sums[k].seconds += m[k].seconds;
    }
    std::fflush(stdout);
  }
  std::printf("\n| method | small holes, summed | worst share of points in the mesh | longest edge / r0 | seconds, summed |\n");
  std::printf("|---|---|---|---|---|\n");
  for (int k = 0; k < kMethods; ++k)
    if (sums[k].scans > 0)
      std::printf("| %s%s | %zu | %.2f %% | %.1f | %.3f |\n", names[k], k == 4 ? " (scans where it was taken)" : "",
                  sums[k].small_holes, sums[k].worst_used, sums[k].longest, sums[k].seconds);
  std::printf("\n");
  for (const auto& n : notes) std::printf("- %s\n", n.c_str());
  return 0;
}
