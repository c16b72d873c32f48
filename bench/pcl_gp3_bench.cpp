// particlemesh_pcl::ParticleTriangulation beside pcl::GreedyProjectionTriangulation, on the
// same clouds in one run: time, and the mesh's faults by topology_report (non-manifold edges,
// boundary loops = holes and openings, orientation conflicts = flipped faces).
//
//   pcl_gp3_bench [shared/data folder] [--quick]
//
// Greedy projection runs with the parameters of PCL's "Fast triangulation of unordered point
// clouds" tutorial (mu 2.5, 100 nearest neighbours, max surface angle 45 deg, angles 10..120
// deg, no normal consistency, normals by NormalEstimation with k = 20), and its search radius
// scaled to each cloud: the tutorial's 0.025 on bun0.pcd is 4.16 x that cloud's median
// nearest-neighbour distance r0, so every cloud gets 4.16 x its own r0.
// Prints a Markdown table (bench/RESULTS.md).
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <functional>
#include <string>
#include <type_traits>
#include <vector>

#include <pcl/features/normal_3d.h>
#include <pcl/io/pcd_io.h>
#include <pcl/point_types.h>
#include <pcl/search/kdtree.h>
#include <pcl/surface/gp3.h>

#include "particlemesh/io/mesh_io.h"
#include "particlemesh/mesh/topology_report.h"
#include "particlemesh/sample/shapes.h"
#include "particlemesh/spatial/spacing.h"
#include "particlemesh_pcl/io.h"
#include "particlemesh_pcl/particle_triangulation.h"
#include "particlemesh_pcl/preprocessing.h"

namespace {

using Clock = std::chrono::steady_clock;
using Cloud = pcl::PointCloud<pcl::PointNormal>;

struct Input {
  std::string name;
  Cloud::Ptr cloud;                            // the tutorial's PointNormal cloud
  pcl::PointCloud<pcl::PointXYZ>::Ptr xyz;     // the same points without normals
  double r0 = 0;                               // median nearest-neighbour distance
  double spacing = 0;                          // r0 given to ParticleTriangulation (0 = estimate)
};

double seconds_since(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }

// Best of `runs` wall times of f.
double best_of(int runs, const std::function<void()>& f) {
  double best = 1e300;
  for (int i = 0; i < runs; ++i) {
    const auto t = Clock::now();
    f();
    best = std::min(best, seconds_since(t));
  }
  return best;
}

Input make_input(const std::string& name, const particlemesh::PointCloud& pts) {
  Input in;
  in.name = name;
  in.cloud.reset(new Cloud);
  in.xyz.reset(new pcl::PointCloud<pcl::PointXYZ>);
  for (const auto& p : pts.positions) {
    in.xyz->push_back(pcl::PointXYZ(float(p.x), float(p.y), float(p.z)));
    pcl::PointNormal q;
    q.x = float(p.x), q.y = float(p.y), q.z = float(p.z);
    q.normal_x = q.normal_y = q.normal_z = q.curvature = 0;
    in.cloud->push_back(q);
  }
  std::vector<particlemesh::Vec3> f;
  for (const auto& q : *in.cloud) f.push_back({q.x, q.y, q.z});
  in.r0 = particlemesh::estimate_spacing(f.data(), f.size()).spacing;
  return in;
}

// The tutorial's normal estimation: k = 20, written into the PointNormal cloud.
double estimate_normals(Cloud& cloud) {
  const auto t = Clock::now();
  pcl::PointCloud<pcl::PointXYZ>::Ptr xyz(new pcl::PointCloud<pcl::PointXYZ>);
  for (const auto& p : cloud) xyz->push_back({p.x, p.y, p.z});
  pcl::NormalEstimation<pcl::PointXYZ, pcl::Normal> n;
  pcl::PointCloud<pcl::Normal> normals;
  pcl::search::KdTree<pcl::PointXYZ>::Ptr tree(new pcl::search::KdTree<pcl::PointXYZ>);
  tree->setInputCloud(xyz);
  n.setInputCloud(xyz);
  n.setSearchMethod(tree);
  n.setKSearch(20);
  n.compute(normals);
  for (size_t i = 0; i < cloud.size(); ++i) {
    cloud[i].normal_x = normals[i].normal_x;
    cloud[i].normal_y = normals[i].normal_y;
    cloud[i].normal_z = normals[i].normal_z;
    cloud[i].curvature = normals[i].curvature;
  }
  return seconds_since(t);
}

particlemesh::TopologyReport report_of(const Cloud& cloud, const std::vector<pcl::Vertices>& polygons) {
  particlemesh::TriMesh m;
  for (const auto& p : cloud) m.positions.push_back({p.x, p.y, p.z});
  for (const auto& p : polygons)
    m.triangles.push_back({uint32_t(p.vertices[0]), uint32_t(p.vertices[1]), uint32_t(p.vertices[2])});
  return particlemesh::topology_report(m);
}

void row(const std::string& cloud, size_t n, const char* method, const std::string& t,
         const particlemesh::TopologyReport& r) {
  std::printf("| %s | %zu | %s | %s | %zu | %zu | %zu | %zu | %zu | %zu |\n", cloud.c_str(), n, method,
              t.c_str(), r.triangles, r.vertices_used, r.nonmanifold_edges, r.boundary_loops, r.orientation_conflicts,
              r.components);
}

}  // namespace

