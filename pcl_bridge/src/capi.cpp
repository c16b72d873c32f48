// The bridge's C entry points (particlemesh_pcl/particlemesh_pcl_c.h). The cloud is built
// through libparticlemesh's public C ABI (pm_cloud_create, pm_cloud_set_attribute), so the
// bridge needs no internal header of the core library; errors go to this library's own
// thread-local message, and no exception leaves a function here.
#include <particlemesh_pcl/particlemesh_pcl_c.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <memory>
#include <new>
#include <string>
#include <vector>

#include <particlemesh/core/c_guard.h>
#include <particlemesh/core/error.h>
#include <particlemesh_pcl/io.h>
#include <particlemesh_pcl/preprocessing.h>

namespace
{
  thread_local std::string last_error;

  void
  setError (const std::string &message) noexcept
  {
    try
    {
      last_error = message;
    }
    catch (...)
    {
    }
  }

  // A failed core C ABI call inside the bridge: its status, its message after the file's name.
  void
  check (pm_status status, const std::string &path)
  {
    if (status != PM_OK)
      throw particlemesh::Error (static_cast<particlemesh::Status> (status), path + ": " + pm_last_error_message ());
  }

  // The same firewall as the core library's C ABI, with this library's own message.
  template <class F> pm_status
  guarded (F &&body) noexcept
  {
    last_error.clear ();
    return particlemesh::run_guarded (setError, body);
  }

  // An output struct sized by the caller (its first member: uint32_t struct_size), checked
  // before any work: `name` names it in the error.
  template <class T> void
  checkSized (const T *out, const char *name, const char *type)
  {
    if (out != nullptr && (out->struct_size < sizeof (uint32_t) || out->struct_size > 4096))
      throw particlemesh::Error (particlemesh::Status::InvalidArgument,
                                 std::string (name) + "->struct_size must be set to sizeof(" + type + "), is " +
                                     std::to_string (out->struct_size));
  }

  // `value` into the caller's struct: an older caller's smaller struct gets its prefix only.
  template <class T> void
  writeSized (T *out, const T &value)
  {
    const std::size_t size = std::min<std::size_t> (out->struct_size, sizeof (T));
    std::memcpy (out, &value, size);
    out->struct_size = static_cast<uint32_t> (size);
  }

  struct CloudDeleter
  {
    void operator() (pm_cloud *c) const { pm_cloud_destroy (c); }
  };
  using CloudHandle = std::unique_ptr<pm_cloud, CloudDeleter>;

  // A pm_cloud of the particles, through the core library's public C ABI. `what` names the
  // input in an error.
  CloudHandle
  toHandle (const particlemesh::PointCloud &particles, const std::string &what)
  {
    const std::size_t n = particles.size ();
    std::vector<double> positions (3 * n), normals;
    for (std::size_t i = 0; i < n; ++i)
      for (int c = 0; c < 3; ++c)
        positions[3 * i + c] = particles.positions[i][c];
    if (particles.has_normals ())
    {
      normals.resize (3 * n);
      for (std::size_t i = 0; i < n; ++i)
        for (int c = 0; c < 3; ++c)
          normals[3 * i + c] = particles.normals[i][c];
    }
    pm_cloud *raw = nullptr;
    check (pm_cloud_create (positions.data (), normals.empty () ? nullptr : normals.data (), n, &raw), what);
    CloudHandle cloud (raw);
    for (const auto &a : particles.attributes)
      check (pm_cloud_set_attribute (cloud.get (), a.name.c_str (), a.components, a.values.data (), n), what);
    return cloud;
  }

