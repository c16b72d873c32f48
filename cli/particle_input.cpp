// Reading particles for the CLI (particle_input.h). .ply, .xyz and the simulators' formats
// without preprocessing are read by the core reader; .pcd files, PCL preprocessing and
// --pcl-mesh go through one of the CLI's PCL modules (pcl_module.h), loaded only then, so that
// the runs that need no PCL do not pay for linking it at start.
#include <dlfcn.h>

#include <cctype>
#include <cstdio>
#include <filesystem>
#include <mutex>
#include <string>
#include <system_error>
#include <vector>

#include "commands.h"
#include "particle_input.h"
#include "particlemesh/core/error.h"
#include "particlemesh/io/mesh_io.h"
#include "pcl_module.h"

namespace particlemesh::cli {

namespace {

namespace fs = std::filesystem;

/// The input's extension in lower case; Houdini's compressed ".bgeo.gz", ".bgeo.sc",
/// ".geo.gz" and ".geo.sc" as one (the report's "format": "bgeo.sc", not "sc").
std::string lower_extension(const std::string& path) {
  const auto lower = [](std::string e) {
    for (char& ch : e) ch = char(std::tolower(static_cast<unsigned char>(ch)));
    return e;
  };
  const fs::path p(path);
  const std::string ext = lower(p.extension().string());
  if (ext == ".gz" || ext == ".sc") {
    const std::string inner = lower(p.stem().extension().string());
    if (inner == ".bgeo" || inner == ".geo") return inner + ext;
  }
  return ext;
}

/// Whether a PCL preprocessing switch is given: the PCL module then, else the PCD module.
bool wants_preprocessing(const ParticleInputArgs& a) {
  return a.uniform_sampling > 0 || a.voxel_grid > 0 || a.remove_outliers || a.mls_radius > 0 || a.estimate_normals;
}

bool wants_pcl(const std::string& path, const ParticleInputArgs& a) {
  return lower_extension(path) == ".pcd" || wants_preprocessing(a);
}

#ifdef PM_CLI_PCL_MODULE
/// One of the CLI's PCL modules, named `name`, loaded on first use: beside the executable (the
/// build tree), then where `cmake --install` puts it relative to the executable (the library
/// folder), then by name on the library search path. @throws Error saying where it looked and
/// why it did not load.
class ModuleLoader {
 public:
  explicit ModuleLoader(const char* name) : name_(name) {}

  const PclModule& get(const std::string& what) {
    std::call_once(once_, [this] { load(); });
    if (module_ == nullptr)
      throw Error(Status::IoError, what + " needs the CLI's PCL module, which did not load: " + failure_);
    return *module_;
  }

 private:
  void load() {
    std::error_code ec;
    const fs::path exe_dir = fs::read_symlink("/proc/self/exe", ec).parent_path();
    std::vector<std::string> places;
    if (!ec) {
      places.push_back((exe_dir / name_).string());
      places.push_back((exe_dir / PM_CLI_PCL_MODULE_FROM_BINDIR / name_).lexically_normal().string());
    }
    std::string tried;
    auto attempt = [&](const std::string& file) {
      void* handle = dlopen(file.c_str(), RTLD_NOW | RTLD_LOCAL);
      if (handle == nullptr) {
        const char* why = dlerror();
        tried += std::string(tried.empty() ? "" : "; ") + (why ? why : file + ": cannot be loaded");
        return false;
      }
      using Entry = const PclModule* (*)();
      const auto entry = reinterpret_cast<Entry>(dlsym(handle, PM_CLI_PCL_MODULE_ENTRY));
      const PclModule* m = entry ? entry() : nullptr;
      if (m == nullptr || m->version != PclModule::kVersion) {
        tried += std::string(tried.empty() ? "" : "; ") + file + " is not this version's PCL module";
        return false;
      }
      module_ = m;
      return true;
    };
    bool present = false;
    for (const std::string& file : places) {
      if (!fs::exists(file, ec)) continue;
      present = true;
      if (attempt(file)) return;
    }
    if (!present && attempt(name_)) return;
    std::string where;
    for (const std::string& file : places) where += (where.empty() ? "" : " nor ") + fs::path(file).parent_path().string();
    failure_ = present ? tried
                       : name_ + " is neither beside the program nor in its library folder (" + where +
                             ") nor on the library path; install particlemesh with the PCL bridge (PM_WITH_PCL=ON)";
  }