int main(int argc, char** argv) {
  std::string data = "../shared/data";
  bool quick = false;
  for (int i = 1; i < argc; ++i) {
    if (std::strcmp(argv[i], "--quick") == 0)
      quick = true;
    else
      data = argv[i];
  }
  pcl::console::setVerbosityLevel(pcl::console::L_ALWAYS);
  const int runs = quick ? 1 : 3;

  std::vector<Input> inputs;
  auto pcd = [&](const std::string& rel, bool preprocess) {
    const std::string path = data + "/" + rel;
    if (!std::filesystem::exists(path)) {
      std::fprintf(stderr, "skipping %s (not found)\n", path.c_str());
      return;
    }
    particlemesh::PointCloud pts = particlemesh_pcl::loadParticles(path);
    std::string name = std::filesystem::path(rel).filename().string();
    if (preprocess) {
      particlemesh_pcl::PreprocessOptions o;
      o.remove_outliers = true;
      o.downsampling = particlemesh_pcl::Downsampling::UniformSampling;
      o.leaf_size = 0.005;
      particlemesh_pcl::preprocess(pts, o);
      name += " (outliers removed, uniform 5 mm)";
    }
    inputs.push_back(make_input(name, pts));
    if (preprocess) inputs.back().spacing = 0.005;  // the leaf is r0, as ParticleTriangulation does itself
  };
  pcd("pcd/bun0.pcd", false);
  pcd("pcd/milk.pcd", false);
  pcd("pcd/kinect_frame_20121214T142255.814212.pcd", true);
  if (!quick) pcd("pcd/kinect_frame_20121214T142255.814212.pcd", false);
  for (const char* rel : {"points/bunny_poisson.ply", "points/spot_poisson.ply"}) {
    const std::string path = data + "/" + rel;
    if (std::filesystem::exists(path)) inputs.push_back(make_input(rel, particlemesh::read_point_cloud(path)));
  }
  const size_t fib = quick ? 20000 : 100000;
  inputs.push_back(make_input("fibonacci sphere " + std::to_string(fib / 1000) + "k", particlemesh::fibonacci_sphere(fib)));

  std::printf("| cloud | points | method | seconds | triangles | vertices used | non-manifold edges | "
              "boundary loops (holes) | orientation conflicts (flipped) | components |\n");
  std::printf("|---|---|---|---|---|---|---|---|---|---|\n");
  for (Input& in : inputs) {
    const double t_normals = estimate_normals(*in.cloud);
    const size_t n = in.cloud->size();

    // pcl::GreedyProjectionTriangulation, tutorial parameters, radius 4.16 r0.
    std::vector<pcl::Vertices> gp3_polygons;
    const double t_gp3 = best_of(runs, [&] {
      pcl::search::KdTree<pcl::PointNormal>::Ptr tree2(new pcl::search::KdTree<pcl::PointNormal>);
      tree2->setInputCloud(in.cloud);
      pcl::GreedyProjectionTriangulation<pcl::PointNormal> gp3;
      gp3.setSearchRadius(0.025 / 0.00601229 * in.r0);
      gp3.setMu(2.5);
      gp3.setMaximumNearestNeighbors(100);
      gp3.setMaximumSurfaceAngle(M_PI / 4);
      gp3.setMinimumAngle(M_PI / 18);
      gp3.setMaximumAngle(2 * M_PI / 3);
      gp3.setNormalConsistency(false);
      gp3.setInputCloud(in.cloud);
      gp3.setSearchMethod(tree2);
      gp3.reconstruct(gp3_polygons);
    });
    char t[64];
    std::snprintf(t, sizeof t, "%.3f (+ %.3f normals)", t_gp3, t_normals);
    row(in.name, n, "PCL GreedyProjectionTriangulation", t, report_of(*in.cloud, gp3_polygons));

    // particlemesh: dropped into the tutorial's code (the same PointNormal cloud, PCL's
    // normals), and on the bare points (it needs no normals). All cores; 1 thread beside.
    auto ours = [&](auto cloud, const char* method) {
      using PointT = typename std::decay_t<decltype(*cloud)>::PointType;
      std::vector<pcl::Vertices> polygons;
      double t[2];
      for (unsigned threads : {0u, 1u}) {
        particlemesh_pcl::ParticleTriangulation<PointT> pt;
        pt.setNumberOfThreads(threads);
        pt.setSpacing(in.spacing);
        t[threads] = best_of(runs, [&] {
          pt.setInputCloud(cloud);
          pt.reconstruct(polygons);
        });
        if (!pt.getReport().ok) std::fprintf(stderr, "%s: %s\n", in.name.c_str(), pt.getReport().error.c_str());
      }
      char ts[64];
      std::snprintf(ts, sizeof ts, "%.3f (1 thread: %.3f)", t[0], t[1]);
      row(in.name, n, method, ts, report_of(*in.cloud, polygons));
    };
    ours(in.cloud, "particlemesh ParticleTriangulation, same PointNormal cloud");
    ours(in.xyz, "particlemesh ParticleTriangulation, PointXYZ (own normals)");
    std::fflush(stdout);
  }
  return 0;
}
