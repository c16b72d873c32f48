#include "run_outputs.h"

#include <chrono>
#include <csignal>
#include <cstdio>
#include <fcntl.h>
#include <unistd.h>
#include <sys/stat.h>

#include <tbb/task_group.h>

#include "particlemesh/core/error.h"
#include "progress_line.h"

namespace particlemesh::cli {

namespace {

std::string lower_extension(const std::string& path) {
  const size_t slash = path.find_last_of('/');
  const size_t dot = path.find_last_of('.');
  if (dot == std::string::npos || (slash != std::string::npos && dot < slash)) return {};
  std::string ext = path.substr(dot);
  for (char& c : ext) c = char(std::tolower(static_cast<unsigned char>(c)));
  return ext;
}

bool character_device(const std::string& path) {
  struct stat st {};
  return ::stat(path.c_str(), &st) == 0 && S_ISCHR(st.st_mode);
}

}  // namespace

RunOutputs::RunOutputs(std::vector<OutputSpec> outputs, const std::vector<std::string>& inputs) {
  for (OutputSpec& o : outputs)
    if (!o.path.empty()) specs_.push_back(std::move(o));
  // "-" is standard output. An output that goes to standard output (-, /dev/stdout, or the
  // file stdout is redirected to) gets its own copy of the descriptor, and what the command
  // prints (its summary) goes to stderr instead, so that the file's bytes stay alone.
  bool to_stdout = false;
  for (OutputSpec& o : specs_) {
    if (o.path == "-") o.path = "/dev/stdout";
    if (o.path == "/dev/stdout" || o.path == "/proc/self/fd/1" || o.path == "/dev/fd/1") to_stdout = true;
  }
  if (to_stdout) {
    std::fflush(stdout);
    const int fd = ::fcntl(STDOUT_FILENO, F_DUPFD_CLOEXEC, 3);
    if (fd < 0) throw UsageError("-o: standard output is not open");
    for (OutputSpec& o : specs_)
      if (o.path == "/dev/stdout" || o.path == "/proc/self/fd/1" || o.path == "/dev/fd/1") o.path = "/dev/fd/" + std::to_string(fd);
    ::dup2(STDERR_FILENO, STDOUT_FILENO);
  }
  for (const OutputSpec& o : specs_) {
    auto usage = [&](const std::string& why) { throw UsageError(o.option + ": " + why); };
    try {
      const std::string ext = lower_extension(o.path);
      switch (o.kind) {
        case OutputKind::Mesh: mesh_output_format(o.path, o.format); break;
        case OutputKind::Points: check_point_cloud_output(o.path); break;
        case OutputKind::Png:
          if (ext != ".png" && !is_stream_output(o.path)) usage("'" + o.path + "': the image is written as .png");
          break;
        case OutputKind::PlyOnly:
          if (ext != ".ply" && !is_stream_output(o.path)) usage("'" + o.path + "': PCL's mesh is written as .ply");
          break;
        case OutputKind::Text: break;
      }
      check_output_path(o.path);
    } catch (const Error& e) {
      usage(e.what());
    }
  }
  for (size_t i = 0; i < specs_.size(); ++i) {
    for (const std::string& in : inputs)
      if (!in.empty() && same_file(specs_[i].path, in))
        throw UsageError(specs_[i].option + " '" + specs_[i].path + "' is the input file '" + in +
                         "': it would be overwritten (choose another output name)");
    for (size_t j = 0; j < i; ++j)
      if (same_file(specs_[i].path, specs_[j].path) && !character_device(specs_[i].path))
        throw UsageError(specs_[j].option + " and " + specs_[i].option + " both name '" + specs_[i].path +
                         "': one would overwrite the other");
  }
}

RunOutputs::~RunOutputs() = default;

bool RunOutputs::has(const std::string& option) const {
  for (const OutputSpec& o : specs_)
    if (o.option == option) return true;
  return false;
}

OutputFile& RunOutputs::open(const std::string& option) {
  for (const OutputSpec& o : specs_)
    if (o.option == option) {
      open_.emplace_back(option, std::make_unique<OutputFile>(o.path));
      return *open_.back().second;
    }
  throw Error(Status::Internal, "no output " + option);
}

void RunOutputs::write_mesh(const std::string& option, const TriMesh& mesh) {
  for (const OutputSpec& o : specs_)
    if (o.option == option) {
      WriteMeshOptions wo;
      wo.format = o.format;
      particlemesh::write_mesh(mesh, open(option), wo);
      return;
    }
  throw Error(Status::Internal, "no output " + option);
}

std::vector<std::string> RunOutputs::channels_not_written(const std::string& option, const TriMesh& mesh,
                                                          std::string* why) const {
  std::vector<std::string> out;
  for (const OutputSpec& o : specs_) {
    if (o.option != option || o.path.empty()) continue;
    // OBJ's "v x y z r g b" holds a colour; PCL's PLY writer knows rgb and intensity.
    const bool obj = o.kind == OutputKind::Mesh && mesh_output_format(o.path, o.format) == MeshFormat::Obj;
    const bool pcl = o.kind == OutputKind::PlyOnly;
    // Values per triangle corner: OBJ's vt and PLY's texcoord lists hold texture coordinates
    // ("uv"), no output any other.
    const bool ply = o.kind == OutputKind::Mesh && (mesh_output_format(o.path, o.format) == MeshFormat::PlyBinary ||
                                                    mesh_output_format(o.path, o.format) == MeshFormat::PlyAscii);
    bool corners = false;
    for (const VertexAttribute& a : mesh.corner_attributes)
      if (!((obj || ply) && a.name == "uv" && a.components == 2)) {
        out.push_back(a.name + " (per corner)");
        corners = true;
      }
    if (!obj && !pcl) {
      if (why && corners) *why = "only .obj and .ply hold texture coordinates (uv), and no other value per corner";
      continue;
    }
    for (const VertexAttribute& a : mesh.attributes)
      if (!(a.name == "color" && a.components == 3) && !(pcl && a.name == "intensity" && a.components == 1))
        out.push_back(a.name);
    if (why)
      *why = obj ? "OBJ holds a colour per vertex and texture coordinates only; .ply, .vtk, .vtu and .vtp hold every "
                   "per-vertex channel"
                 : "PCL's PLY writer holds rgb and intensity only; -o with .ply holds every channel";
  }
  return out;
}

std::string not_written_lines(const RunOutputs& outputs, const TriMesh& mesh) {
  std::string lines;
  for (const char* option : {"-o", "--pcl-mesh"}) {
    std::string why;
    const std::vector<std::string> names = outputs.channels_not_written(option, mesh, &why);
    if (names.empty()) continue;
    std::string list;
    for (const std::string& n : names) list += (list.empty() ? "" : ", ") + n;
    lines += std::string("  not written   ") + (option == std::string("-o") ? "" : std::string(option) + ": ") + list +
             " (" + why + ")\n";
  }
  return lines;
}

void RunOutputs::commit_all() {
  for (auto& [option, file] : open_) file->finish();
  // Hold off the signals while the files go in place: all of them, or none.
  sigset_t all, old;
  sigfillset(&all);
  sigprocmask(SIG_BLOCK, &all, &old);
  try {
    for (auto& [option, file] : open_) file->commit();
  } catch (...) {
    set_phase(Phase::Done);
    sigprocmask(SIG_SETMASK, &old, nullptr);
    throw;
  }
  set_phase(Phase::Done);  // a signal from now on ends the process as usual: the outputs are complete
  sigprocmask(SIG_SETMASK, &old, nullptr);
}

WrittenMesh write_with_report(const TriMesh& mesh, bool want_report, const std::function<void()>& write,
                              const std::function<TopologyReport()>& report) {
  set_phase(Phase::Writing);
  WrittenMesh w;
  tbb::task_group beside;
  if (want_report) beside.run([&] { w.report = report ? report() : topology_report(mesh); });
  const auto t0 = std::chrono::steady_clock::now();
  try {
    write();
  } catch (...) {
    beside.wait();
    throw;
  }
  w.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  beside.wait();
  return w;
}

}  // namespace particlemesh::cli
