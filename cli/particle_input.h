// Reading particles for the CLI (particle_input.cpp), with the PCL bridge when it is built
// (PM_WITH_PCL): .pcd through PCL's reader (invalid points dropped and reported), optional PCL
// preprocessing, and a pcl::PolygonMesh PLY beside the normal output, all in the CLI's PCL
// module (pcl_module.h), loaded only for them. Without PCL: the core reader's formats only.
#pragma once

#include <string>
#include <vector>

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include "particlemesh/core/error.h"
#include "particlemesh/io/output_file.h"
#include "particlemesh/mesh/point_cloud.h"
#include "particlemesh/mesh/tri_mesh.h"

namespace particlemesh::cli {

/// The particle files every command reads, for their help: the one list.
inline const std::string kParticleFormats =
    ".ply (x y z [nx ny nz or normal_x ..], other properties as channels), .xyz/.pts/.txt/.csv (x y z [nx ny nz] per line, "
    "or columns named by a header line), .obj (v x y z "
    "[r g b] lines, vn normals), a mesh's vertices from .off or .stl, VTK .vtk/.vtu/.vtp/.pvtu/.pvtp, Houdini .bgeo/.geo "
    "(.gz, .sc), lidar .las, Krakatoa .prt or, "
    "with the PCL bridge, .pcd (ascii, binary, binary_compressed)";

struct ParticleInputArgs {
  double uniform_sampling = 0;  ///< leaf size, 0 = off
  double voxel_grid = 0;        ///< leaf size, 0 = off
  bool remove_outliers = false;
  int outlier_k = 50;
  double outlier_std = 1.0;
  double mls_radius = 0;        ///< pcl::MovingLeastSquares' radius, 0 = off
  int mls_order = 2;
  bool estimate_normals = false;
  int normal_k = 20;
  std::vector<double> viewpoint;  ///< empty = the PCD's sensor origin (none for other formats)
  std::string pcl_mesh;           ///< also write a pcl::PolygonMesh PLY here
  /// --crop: MINX MINY MINZ MAXX MAXY MAXZ, only the particles inside are kept (after any
  /// preprocessing); empty = all of them.
  std::vector<double> crop;
};

struct ParticleInput {
  PointCloud cloud;
  nlohmann::json report;  ///< what was read, dropped and preprocessed
  std::string summary;    ///< lines for the human summary ("" when nothing to say)
  double spacing_hint = 0;  ///< the downsampling leaf size: the spacing to use when none is given
  /// Where the scan was taken from: a .pcd's VIEWPOINT, or --viewpoint.
  bool has_viewpoint = false;
  Vec3 viewpoint;
};

/// Whether this build has the PCL preprocessing switches (--mls, --voxel-grid, ...).
bool has_pcl_preprocessing();

/// Add the input options (preprocessing switches, --pcl-mesh) to a subcommand.
void add_particle_input_options(CLI::App& app, ParticleInputArgs& args);

/// Add --crop (every command that meshes or renders particles; not PCL's).
void add_crop_option(CLI::App& app, std::vector<double>& crop);

/// For the library's "far outliers" error (a grid too large for the particles' extent), its
/// message with the switches that go on without them: --crop, and --remove-outliers where this
/// build has it and `outliers`. "" for any other error.
std::string with_far_outlier_advice(const Error& e, bool outliers);

/// Read `path` (.pcd, .ply, .xyz), preprocess and crop as asked. @throws Error naming the file.
ParticleInput read_particles(const std::string& path, const ParticleInputArgs& args, int threads);

/// Write the mesh as a pcl::PolygonMesh PLY (--pcl-mesh) into `out`.
void write_pcl_mesh(const TriMesh& mesh, OutputFile& out);

}  // namespace particlemesh::cli
