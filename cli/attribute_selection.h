// --attributes: which per-particle channels (velocity, density, id, colour...) travel to the
// mesh's vertices. The default, "all", keeps every channel the input file carries; "none"
// keeps none; a comma-separated list keeps those, in the file's order, and refuses a name the
// file does not carry (so a typo is not a silently missing channel).
#pragma once

#include <algorithm>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "particlemesh/core/error.h"
#include "particlemesh/mesh/point_cloud.h"

namespace particlemesh::cli {

inline void add_attributes_option(CLI::App& app, std::string& spec) {
  app.add_option("--attributes", spec,
                 "Per-particle channels written on the mesh's vertices: all (every channel of the input: velocity, "
                 "density, id, colour...), none, or a comma-separated list of names, e.g. velocity,density. PLY "
                 "gets vertex properties named after the channel (name, or name_0..name_k for vectors; colour as "
                 "red green blue), .vtk/.vtu/.vtp point-data arrays; OBJ carries colour only")
      ->capture_default_str();
}

/// Keep the channels `spec` names. @throws Error(InvalidArgument) for a name the cloud lacks.
inline void select_attributes(PointCloud& cloud, const std::string& spec) {
  if (spec.empty() || spec == "all") return;
  if (spec == "none") {
    cloud.attributes.clear();
    return;
  }
  std::vector<std::string> names;
  for (size_t start = 0; start <= spec.size();) {
    const size_t comma = std::min(spec.find(',', start), spec.size());
    if (comma > start) names.push_back(spec.substr(start, comma - start));
    start = comma + 1;
  }
  for (const std::string& n : names) {
    if (std::none_of(cloud.attributes.begin(), cloud.attributes.end(),
                     [&](const VertexAttribute& a) { return a.name == n; })) {
      std::string have;
      for (const VertexAttribute& a : cloud.attributes) have += (have.empty() ? "" : ", ") + a.name;
      throw Error(Status::InvalidArgument, "--attributes: the particles carry no '" + n + "' (they carry: " +
                                               (have.empty() ? std::string("none") : have) + ")");
    }
  }
  std::erase_if(cloud.attributes, [&](const VertexAttribute& a) {
    return std::find(names.begin(), names.end(), a.name) == names.end();
  });
}

}  // namespace particlemesh::cli
