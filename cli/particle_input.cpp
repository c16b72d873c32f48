// Reading particles for the CLI (particle_input.h). .ply and .xyz without preprocessing are read
// by the core reader; .pcd files, PCL preprocessing and --pcl-mesh go through the PCL module
// (pcl_module.h), loaded only then.
#include <dlfcn.h>
#include <unistd.h>

#include <filesystem>
#include <mutex>
#include <string>

#include "commands.h"
#include "particle_input.h"
#include "particlemesh/core/error.h"
#include "particlemesh/io/mesh_io.h"
#include "pcl_module.h"

namespace particlemesh::cli {

namespace {

namespace fs = std::filesystem;

bool wants_pcl(const std::string& path, const ParticleInputArgs& a) {
  std::string ext = fs::path(path).extension().string();
  for (char& ch : ext) ch = char(std::tolower(static_cast<unsigned char>(ch)));
  return ext == ".pcd" || a.uniform_sampling > 0 || a.voxel_grid > 0 || a.remove_outliers || a.estimate_normals;
}

/// The PCL module, loaded on first use: next to the executable (the build tree), then where
/// it is installed relative to the executable, then on the library search path.
const PclModule& pcl_module(const std::string& why) {
#ifndef PM_CLI_PCL_MODULE
  throw Error(Status::InvalidArgument, why + " needs the PCL bridge (built with PM_WITH_PCL=OFF)");
#else
  static std::once_flag once;
  static const PclModule* module = nullptr;
  static std::string error;
  std::call_once(once, [] {
    const std::string name = PM_CLI_PCL_MODULE;
    std::error_code ec;
    const fs::path exe_dir = fs::read_symlink("/proc/self/exe", ec).parent_path();
    std::vector<std::string> candidates;
    if (!ec) {
      candidates.push_back((exe_dir / name).string());
      candidates.push_back((exe_dir / PM_CLI_PCL_MODULE_FROM_BINDIR / name).lexically_normal().string());
    }
    candidates.push_back(name);
    for (const std::string& c : candidates) {
      void* handle = dlopen(c.c_str(), RTLD_NOW | RTLD_LOCAL);
      if (handle == nullptr) {
        if (error.empty()) error = dlerror();
        continue;
      }
      using Entry = const PclModule* (*)();
      const auto entry = reinterpret_cast<Entry>(dlsym(handle, "particlemesh_cli_pcl_module"));
      const PclModule* m = entry ? entry() : nullptr;
      if (m != nullptr && m->version == PclModule::kVersion) {
        module = m;
        return;
      }
      error = c + " is not this version's PCL module";
    }
  });
  if (module == nullptr) throw Error(Status::IoError, why + " needs the CLI's PCL module, which did not load: " + error);
  return *module;
#endif
}

}  // namespace

#ifdef PM_CLI_PCL_MODULE
void add_particle_input_options(CLI::App& app, ParticleInputArgs& a) {
  const char* group = "Input preprocessing (PCL; off by default)";
  auto* us = app.add_option("--uniform-sampling", a.uniform_sampling,
                            "Downsample with pcl::UniformSampling to this spacing (voxel edge, world units; also r0 unless --spacing)")
                 ->check(CLI::PositiveNumber)
                 ->check(finite_number())
                 ->group(group);
  auto* vg = app.add_option("--voxel-grid", a.voxel_grid,
                            "Downsample with pcl::VoxelGrid to this spacing (the input point nearest each voxel's centroid; also r0 unless --spacing)")
                 ->check(CLI::PositiveNumber)
                 ->check(finite_number())
                 ->group(group);
  us->excludes(vg);
  app.add_flag("--remove-outliers", a.remove_outliers,
               "Statistical outlier removal (pcl::StatisticalOutlierRemoval) before downsampling")
      ->group(group);
  app.add_option("--outlier-k", a.outlier_k, "Neighbours for the outlier statistics")
      ->check(CLI::Range(1, 100000))
      ->capture_default_str()
      ->group(group);
  app.add_option("--outlier-std", a.outlier_std, "Outlier threshold: mean + this x stddev")
      ->check(CLI::Range(0.0, 1e6))
      ->check(finite_number())
      ->capture_default_str()
      ->group(group);
  app.add_flag("--estimate-normals", a.estimate_normals,
               "Estimate normals with PCL (replacing the file's), flipped toward the viewpoint")
      ->group(group);
  app.add_option("--normal-k", a.normal_k, "Neighbours for normal estimation")
      ->check(CLI::Range(3, 100000))
      ->capture_default_str()
      ->group(group);
  app.add_option("--viewpoint", a.viewpoint, "Viewpoint X Y Z for normal orientation (default: the PCD's sensor origin)")
      ->expected(3)
      ->group(group);
  app.add_option("--pcl-mesh", a.pcl_mesh,
                 "Also write the mesh as a pcl::PolygonMesh PLY (pcl::io::savePLYFileBinary; with rgb/intensity)");
}
#else
void add_particle_input_options(CLI::App&, ParticleInputArgs&) {}
#endif

ParticleInput read_particles(const std::string& path, const ParticleInputArgs& a, int threads) {
  if (wants_pcl(path, a)) return pcl_module(path + ": .pcd input").read(path, a, threads);
  // What the bridge reports for a file it does not convert (pcl_bridge's loadParticles).
  ParticleInput in;
  in.cloud = read_point_cloud(path);
  std::string ext = fs::path(path).extension().string();
  for (char& ch : ext) ch = char(std::tolower(static_cast<unsigned char>(ch)));
  const size_t n = in.cloud.size();
  in.report = {{"format", ext.empty() ? "" : ext.substr(1)},
               {"encoding", ""},
               {"points", n},
               {"valid_points", n},
               {"invalid_points", 0},
               {"invalid_normals", 0},
               {"organized", false},
               {"width", uint32_t(n)},
               {"height", 1},
               {"has_normals", in.cloud.has_normals()},
               {"has_color", false},
               {"has_intensity", false}};
  return in;
}

void write_pcl_mesh(const TriMesh& mesh, const ParticleInputArgs& a) {
  if (a.pcl_mesh.empty()) return;
  pcl_module("--pcl-mesh").write_mesh(mesh, a.pcl_mesh);
}

}  // namespace particlemesh::cli
