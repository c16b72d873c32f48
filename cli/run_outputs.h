// A run's output files, handled as one: every path (-o, --report, --pcl-mesh) is checked
// before any input is read (a usage error, exit 2: a missing or read-only folder, a folder,
// a read-only file, an extension the command cannot write, two outputs naming one file, an
// output naming an input), each is written into its own temporary (OutputFile), and they are
// put in place together at the end, with signals held off so that a Ctrl-C cannot leave some
// of them: a run's outputs appear together or not at all.
#pragma once

#include <functional>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "particlemesh/io/mesh_io.h"
#include "particlemesh/io/output_file.h"
#include "particlemesh/mesh/topology_report.h"

namespace particlemesh::cli {

/// A usage error found after CLI11's parsing (main prints it and exits with status 2).
class UsageError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

enum class OutputKind {
  Mesh,     ///< .ply / .obj (or a device / FIFO: PLY)
  Points,   ///< .ply / .xyz
  Png,      ///< .png
  PlyOnly,  ///< .ply (PCL's PLY writer)
  Text,     ///< any name (JSON reports)
};

struct OutputSpec {
  std::string option;  ///< "-o", "--report", ...: for messages
  std::string path;    ///< "" = not asked for
  OutputKind kind = OutputKind::Text;
  MeshFormat format = MeshFormat::Auto;  ///< Mesh: the format asked for (--ascii)
};

class RunOutputs {
 public:
  /// Checks every output and its collisions with the others and with `inputs`.
  /// @throws UsageError naming the option, the path and the problem.
  RunOutputs(std::vector<OutputSpec> outputs, const std::vector<std::string>& inputs);
  ~RunOutputs();

  /// Whether `option` was given.
  bool has(const std::string& option) const;
  /// Opens `option`'s output for writing (its temporary, or the device / FIFO).
  OutputFile& open(const std::string& option);
  /// Opens `option`'s output and writes `mesh` into it, in the format its spec asks for.
  void write_mesh(const std::string& option, const TriMesh& mesh);
  /// The channels of `mesh` that `option`'s format cannot hold (OBJ: every one but the
  /// 3-component "color"; PCL's PLY writer: every one but it and "intensity"), for the
  /// summary's "not written" line; empty when not asked for. `why` receives the reason.
  std::vector<std::string> channels_not_written(const std::string& option, const TriMesh& mesh,
                                                std::string* why = nullptr) const;
  /// Finish every opened output and put them all in place.
  void commit_all();

 private:
  std::vector<OutputSpec> specs_;
  std::vector<std::pair<std::string, std::unique_ptr<OutputFile>>> open_;
};

/// The summary's "not written" lines: per mesh output (-o, --pcl-mesh) whose format cannot
/// hold some of `mesh`'s channels, those channels and why ("" when every output holds all).
std::string not_written_lines(const RunOutputs& outputs, const TriMesh& mesh);

/// What the mesh outputs' writing gives the summary and --report: the written mesh's topology
/// report (empty when not asked for) and the seconds the writing took.
struct WrittenMesh {
  TopologyReport report;
  double seconds = 0;
};

/// The writing phase of a command (set_phase(Phase::Writing)): runs `write` (the mesh outputs)
/// while, when `want_report` (a summary or --report will show it), the topology report of
/// `mesh` is taken on the other cores (by `report` when given: a cheaper way to the same
/// report, such as subdivided_topology_report); both are done before it returns, also when
/// `write` throws.
WrittenMesh write_with_report(const TriMesh& mesh, bool want_report, const std::function<void()>& write,
                              const std::function<TopologyReport()>& report = {});

}  // namespace particlemesh::cli