  // The particles a pm_cloud holds (positions and normals in double, every attribute).
  particlemesh::PointCloud
  fromHandle (const pm_cloud *cloud)
  {
    const std::string what = "cloud";
    std::size_t n = 0;
    check (pm_cloud_get_count (cloud, &n), what);
    particlemesh::PointCloud out;
    std::vector<double> values (3 * n);
    check (pm_cloud_copy_positions (cloud, values.data (), n), what);
    out.positions.resize (n);
    for (std::size_t i = 0; i < n; ++i)
      out.positions[i] = {values[3 * i], values[3 * i + 1], values[3 * i + 2]};
    int32_t has_normals = 0;
    check (pm_cloud_has_normals (cloud, &has_normals), what);
    if (has_normals != 0)
    {
      check (pm_cloud_copy_normals (cloud, values.data (), n), what);
      out.normals.resize (n);
      for (std::size_t i = 0; i < n; ++i)
        out.normals[i] = {values[3 * i], values[3 * i + 1], values[3 * i + 2]};
    }
    std::size_t count = 0;
    check (pm_cloud_get_attribute_count (cloud, &count), what);
    for (std::size_t k = 0; k < count; ++k)
    {
      const char *name = nullptr;
      int32_t components = 0;
      check (pm_cloud_get_attribute_name (cloud, k, &name), what);
      check (pm_cloud_get_attribute_components (cloud, name, &components), what);
      particlemesh::VertexAttribute a;
      a.name = name;
      a.components = components;
      a.values.resize (n * std::size_t (components));
      check (pm_cloud_copy_attribute (cloud, name, a.values.data (), n), what);
      out.attributes.push_back (std::move (a));
    }
    return out;
  }
}

