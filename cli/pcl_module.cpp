// The CLI's PCL module (pcl_module.h): what the PCD module does (pcd_input.h) and PCL's
// preprocessing (outliers, downsampling, moving least squares, normals). Built as a module
// that the CLI loads only when preprocessing is asked for.
#include <cstdio>
#include <string>
#include <vector>

#include "pcd_input.h"
#include "pcl_module.h"
#include "particlemesh_pcl/preprocessing.h"

namespace particlemesh::cli {

namespace {

ParticleInput read_with_pcl(const std::string& path, const ParticleInputArgs& a, int threads) {
  ParticleInput in = read_with_bridge(path, a);
  const std::vector<std::string> not_read = in.cloud.not_read;  // about the file: kept through preprocessing
  char line[512];
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
  // (--viewpoint's, or a .pcd's VIEWPOINT, which is float: the same floats either way.)
  for (int k = 0; k < 3; ++k) o.viewpoint[k] = float(in.viewpoint[k]);
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

}  // namespace

}  // namespace particlemesh::cli

extern "C" __attribute__((visibility("default"))) const particlemesh::cli::PclModule* particlemesh_cli_pcl_module() {
  static const particlemesh::cli::PclModule module{particlemesh::cli::PclModule::kVersion,
                                                   &particlemesh::cli::read_with_pcl,
                                                   &particlemesh::cli::write_polygon_mesh};
  return &module;
}
