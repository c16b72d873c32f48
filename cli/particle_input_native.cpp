// particle_input.h without PCL (PM_WITH_PCL=OFF): .ply/.xyz through the core reader.
#include <filesystem>

#include "particle_input.h"
#include "particlemesh/core/error.h"
#include "particlemesh/io/mesh_io.h"

namespace particlemesh::cli {

void add_particle_input_options(CLI::App&, ParticleInputArgs&) {}

ParticleInput read_particles(const std::string& path, const ParticleInputArgs&, int) {
  std::string ext = std::filesystem::path(path).extension().string();
  for (char& ch : ext) ch = char(std::tolower(static_cast<unsigned char>(ch)));
  if (ext == ".pcd")
    throw Error(Status::InvalidArgument, path + ": .pcd input needs the PCL bridge (built with PM_WITH_PCL=OFF)");
  ParticleInput in;
  in.cloud = read_point_cloud(path);
  return in;
}

void write_pcl_mesh(const TriMesh&, OutputFile& out) {
  throw Error(Status::InvalidArgument, "'" + out.path() + "': --pcl-mesh needs the PCL bridge (built with PM_WITH_PCL=OFF)");
}

}  // namespace particlemesh::cli
