// The CLI's PCL part (pcl_module.h): .pcd input through the bridge (invalid points dropped and
// reported), PCL preprocessing, and the pcl::PolygonMesh PLY of --pcl-mesh. Built as a module
// that the CLI loads only when one of these is asked for.
#include <cstdio>
#include <string>

#include <pcl/console/print.h>

#include "pcl_module.h"
#include "particlemesh/core/error.h"
#include "particlemesh_pcl/conversions.h"
#include "particlemesh_pcl/io.h"
#include "particlemesh_pcl/preprocessing.h"

namespace particlemesh::cli {

namespace {

ParticleInput read_with_pcl(const std::string& path, const ParticleInputArgs& a, int threads) {
  // PCL's own console messages would duplicate ours; errors come back as exceptions.
  pcl::console::setVerbosityLevel(pcl::console::L_ALWAYS);
  ParticleInput in;
  particlemesh_pcl::LoadReport load;
  in.cloud = particlemesh_pcl::loadParticles(path, &load);
  const std::vector<std::string> not_read = in.cloud.not_read;  // about the file: kept through preprocessing
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

  particlemesh_pcl::PreprocessOptions o;
  o.remove_outliers = a.remove_outliers;
  o.outlier_mean_k = a.outlier_k;
  o.outlier_stddev_mul = a.outlier_std;
  if (a.uniform_sampling > 0) {
    o.downsampling = particlemesh_pcl::Downsampling::UniformSampling;
    o.leaf_size = a.uniform_sampling;
  } else if (a.voxel_grid > 0) {
    o.downsampling = particlemesh_pcl::Downsampling::VoxelGrid;
    o.leaf_size = a.voxel_grid;
  }
  o.mls_radius = a.mls_radius;
  o.mls_order = a.mls_order;
  o.estimate_normals = a.estimate_normals;
  o.normal_k = a.normal_k;
  for (int k = 0; k < 3; ++k) o.viewpoint[k] = a.viewpoint.size() == 3 ? float(a.viewpoint[k]) : load.origin[k];
  in.has_viewpoint = a.viewpoint.size() == 3 || load.format == "pcd";
  in.viewpoint = a.viewpoint.size() == 3 ? Vec3{a.viewpoint[0], a.viewpoint[1], a.viewpoint[2]}
                                         : Vec3{load.origin[0], load.origin[1], load.origin[2]};
  o.threads = threads;
  in.spacing_hint = o.downsampling == particlemesh_pcl::Downsampling::None ? 0.0 : o.leaf_size;
  if (particlemesh_pcl::anyPreprocessing(o)) {
    const auto p = particlemesh_pcl::preprocess(in.cloud, o);
    in.report["preprocessing"] = {{"outliers_removed", p.outliers_removed},
                                  {"downsampling", a.uniform_sampling > 0 ? "uniform_sampling"
                                                   : a.voxel_grid > 0     ? "voxel_grid"
                                                                          : "none"},
                                  {"leaf_size", o.leaf_size},
                                  {"downsampled_away", p.downsampled_away},
                                  {"mls_radius", o.mls_radius},
                                  {"mls_order", o.mls_order},
                                  {"smoothed", p.smoothed},
                                  {"smoothing_skipped", p.smoothing_skipped},
                                  {"smoothing_mean_shift", p.smoothing_mean_shift},
                                  {"smoothing_max_shift", p.smoothing_max_shift},
                                  {"output_points", p.output_points},
                                  {"normals_estimated", p.normals_estimated},
                                  {"normals_failed", p.normals_failed},
                                  {"seconds", p.seconds}};
    std::string s = "  preprocessing";
    if (a.remove_outliers) s += " " + std::to_string(p.outliers_removed) + " outliers removed;";
    if (o.downsampling != particlemesh_pcl::Downsampling::None) {
      std::snprintf(line, sizeof line, " %s %.6g: %zu points dropped;",
                    a.uniform_sampling > 0 ? "uniform sampling" : "voxel grid", o.leaf_size, p.downsampled_away);
      s += line;
    }
    if (o.mls_radius > 0) {
      std::snprintf(line, sizeof line, " moving least squares (radius %.6g, order %d): %zu points moved, %.3g on average, at most %.3g",
                    o.mls_radius, o.mls_order, p.smoothed, p.smoothing_mean_shift, p.smoothing_max_shift);
      s += line;
      if (p.smoothing_skipped > 0)
        s += ", " + std::to_string(p.smoothing_skipped) + " left in place (fewer than 3 neighbours within the radius)";
      s += ";";
    }
    if (a.estimate_normals) {
      std::snprintf(line, sizeof line, " normals %s (k %d, toward %g %g %g);",
                    p.normals_estimated ? "estimated" : "failed, none used", o.normal_k, o.viewpoint[0],
                    o.viewpoint[1], o.viewpoint[2]);
      s += line;
    }
    s.back() = '\n';
    in.summary += s;
  }
  in.cloud.not_read = not_read;
  return in;
}

void write_polygon_mesh(const TriMesh& mesh, OutputFile& out) {
  pcl::PolygonMesh pm;
  particlemesh_pcl::toPolygonMesh(mesh, pm);
  particlemesh_pcl::savePLYFile(out, pm);
}

}  // namespace

}  // namespace particlemesh::cli

extern "C" __attribute__((visibility("default"))) const particlemesh::cli::PclModule* particlemesh_cli_pcl_module() {
  static const particlemesh::cli::PclModule module{particlemesh::cli::PclModule::kVersion,
                                                   &particlemesh::cli::read_with_pcl,
                                                   &particlemesh::cli::write_polygon_mesh};
  return &module;
}
