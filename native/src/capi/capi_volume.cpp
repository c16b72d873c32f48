// C ABI: volume particles (kernels, lattice field, polygonization).
#include <cstdint>
#include <cstring>
#include <memory>
#include <string>

#include "capi/conversions.h"
#include "capi/firewall.h"
#include "capi/handles.h"
#include "particlemesh/volume/field.h"
#include "particlemesh/volume/kernel.h"
#include "particlemesh/volume/polygonize.h"
#include "particlemesh/volume/polygonize_attributes.h"

using namespace particlemesh;
using particlemesh::capi::guarded;
using particlemesh::capi::wrap_progress;
using particlemesh::capi::require;
using particlemesh::capi::to_kernel;

static_assert(PM_KERNEL_WYVILL == int(Kernel::Wyvill) && PM_KERNEL_POLY4 == int(Kernel::Poly4) &&
                  PM_KERNEL_POLY6 == int(Kernel::Poly6) && PM_KERNEL_BLINN == int(Kernel::Blinn),
              "the C kernel numbers are those of particlemesh::Kernel");

extern "C" {

void pm_polygonize_options_init(pm_polygonize_options* options) {
  if (!capi::reset_versioned(options)) return;
  const PolygonizeOptions d;
  capi::kernel_settings_to_c(d, options);
  options->cell_size = d.cell_size;
  options->threads = d.threads;
  options->max_grid_bytes = d.max_grid_bytes;
  options->min_component_volume = d.min_component_volume;
  options->min_component_particles = d.min_component_particles;
  options->taubin_iterations = d.surface_smoothing.iterations;
  options->taubin_lambda = d.surface_smoothing.lambda;
  options->taubin_mu = d.surface_smoothing.mu;
  options->flags = 0;
  options->domain_max_radius = d.domain_max_radius;
  options->collapse_edges = d.collapse_edges;
  options->domain_grid_radius = d.domain_grid_radius;
}

}  // extern "C"

namespace {

// PolygonizeOptions from the C options (checked), as pm_polygonize and
// pm_polygonize_attributes read them.
PolygonizeOptions polygonize_options_from_c(const pm_polygonize_options& o, const double* radii,
                                            const double* strengths, size_t count) {
  PolygonizeOptions opt;
  capi::kernel_settings_from_c(o, radii, strengths, count, &opt);
  opt.cell_size = o.cell_size;
  opt.threads = o.threads;
  opt.max_grid_bytes = o.max_grid_bytes;
  opt.progress = wrap_progress(o.progress, o.progress_user_data);
  opt.min_component_volume = o.min_component_volume;
  opt.min_component_particles = o.min_component_particles;
  opt.surface_smoothing.iterations = o.taubin_iterations;
  opt.surface_smoothing.lambda = o.taubin_lambda;
  opt.surface_smoothing.mu = o.taubin_mu;
  opt.collapse_edges = o.collapse_edges;
  if (o.flags & ~uint32_t(PM_POLYGONIZE_DOMAIN_MIN | PM_POLYGONIZE_CELL_RANGE | PM_POLYGONIZE_ANCHOR_IN_SPACE))
    throw Error(Status::InvalidArgument, "options->flags has unknown bits: " + std::to_string(o.flags));
  if (o.flags & PM_POLYGONIZE_ANCHOR_IN_SPACE) opt.lattice_anchor = LatticeAnchor::Space;
  if (o.flags & PM_POLYGONIZE_DOMAIN_MIN) opt.domain_min = Vec3{o.domain_min[0], o.domain_min[1], o.domain_min[2]};
  opt.domain_max_radius = o.domain_max_radius;
  opt.domain_grid_radius = o.domain_grid_radius;
  if (o.flags & PM_POLYGONIZE_CELL_RANGE) {
    PolygonizeOptions::CellRange range;
    for (int a = 0; a < 3; ++a) {
      range.min[a] = o.cell_min[a];
      range.max[a] = o.cell_max[a];
    }
    opt.cells = range;
  }
  return opt;
}

}  // namespace

