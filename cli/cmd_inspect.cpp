// particlemesh inspect MESH [--json]: what a mesh is, topologically.
#include <cstdio>
#include <memory>

#include "commands.h"
#include "particlemesh/io/mesh_io.h"
#include "particlemesh/mesh/topology_report.h"
#include "report_json.h"

namespace particlemesh::cli {

void add_inspect(CLI::App& root, std::vector<Command>& commands) {
  struct Args {
    std::string input;
    bool json = false;
  };
  auto args = std::make_shared<Args>();
  CLI::App* app = root.add_subcommand("inspect", "Print the topology report of a mesh (.ply, .obj, .off, .stl)");
  app->add_option("mesh", args->input, "Mesh file")->required();
  app->add_flag("--json", args->json, "Print the report as JSON");
  commands.push_back({app, [args] {
                        const TriMesh mesh = read_mesh(args->input);
                        const TopologyReport r = topology_report(mesh);
                        if (args->json) {
                          std::printf("%s\n", to_json(r).dump(2).c_str());
                        } else {
                          std::printf("%s\n%s", args->input.c_str(), describe(r).c_str());
                        }
                        return 0;
                      }});
}

}  // namespace particlemesh::cli
