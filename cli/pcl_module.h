// The interface of the CLI's PCL module (pcl_module.cpp, a shared module next to the CLI):
// what particle_input.cpp calls when the input is a .pcd file, PCL preprocessing is asked for,
// or --pcl-mesh is given. Loaded with dlopen on first use (pcl_module()).
#pragma once

#include <string>

#include "particle_input.h"

namespace particlemesh::cli {

struct PclModule {
  static constexpr int kVersion = 1;
  int version;
  /// Read `path` (.pcd, .ply, .xyz) through the bridge and preprocess as asked.
  ParticleInput (*read)(const std::string& path, const ParticleInputArgs& args, int threads);
  /// Write `mesh` as a pcl::PolygonMesh PLY at `path` (atomically).
  void (*write_mesh)(const TriMesh& mesh, const std::string& path);
};

}  // namespace particlemesh::cli