  const std::string name_;
  std::once_flag once_;
  const PclModule* module_ = nullptr;
  std::string failure_;
};

/// The module for `what`: with PCL's preprocessing when `preprocessing`, else the PCD module
/// (reading and --pcl-mesh, PCL's io library alone).
const PclModule& pcl_module(const std::string& what, bool preprocessing) {
  static ModuleLoader pcd(PM_CLI_PCD_MODULE), pcl(PM_CLI_PCL_MODULE);
  return (preprocessing ? pcl : pcd).get(what);
}
#else
[[noreturn]] const PclModule& pcl_module(const std::string& what, bool /*preprocessing*/) {
  throw Error(Status::InvalidArgument, what + " needs the PCL bridge (built with PM_WITH_PCL=OFF)");
}
#endif

/// What the bridge would report and print for an input it reads with the core reader.
ParticleInput read_natively(const std::string& path, const ParticleInputArgs& a) {
  ParticleInput in;
  in.cloud = read_point_cloud(path);
  const std::string ext = lower_extension(path);
  const size_t n = in.cloud.size();
  in.report = {{"format", ext.empty() ? "" : ext.substr(1)},
               {"encoding", ""},
               {"points", n},
               {"valid_points", n},
               {"invalid_points", 0},
               {"invalid_normals", 0},
               {"organized", false},
               {"width", uint32_t(n)},
               {"height", 1},
               {"has_normals", in.cloud.has_normals()},
               {"has_color", false},
               {"has_intensity", false}};
  in.has_viewpoint = a.viewpoint.size() == 3;
  if (in.has_viewpoint) in.viewpoint = Vec3{a.viewpoint[0], a.viewpoint[1], a.viewpoint[2]};
  return in;
}

}  // namespace

#ifdef PM_CLI_PCL_MODULE
void add_particle_input_options(CLI::App& app, ParticleInputArgs& a) {
  const char* group = "Input preprocessing (PCL; off by default)";
  auto* us = app.add_option("--uniform-sampling", a.uniform_sampling,
                            "Downsample with pcl::UniformSampling to this spacing (voxel edge, world units; also r0 unless --spacing)")
                 ->check(positive_number())
                 ->check(finite_number())
                 ->group(group);
  auto* vg = app.add_option("--voxel-grid", a.voxel_grid,
                            "Downsample with pcl::VoxelGrid to this spacing (the input point nearest each voxel's centroid; also r0 unless --spacing)")
                 ->check(positive_number())
                 ->check(finite_number())
                 ->group(group);
  us->excludes(vg);
  app.add_flag("--remove-outliers", a.remove_outliers,
               "Statistical outlier removal (pcl::StatisticalOutlierRemoval) before downsampling")
      ->group(group);
  app.add_option("--outlier-k", a.outlier_k, "Neighbours for the outlier statistics")
      ->check(in_range(1, 100000))
      ->capture_default_str()
      ->group(group);
  app.add_option("--outlier-std", a.outlier_std, "Outlier threshold: mean + this x stddev")
      ->check(in_range(0.0, 1e6))
      ->check(finite_number())
      ->capture_default_str()
      ->group(group);
  app.add_option("--mls", a.mls_radius,
                 "Smooth with pcl::MovingLeastSquares, after downsampling: each point moved onto the polynomial "
                 "surface fitted to its neighbours within this radius (world units; a few times the spacing), which "
                 "takes out a scanner's noise. The mesh's vertices are then the moved points")
      ->check(positive_number())
      ->check(finite_number())
      ->group(group);
  app.add_option("--mls-order", a.mls_order, "Order of the polynomial --mls fits (0 or 1: a plane)")
      ->check(in_range(0, 5))
      ->capture_default_str()
      ->group(group);
  app.add_flag("--estimate-normals", a.estimate_normals,
               "Estimate normals with PCL (replacing the file's), flipped toward the viewpoint")
      ->group(group);
  app.add_option("--normal-k", a.normal_k, "Neighbours for normal estimation")
      ->check(in_range(3, 100000))
      ->capture_default_str()
      ->group(group);
  app.add_option("--viewpoint", a.viewpoint,
                 "Where the scan was taken from, X Y Z: normals estimated with --estimate-normals face it, and "
                 "triangulate keeps depth jumps seen from it open (default: a .pcd's VIEWPOINT)")
      ->expected(3)
      ->group(group);
  app.add_option("--pcl-mesh", a.pcl_mesh,
                 "Also write the mesh as a pcl::PolygonMesh PLY (pcl::io::savePLYFileBinary; with rgb/intensity)");
}
#else
void add_particle_input_options(CLI::App&, ParticleInputArgs&) {}
#endif

void add_crop_option(CLI::App& app, std::vector<double>& crop) {
  app.add_option("--crop", crop,
                 "Keep only the particles inside this box, MINX MINY MINZ MAXX MAXY MAXZ (world units; spaces or commas): "
                 "a region of a large scene, or a simulation's particles without those flung far away (strays make the "
                 "grid too large). Applied after any preprocessing; the summary and the report count those dropped")
      ->expected(6)
      ->delimiter(',')
      ->check(finite_number());
}

std::string with_far_outlier_advice(const Error& e, bool outliers) {
  const std::string what = e.what();
  if (e.status() != Status::LimitExceeded || what.find("far outliers") == std::string::npos) return {};
  std::string advice = "--crop MINX MINY MINZ MAXX MAXY MAXZ keeps the particles inside a box";
  if (outliers && has_pcl_preprocessing()) advice = "--remove-outliers drops them; " + advice;
  return what + " (" + advice + ")";
}

namespace {

/// --crop: the particles inside the box (bounds included), in their order, with their normals
/// and channels; counted in the report and the summary.
void crop_particles(ParticleInput& in, const std::vector<double>& box) {
  if (box.empty()) return;
  for (int a = 0; a < 3; ++a)
    if (!(box[a] <= box[a + 3]))
      throw Error(Status::InvalidArgument, std::string("--crop: the box's minimum ") + "xyz"[a] + " (" +
                                               detail::shortest(box[a]) + ") is above its maximum (" +
                                               detail::shortest(box[a + 3]) + ")");
  const size_t n = in.cloud.size();
  std::vector<uint32_t> keep;
  for (size_t i = 0; i < n; ++i) {
    const Vec3& p = in.cloud.positions[i];
    if (p.x >= box[0] && p.y >= box[1] && p.z >= box[2] && p.x <= box[3] && p.y <= box[4] && p.z <= box[5])
      keep.push_back(uint32_t(i));
  }
  if (keep.empty())
    throw Error(Status::InvalidInput, "--crop: none of the " + std::to_string(n) + " particles lies inside the box");
  if (keep.size() < n) in.cloud = select_points(in.cloud, keep);
  in.report["crop"] = {{"min", {box[0], box[1], box[2]}},
                       {"max", {box[3], box[4], box[5]}},
                       {"kept", keep.size()},
                       {"dropped", n - keep.size()}};
  char line[160];
  std::snprintf(line, sizeof line, "  crop          %zu of %zu particles inside the box (%zu outside, dropped)\n",
                keep.size(), n, n - keep.size());
  in.summary += line;
}

}  // namespace

bool has_pcl_preprocessing() {
#ifdef PM_CLI_PCL_MODULE
  return true;
#else
  return false;
#endif
}

ParticleInput read_particles(const std::string& path, const ParticleInputArgs& a, int threads) {
  ParticleInput in;
  if (!wants_pcl(path, a)) {
    in = read_natively(path, a);
  } else {
    const std::string what = lower_extension(path) == ".pcd" ? "'" + path + "': .pcd input" : "PCL preprocessing";
    in = pcl_module(what, wants_preprocessing(a)).read(path, a, threads);
  }
  if (!in.cloud.not_read.empty()) {
    // Said, not dropped silently: what the file holds per particle that no channel carries.
    in.summary += not_read_line(in.cloud.not_read);
    in.report["not_read"] = in.cloud.not_read;
  }
  crop_particles(in, a.crop);
  return in;
}

void write_pcl_mesh(const TriMesh& mesh, OutputFile& out) {
  pcl_module("'" + out.path() + "': --pcl-mesh", false).write_mesh(mesh, out);
}

}  // namespace particlemesh::cli
