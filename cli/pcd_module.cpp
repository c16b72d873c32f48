// The CLI's PCD module (pcl_module.h): .pcd input through the bridge (invalid points dropped
// and reported) and the pcl::PolygonMesh PLY of --pcl-mesh, without PCL's preprocessing. It
// links PCL's common and io libraries only, so a run that reads a .pcd file and asks for no
// preprocessing does not load PCL's features, filters and surface libraries too (the PCL
// module, pcl_module.cpp, does: ~60 ms more at every start; bench/RESULTS.md).
#include "pcd_input.h"
#include "pcl_module.h"

namespace particlemesh::cli {

namespace {

ParticleInput read_pcd(const std::string& path, const ParticleInputArgs& a, int /*threads*/) {
  return read_with_bridge(path, a);
}

}  // namespace

}  // namespace particlemesh::cli

extern "C" __attribute__((visibility("default"))) const particlemesh::cli::PclModule* particlemesh_cli_pcl_module() {
  static const particlemesh::cli::PclModule module{particlemesh::cli::PclModule::kVersion,
                                                   &particlemesh::cli::read_pcd,
                                                   &particlemesh::cli::write_polygon_mesh};
  return &module;
}
