// What both of the CLI's PCL modules do (pcd_input.cpp): a file read through the bridge's
// PCL reader with its report and summary line, and the pcl::PolygonMesh PLY of --pcl-mesh.
// Only pcl_common and pcl_io are behind these, so the PCD module (pcd_module.cpp) loads
// without the rest of PCL; the PCL module (pcl_module.cpp) adds the preprocessing.
#pragma once

#include <string>

#include "particle_input.h"

namespace particlemesh::cli {

/// `path` (.pcd, .ply, .xyz) read through the bridge: invalid points dropped and reported,
/// the viewpoint --viewpoint's or else a .pcd's VIEWPOINT. @throws Error naming the file.
ParticleInput read_with_bridge(const std::string& path, const ParticleInputArgs& args);

/// `mesh` written into `out` as a pcl::PolygonMesh PLY.
void write_polygon_mesh(const TriMesh& mesh, OutputFile& out);

}  // namespace particlemesh::cli
