// particlemesh: particles to surfaces, for pipelines.
//   particlemesh triangulate IN -o OUT.ply      surface particles -> mesh
//   particlemesh inspect MESH [--json]          topology report of a mesh
//   particlemesh sample SHAPE -o OUT.xyz        evenly sampled demo/test particles
//   particlemesh smooth MESH -o OUT.ply         Loop / butterfly subdivision
//   particlemesh polygonize IN -o OUT.ply       volume particles -> implicit surface mesh
//   particlemesh render IN -o IMAGE.png         volume particles -> ray-cast image of the surface
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <exception>

#include <CLI/CLI.hpp>

#include "commands.h"
#include "particlemesh/core/error.h"
#include "particlemesh/version.h"
#include "progress_line.h"
#include "run_outputs.h"

int main(int argc, char** argv) {
  using namespace particlemesh;
  CLI::App app{"particlemesh " PARTICLEMESH_VERSION_STRING ": particles to surfaces"};
  app.set_version_flag("--version", PARTICLEMESH_VERSION_STRING);
  app.require_subcommand(1);
  std::vector<cli::Command> commands;
  cli::add_triangulate(app, commands);
  cli::add_inspect(app, commands);
  cli::add_sample(app, commands);
  cli::add_smooth(app, commands);
  cli::add_polygonize(app, commands);
  cli::add_render(app, commands);

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    const int code = app.exit(e);  // prints help / the usage error
    return code == 0 ? 0 : 2;
  }
  cli::install_signal_handlers();
  for (auto& c : commands) {
    if (!c.app->parsed()) continue;
    const char* name = c.app->get_name().c_str();
    try {
      const int status = c.run();
      // What was printed must have reached stdout (inspect > /dev/full, a closed pipe).
      if (std::fflush(stdout) != 0 || std::ferror(stdout)) {
        std::fprintf(stderr, "particlemesh %s: error: cannot write to standard output: %s\n", name,
                     std::strerror(errno));
        return 1;
      }
      return status;
    } catch (const cli::UsageError& e) {
      std::fprintf(stderr, "particlemesh %s: usage error: %s\nRun with --help for more information.\n", name, e.what());
      return 2;
    } catch (const Error& e) {
      // Cancelled by a signal: the library's own words would name its progress callback.
      const bool by_signal = e.status() == Status::Cancelled && cli::interrupted();
      std::fprintf(stderr, "particlemesh %s: error: %s\n", c.app->get_name().c_str(),
                   by_signal ? "cancelled (interrupted)" : e.what());
      return e.status() == Status::Cancelled ? 130 : 1;
    } catch (const std::bad_alloc&) {
      std::fprintf(stderr, "particlemesh %s: error: out of memory\n", c.app->get_name().c_str());
      return 1;
    } catch (const std::exception& e) {
      std::fprintf(stderr, "particlemesh %s: internal error: %s\n", c.app->get_name().c_str(), e.what());
      return 1;
    }
  }
  return 2;
}
