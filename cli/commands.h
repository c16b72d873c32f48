// The CLI's subcommands. Each file adds its own subcommand to the app; none holds an
// algorithm (those live in the library).
#pragma once

#include <cmath>
#include <cstdlib>
#include <functional>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

namespace particlemesh::cli {

struct Command {
  CLI::App* app;
  std::function<int()> run;  ///< returns the exit status
};

/// CLI11's PositiveNumber and Range let "nan" through (every comparison with NaN is false):
/// every floating-point option adds this check, so "--spacing nan" is refused, not taken as
/// "not given".
inline CLI::Validator finite_number() {
  return CLI::Validator(
      [](std::string& s) -> std::string {
        char* end = nullptr;
        const double v = std::strtod(s.c_str(), &end);
        if (end != s.c_str() && *end == '\0' && !std::isfinite(v)) return "value " + s + " is not a finite number";
        return {};
      },
      "FINITE");
}

void add_triangulate(CLI::App& root, std::vector<Command>& commands);
void add_inspect(CLI::App& root, std::vector<Command>& commands);
void add_sample(CLI::App& root, std::vector<Command>& commands);
void add_smooth(CLI::App& root, std::vector<Command>& commands);
void add_polygonize(CLI::App& root, std::vector<Command>& commands);
void add_render(CLI::App& root, std::vector<Command>& commands);

}  // namespace particlemesh::cli
