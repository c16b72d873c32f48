// JSON and text renderings of the library's reports, for --report, --json and summaries.
#pragma once

#include <string>

#include <nlohmann/json.hpp>

#include "particlemesh/mesh/topology_report.h"
#include "particlemesh/surface/reconstruct.h"
#include "particlemesh/surface/triangulate.h"

namespace particlemesh::cli {

nlohmann::json to_json(const TopologyReport& r);
nlohmann::json to_json(const TriangulateStats& s);
nlohmann::json to_json(const SurfaceStats& s);

/// A few lines describing the mesh, for people.
std::string describe(const TopologyReport& r);

/// The summary's last lines: describe(r), then the time of the run: reading, `work`
/// ("smooth", ...) and writing, in seconds.
void print_mesh_and_times(const TopologyReport& r, const char* work, double t_read, double t_work, double t_write);

/// The text of a --report file.
std::string json_text(const nlohmann::json& j);

}  // namespace particlemesh::cli