extern "C" {

pm_status pm_polygonize_ex(const pm_cloud* cloud, const double* radii, const double* strengths,
                           const pm_polygonize_options* options, pm_mesh** out_mesh,
                           pm_polygonize_stats* out_stats) {
  return guarded([&] {
    require(cloud, "cloud");
    require(out_mesh, "out_mesh");
    const pm_polygonize_options o = capi::read_options(options, pm_polygonize_options_init);
    if (out_stats) capi::check_versioned(out_stats, "out_stats");
    const PolygonizeOptions opt = polygonize_options_from_c(o, radii, strengths, cloud->cloud.size());
    PolygonizeResult r = polygonize(cloud->cloud, opt);
    auto handle = std::make_unique<pm_mesh>();
    handle->mesh = std::move(r.mesh);
    if (out_stats) {
      pm_polygonize_stats s{};
      s.struct_size = sizeof(s);
      s.radius = r.stats.radius;
      s.threshold = r.stats.threshold;
      s.cell_size = r.stats.cell_size;
      s.spacing = r.stats.spacing;
      s.particles = r.stats.particles;
      s.sampled_blocks = r.stats.sampled_blocks;
      s.grid_bytes = r.stats.grid_bytes;
      s.vertices = r.stats.vertices;
      s.triangles = r.stats.triangles;
      s.anisotropic = r.stats.anisotropic ? 1 : 0;
      s.anisotropic_particles = r.stats.anisotropic_particles;
      s.components_removed = r.stats.components_removed;
      s.calibration_ratio = r.stats.calibration_ratio;
      for (int a = 0; a < 3; ++a) s.origin[a] = r.stats.origin[a];
      s.enclosed_fraction = r.stats.enclosed_fraction;
      s.density_radius = r.stats.density_radius;
      s.edges_collapsed = r.stats.edges_collapsed;
      capi::write_versioned(out_stats, s, "out_stats");
    }
    *out_mesh = handle.release();
  });
}

pm_status pm_polygonize(const pm_cloud* cloud, const double* radii, const double* strengths,
                        const pm_polygonize_options* options, pm_mesh** out_mesh) {
  return pm_polygonize_ex(cloud, radii, strengths, options, out_mesh, nullptr);
}

pm_status pm_polygonize_attributes(const pm_cloud* cloud, const double* radii, const double* strengths,
                                   const pm_polygonize_options* options, const double* points, size_t count,
                                   float* out_values, size_t out_capacity) {
  return guarded([&] {
    require(cloud, "cloud");
    const pm_polygonize_options o = capi::read_options(options, pm_polygonize_options_init);
    const PolygonizeOptions opt = polygonize_options_from_c(o, radii, strengths, cloud->cloud.size());
    size_t channels = 0;
    for (const VertexAttribute& a : cloud->cloud.attributes) channels += size_t(a.components);
    if (channels != 0 && count > SIZE_MAX / channels)
      throw Error(Status::LimitExceeded, "count x the attributes' components overflows");
    const size_t needed = count * channels;
    if (count > 0) require(points, "points");
    if (needed > 0) require(out_values, "out_values");
    capi::check_capacity(out_capacity, needed, "floats of the attributes at the points");
    std::vector<Vec3> p(count);
    for (size_t i = 0; i < count; ++i) p[i] = {points[3 * i], points[3 * i + 1], points[3 * i + 2]};
    const std::vector<VertexAttribute> values = polygonize_attributes(cloud->cloud, opt, p.data(), count);
    float* out = out_values;
    for (const VertexAttribute& a : values) {
      std::memcpy(out, a.values.data(), a.values.size() * sizeof(float));
      out += a.values.size();
    }
  });
}

pm_status pm_lattice_field(int32_t kernel, double radius, double spacing, double* out_value) {
  return guarded([&] {
    require(out_value, "out_value");
    const double v = lattice_field(to_kernel(kernel), radius, spacing);
    *out_value = v;
  });
}

pm_status pm_default_radius(const pm_cloud* cloud, const double* strengths, int32_t kernel, int32_t threads,
                            double* out_radius) {
  return guarded([&] {
    require(cloud, "cloud");
    require(out_radius, "out_radius");
    FieldParams p;
    p.kernel = to_kernel(kernel);
    // The default radius does not depend on the threshold (FieldParams::radius): any given one
    // spares the default's need of a positive median strength, as pm_polygonize with a threshold.
    p.threshold = 1;
    if (strengths) p.strengths.assign(strengths, strengths + cloud->cloud.size());
    const double r = ParticleField(cloud->cloud, p, threads).params().radius;
    *out_radius = r;
  });
}

pm_status pm_particle_grid_radius(const double* radii, size_t count, double* out_radius) {
  return guarded([&] {
    require(out_radius, "out_radius");
    if (count > 0) require(radii, "radii");
    *out_radius = particle_grid_radius(radii, count);
  });
}

}  // extern "C"
