// Reading mesh files: particlemesh's readers (one pass, exact doubles) beside the readers of
// the libraries people use for them, on the same files in the same run: OpenMesh's IO
// (float32, into its half-edge mesh: what particlemesh used before its own readers) and, when
// the PCL bridge is built, pcl::io::loadPLYFile (into a pcl::PolygonMesh).
//
//   build/bench/read_bench [POINTS]     (default 1000000; files go to a temporary folder)
//
// Prints a Markdown table: the best of 3 reads of each file by each reader.
#include <OpenMesh/Core/IO/MeshIO.hh>
#include <OpenMesh/Core/Mesh/TriMesh_ArrayKernelT.hh>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <string>

#ifdef PM_BENCH_WITH_PCL
#include <pcl/PolygonMesh.h>
#include <pcl/io/ply_io.h>
#endif

#include "particlemesh/io/mesh_io.h"
#include "particlemesh/sample/shapes.h"
#include "particlemesh/surface/reconstruct.h"

namespace fs = std::filesystem;
using namespace particlemesh;

namespace {

double best_of_3(const std::function<size_t()>& read, size_t* triangles) {
  double best = 1e30;
  for (int r = 0; r < 3; ++r) {
    const auto t0 = std::chrono::steady_clock::now();
    *triangles = read();
    best = std::min(best, std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
  }
  return best;
}

}  // namespace

int main(int argc, char** argv) {
  const size_t points = argc > 1 ? std::stoul(argv[1]) : 1000000;
  const fs::path dir = fs::temp_directory_path() / ("pm_read_bench_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  const TriMesh mesh = reconstruct_surface(fibonacci_sphere(points)).mesh;
  struct File {
    std::string name;
    WriteMeshOptions options;
  };
  const File files[] = {{"mesh.ply", {MeshFormat::PlyBinary, true}},
                        {"mesh_ascii.ply", {MeshFormat::PlyAscii, true}},
                        {"mesh.obj", {MeshFormat::Obj, true}}};
  std::printf("%zu vertices, %zu triangles (a Fibonacci sphere's surface, with normals)\n\n", mesh.positions.size(),
              mesh.triangles.size());
  std::printf("| file | size | particlemesh::read_mesh | OpenMesh::IO::read_mesh | pcl::io::loadPLYFile |\n");
  std::printf("|---|---|---|---|---|\n");
  for (const File& f : files) {
    const std::string path = (dir / f.name).string();
    write_mesh(mesh, path, f.options);
    size_t n = 0;
    const double ours = best_of_3([&] { return read_mesh(path).triangles.size(); }, &n);
    const bool ok_ours = n == mesh.triangles.size();
    size_t m = 0;
    const double om = best_of_3([&] {
      OpenMesh::TriMesh_ArrayKernelT<> om_mesh;
      OpenMesh::IO::Options opt = OpenMesh::IO::Options::VertexNormal;
      om_mesh.request_vertex_normals();
      if (!OpenMesh::IO::read_mesh(om_mesh, path, opt)) return size_t(0);
      return size_t(om_mesh.n_faces());
    }, &m);
    std::string pcl_cell = "-";
#ifdef PM_BENCH_WITH_PCL
    if (f.name.size() > 4 && f.name.substr(f.name.size() - 4) == ".ply") {
      size_t k = 0;
      const double t = best_of_3([&] {
        pcl::PolygonMesh pm;
        return pcl::io::loadPLYFile(path, pm) < 0 ? size_t(0) : pm.polygons.size();
      }, &k);
      char s[64];
      std::snprintf(s, sizeof s, "%.3f s%s", t, k == mesh.triangles.size() ? "" : " (wrong count)");
      pcl_cell = s;
    }
#endif
    std::printf("| %s | %.1f MB | %.3f s%s | %.3f s%s | %s |\n", f.name.c_str(), double(fs::file_size(path)) / 1e6, ours,
                ok_ours ? "" : " (wrong count)", om, m == mesh.triangles.size() ? "" : " (wrong count)", pcl_cell.c_str());
  }
  fs::remove_all(dir);
  return 0;
}
