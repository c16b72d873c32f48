// The file side of the CLI's PCL modules (pcd_input.h): only the bridge's files and
// conversions, which need pcl_common and pcl_io alone.
#include "pcd_input.h"

#include <cstdio>
#include <string>

#include <pcl/console/print.h>

#include "particlemesh_pcl/conversions.h"
#include "particlemesh_pcl/io.h"

namespace particlemesh::cli {

ParticleInput read_with_bridge(const std::string& path, const ParticleInputArgs& a) {
  // PCL's own console messages would duplicate ours; errors come back as exceptions.
  pcl::console::setVerbosityLevel(pcl::console::L_ALWAYS);
  ParticleInput in;
  particlemesh_pcl::LoadReport load;
  in.cloud = particlemesh_pcl::loadParticles(path, &load);
  const auto& c = load.conversion;
  in.report = {{"format", load.format},
               {"encoding", load.encoding},
               {"points", c.input_points},
               {"valid_points", c.valid_points},
               {"invalid_points", c.invalid_points},
               {"invalid_normals", c.invalid_normals},
               {"organized", c.organized},
               {"width", c.width},
               {"height", c.height},
               {"has_normals", c.has_normals},
               {"has_color", c.has_color},
               {"has_intensity", c.has_intensity}};
  char line[512];
  if (load.format == "pcd") {
    std::snprintf(line, sizeof line, "  input         %zu points (%s%s, pcd %s%s%s%s)", c.input_points,
                  c.organized ? (std::to_string(c.width) + " x " + std::to_string(c.height)).c_str() : "",
                  c.organized ? " organized" : "unorganized", load.encoding.c_str(), c.has_normals ? ", normals" : "",
                  c.has_color ? ", rgb" : "", c.has_intensity ? ", intensity" : "");
    in.summary += line;
    if (c.invalid_points > 0) in.summary += "; " + std::to_string(c.invalid_points) + " invalid (NaN/Inf) dropped";
    if (c.invalid_normals > 0)
      in.summary += "; normals dropped (" + std::to_string(c.invalid_normals) + " invalid)";
    in.summary += "\n";
  }

  in.has_viewpoint = a.viewpoint.size() == 3 || load.format == "pcd";
  in.viewpoint = a.viewpoint.size() == 3 ? Vec3{a.viewpoint[0], a.viewpoint[1], a.viewpoint[2]}
                                         : Vec3{load.origin[0], load.origin[1], load.origin[2]};
  return in;
}

void write_polygon_mesh(const TriMesh& mesh, OutputFile& out) {
  pcl::PolygonMesh pm;
  particlemesh_pcl::toPolygonMesh(mesh, pm);
  particlemesh_pcl::savePLYFile(out, pm);
}

}  // namespace particlemesh::cli
