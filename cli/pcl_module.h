// The interface of the CLI's two PCL modules (shared modules installed beside the library):
// what particle_input.cpp calls when the input is a .pcd file, PCL preprocessing is asked for,
// or --pcl-mesh is given. The PCD module (pcd_module.cpp) reads and writes through PCL's io
// library alone; the PCL module (pcl_module.cpp) also preprocesses, with PCL's features,
// filters and surface libraries. The CLI loads the one a run needs with dlopen on first use
// only: PCL and what it brings (VTK, Boost, ...) cost tens of milliseconds of dynamic linking
// at start, which every other run would pay.
#pragma once

#include <string>

#include "particle_input.h"

namespace particlemesh::cli {

struct PclModule {
  /// Changes whenever this struct or the types it passes change: a module from another build
  /// is refused, not called.
  static constexpr int kVersion = 2;
  int version;
  /// Read `path` (.pcd, .ply, .xyz) through the bridge and preprocess as asked (the PCD
  /// module is only called without preprocessing).
  ParticleInput (*read)(const std::string& path, const ParticleInputArgs& args, int threads);
  /// Write `mesh` as a pcl::PolygonMesh PLY into `out`.
  void (*write_mesh)(const TriMesh& mesh, OutputFile& out);
};

}  // namespace particlemesh::cli

/// Each module's one exported symbol.
#define PM_CLI_PCL_MODULE_ENTRY "particlemesh_cli_pcl_module"
