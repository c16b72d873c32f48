// The bridge's C entry points (particlemesh_pcl/particlemesh_pcl_c.h). The cloud is built
// through libparticlemesh's public C ABI (pm_cloud_create, pm_cloud_set_attribute), so the
// bridge needs no internal header of the core library; errors go to this library's own
// thread-local message, and no exception leaves a function here.
#include <particlemesh_pcl/particlemesh_pcl_c.h>

#include <algorithm>
#include <cstring>
#include <memory>
#include <new>
#include <string>
#include <vector>

#include <particlemesh/core/c_guard.h>
#include <particlemesh/core/error.h>
#include <particlemesh_pcl/io.h>

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

  struct CloudDeleter
  {
    void operator() (pm_cloud *c) const { pm_cloud_destroy (c); }
  };
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
    if (out_info != nullptr && (out_info->struct_size < sizeof (uint32_t) || out_info->struct_size > 4096))
      throw Error (Status::InvalidArgument, "out_info->struct_size must be set to sizeof(pm_pcl_read_info), is " +
                                            std::to_string (out_info->struct_size));
    const std::string file (path);
    particlemesh_pcl::LoadReport report;
    const particlemesh::PointCloud particles = particlemesh_pcl::loadParticles (file, &report);

    const std::size_t n = particles.size ();
    std::vector<double> positions (3 * n), normals;
    for (std::size_t i = 0; i < n; ++i)
    {
      positions[3 * i] = particles.positions[i].x;
      positions[3 * i + 1] = particles.positions[i].y;
      positions[3 * i + 2] = particles.positions[i].z;
    }
    if (particles.has_normals ())
    {
      normals.resize (3 * n);
      for (std::size_t i = 0; i < n; ++i)
      {
        normals[3 * i] = particles.normals[i].x;
        normals[3 * i + 1] = particles.normals[i].y;
        normals[3 * i + 2] = particles.normals[i].z;
      }
    }
    pm_cloud *raw = nullptr;
    check (pm_cloud_create (positions.data (), normals.empty () ? nullptr : normals.data (), n, &raw), file);
    std::unique_ptr<pm_cloud, CloudDeleter> cloud (raw);
    for (const auto &a : particles.attributes)
      check (pm_cloud_set_attribute (cloud.get (), a.name.c_str (), a.components, a.values.data (), n), file);

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
      // An older caller's smaller struct gets its prefix only.
      const std::size_t size = std::min<std::size_t> (out_info->struct_size, sizeof (info));
      std::memcpy (out_info, &info, size);
      out_info->struct_size = static_cast<uint32_t> (size);
    }
    *out_cloud = cloud.release ();
  });
}

}  // extern "C"
