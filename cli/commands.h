// The CLI's subcommands. Each file adds its own subcommand to the app; none holds an
// algorithm (those live in the library).
#pragma once

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <functional>
#include <optional>
#include <string>
#include <type_traits>
#include <vector>

#include <CLI/CLI.hpp>

namespace particlemesh::cli {

struct Command {
  CLI::App* app;
  std::function<int()> run;  ///< returns the exit status
};

namespace detail {
/// The option's text as a number, or nullopt when it is not one (CLI11's conversion then says so).
inline std::optional<double> number_in(const std::string& s) {
  char* end = nullptr;
  const double v = std::strtod(s.c_str(), &end);
  if (end == s.c_str() || *end != '\0') return std::nullopt;
  return v;
}
inline std::string shortest(double v) {
  char b[32];
  std::snprintf(b, sizeof b, "%.10g", v);
  return b;
}
}  // namespace detail

/// The summaries' "not read" line: what a file held but the reader did not carry
/// (PointCloud::not_read, TriMesh::not_read); "" when it carried everything.
inline std::string not_read_line(const std::vector<std::string>& lines) {
  if (lines.empty()) return "";
  std::string out;
  for (const std::string& what : lines) out += (out.empty() ? "" : "; ") + what;
  return "  not read      " + out + "\n";
}

/// CLI11's validators and those below let "nan" through (every comparison with NaN is false):
/// every floating-point option adds this check, so "--spacing nan" is refused, not taken as
/// "not given".
inline CLI::Validator finite_number() {
  return CLI::Validator(
      [](std::string& s) -> std::string {
        const auto v = detail::number_in(s);
        if (v && !std::isfinite(*v)) return "value " + s + " is not a finite number";
        return {};
      },
      "FINITE");
}

// CLI11's PositiveNumber, NonNegativeNumber and Range print their bounds with %f: "Value -1 not
// in range 0.000000 to 1797693134862315708145...000000" (309 digits), a range of 1e-9 to 10 as
// "0.000000 to 10.000000". These say what was wrong in the option's own terms instead.

/// A number > 0 ("--radius: value -1 is not positive (it must be > 0)").
inline CLI::Validator positive_number() {
  return CLI::Validator(
      [](std::string& s) -> std::string {
        const auto v = detail::number_in(s);
        if (v && !std::isnan(*v) && !(*v > 0)) return "value " + s + " is not positive (it must be > 0)";
        return {};
      },
      "POSITIVE");
}

/// A number >= 0.
inline CLI::Validator non_negative_number() {
  return CLI::Validator(
      [](std::string& s) -> std::string {
        const auto v = detail::number_in(s);
        if (v && !std::isnan(*v) && !(*v >= 0)) return "value " + s + " is negative (it must be >= 0)";
        return {};
      },
      "NONNEGATIVE");
}

/// A number in [lo, hi] ("--aniso-radius: value 0 is outside [1e-09, 10]").
template <class T>
CLI::Validator in_range(T lo, T hi) {
  const std::string a = detail::shortest(double(lo)), b = detail::shortest(double(hi));
  return CLI::Validator(
      [lo, hi, a, b](std::string& s) -> std::string {
        const auto v = detail::number_in(s);
        if (v && !std::isnan(*v) && !(*v >= double(lo) && *v <= double(hi)))
          return "value " + s + " is outside [" + a + ", " + b + "]";
        return {};
      },
      std::string(std::is_integral_v<T> ? "INT" : "FLOAT") + " in [" + a + " - " + b + "]");
}

void add_triangulate(CLI::App& root, std::vector<Command>& commands);
void add_inspect(CLI::App& root, std::vector<Command>& commands);
void add_sample(CLI::App& root, std::vector<Command>& commands);
void add_smooth(CLI::App& root, std::vector<Command>& commands);
void add_polygonize(CLI::App& root, std::vector<Command>& commands);
void add_render(CLI::App& root, std::vector<Command>& commands);

}  // namespace particlemesh::cli