extern "C" {

uint32_t
pm_pcl_abi_version (void)
{
  return PM_PCL_ABI_VERSION;
}

const char *
pm_pcl_last_error_message (void)
{
  return last_error.c_str ();
}

pm_status
pm_pcl_read_cloud (const char *path, pm_cloud **out_cloud, pm_pcl_read_info *out_info)
{
  return guarded ([&] {
    using particlemesh::Error;
    using particlemesh::Status;
    if (path == nullptr)
      throw Error (Status::InvalidArgument, "path is NULL");
    if (out_cloud == nullptr)
      throw Error (Status::InvalidArgument, "out_cloud is NULL");
    checkSized (out_info, "out_info", "pm_pcl_read_info");
    const std::string file (path);
    particlemesh_pcl::LoadReport report;
    const particlemesh::PointCloud particles = particlemesh_pcl::loadParticles (file, &report);

    CloudHandle cloud = toHandle (particles, file);

    if (out_info != nullptr)
    {
      pm_pcl_read_info info{};
      info.struct_size = sizeof (pm_pcl_read_info);
      info.input_points = report.conversion.input_points;
      info.valid_points = report.conversion.valid_points;
      info.invalid_points = report.conversion.invalid_points;
      info.invalid_normals = report.conversion.invalid_normals;
      info.width = report.conversion.width;
      info.height = report.conversion.height;
      info.has_normals = particles.has_normals () ? 1 : 0;
      bool color = false, intensity = false;
      for (const auto &a : particles.attributes)
      {
        color = color || a.name == particlemesh_pcl::kColorAttribute;
        intensity = intensity || a.name == particlemesh_pcl::kIntensityAttribute;
      }
      info.has_color = color ? 1 : 0;
      info.has_intensity = intensity ? 1 : 0;
      for (int c = 0; c < 3; ++c)
        info.origin[c] = report.origin[c];
      writeSized (out_info, info);
    }
    *out_cloud = cloud.release ();
  });
}

void
pm_pcl_preprocess_options_init (pm_pcl_preprocess_options *options)
{
  if (options == nullptr)
    return;
  const particlemesh_pcl::PreprocessOptions d;
  pm_pcl_preprocess_options o{};
  o.struct_size = sizeof (o);
  o.remove_outliers = d.remove_outliers ? 1 : 0;
  o.outlier_mean_k = d.outlier_mean_k;
  o.outlier_stddev_mul = d.outlier_stddev_mul;
  o.downsampling = PM_PCL_DOWNSAMPLE_NONE;
  o.leaf_size = d.leaf_size;
  o.mls_radius = d.mls_radius;
  o.mls_order = d.mls_order;
  o.estimate_normals = d.estimate_normals ? 1 : 0;
  o.normal_k = d.normal_k;
  for (int c = 0; c < 3; ++c)
    o.viewpoint[c] = d.viewpoint[c];
  o.threads = d.threads;
  *options = o;
}

pm_status
pm_pcl_preprocess (const pm_cloud *cloud, const pm_pcl_preprocess_options *options, pm_cloud **out_cloud,
                   uint32_t *out_kept, pm_pcl_preprocess_report *out_report)
{
  return guarded ([&] {
    using particlemesh::Error;
    using particlemesh::Status;
    if (cloud == nullptr)
      throw Error (Status::InvalidArgument, "cloud is NULL");
    if (out_cloud == nullptr)
      throw Error (Status::InvalidArgument, "out_cloud is NULL");
    checkSized (out_report, "out_report", "pm_pcl_preprocess_report");
    // An older caller's smaller options struct: its prefix over the defaults.
    pm_pcl_preprocess_options o;
    pm_pcl_preprocess_options_init (&o);
    if (options != nullptr)
    {
      if (options->struct_size < sizeof (uint32_t) || options->struct_size > 4096)
        throw Error (Status::InvalidArgument, "options->struct_size is " + std::to_string (options->struct_size) +
                                              " (call pm_pcl_preprocess_options_init first)");
      std::memcpy (&o, options, std::min<std::size_t> (options->struct_size, sizeof (o)));
    }
    particlemesh_pcl::PreprocessOptions p;
    p.remove_outliers = o.remove_outliers != 0;
    p.outlier_mean_k = o.outlier_mean_k;
    p.outlier_stddev_mul = o.outlier_stddev_mul;
    switch (o.downsampling)
    {
      case PM_PCL_DOWNSAMPLE_NONE: p.downsampling = particlemesh_pcl::Downsampling::None; break;
      case PM_PCL_DOWNSAMPLE_UNIFORM: p.downsampling = particlemesh_pcl::Downsampling::UniformSampling; break;
      case PM_PCL_DOWNSAMPLE_VOXEL_GRID: p.downsampling = particlemesh_pcl::Downsampling::VoxelGrid; break;
      default:
        throw Error (Status::InvalidArgument, "options->downsampling is " + std::to_string (o.downsampling) +
                                              " (PM_PCL_DOWNSAMPLE_NONE 0, _UNIFORM 1 or _VOXEL_GRID 2)");
    }
    p.leaf_size = o.leaf_size;
    p.mls_radius = o.mls_radius;
    p.mls_order = o.mls_order;
    p.estimate_normals = o.estimate_normals != 0;
    p.normal_k = o.normal_k;
    for (int c = 0; c < 3; ++c)
    {
      if (!std::isfinite (o.viewpoint[c]))
        throw Error (Status::InvalidArgument, "options->viewpoint is not 3 finite numbers");
      p.viewpoint[c] = o.viewpoint[c];
    }
    p.threads = o.threads;

    particlemesh::PointCloud particles = fromHandle (cloud);
    const std::size_t input = particles.size ();
    std::vector<std::uint32_t> kept;
    const particlemesh_pcl::PreprocessReport r = particlemesh_pcl::preprocess (particles, p, &kept);
    CloudHandle result = toHandle (particles, "the preprocessed cloud");

    if (out_report != nullptr)
    {
      pm_pcl_preprocess_report report{};
      report.struct_size = sizeof (report);
      report.input_points = input;
      report.outliers_removed = r.outliers_removed;
      report.downsampled_away = r.downsampled_away;
      report.smoothed = r.smoothed;
      report.smoothing_skipped = r.smoothing_skipped;
      report.smoothing_mean_shift = r.smoothing_mean_shift;
      report.smoothing_max_shift = r.smoothing_max_shift;
      report.output_points = r.output_points;
      report.normals_estimated = r.normals_estimated ? 1 : 0;
      report.normals_failed = r.normals_failed;
      report.seconds = r.seconds;
      writeSized (out_report, report);
    }
    if (out_kept != nullptr)
      std::copy (kept.begin (), kept.end (), out_kept);
    *out_cloud = result.release ();
  });
}

}  // extern "C"
