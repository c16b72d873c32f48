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

/// The text of a --report file.
std::string json_text(const nlohmann::json& j);

}  // namespace particlemesh::cli
