// The CLI's subcommands. Each file adds its own subcommand to the app; none holds an
// algorithm (those live in the library).
#pragma once

#include <functional>
#include <vector>

#include <CLI/CLI.hpp>

namespace particlemesh::cli {

struct Command {
  CLI::App* app;
  std::function<int()> run;  ///< returns the exit status
};

void add_triangulate(CLI::App& root, std::vector<Command>& commands);
void add_inspect(CLI::App& root, std::vector<Command>& commands);
void add_sample(CLI::App& root, std::vector<Command>& commands);
void add_smooth(CLI::App& root, std::vector<Command>& commands);
void add_polygonize(CLI::App& root, std::vector<Command>& commands);
void add_render(CLI::App& root, std::vector<Command>& commands);

}  // namespace particlemesh::cli
