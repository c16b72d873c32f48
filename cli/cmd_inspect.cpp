// particlemesh inspect FILE [--json]: what a mesh is, topologically; for a file of particles
// (no triangles), what the meshing commands will read from it: the count, the bounds, the
// spacing, the normals and every channel with its range (the names --attributes and
// --radius-channel take). A mesh file the mesh reader refuses (FormatError) but the particle
// reader takes (a PLY of 1-corner faces, as meshio writes a point cloud) gets the particle
// report, with the mesh reader's message as "not a mesh" (--json: "not_a_mesh"). Particles
// also get what their local spacing measures of the sampling: the spread of the local
// spacings, the irregularity (and the longer reach triangulate gives it) and the thickness
// (a clean surface, a noisy one, a volume). A frame
// collection (.pvd, .series) lists its frames by time, as the sequences number them.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <exception>
#include <limits>
#include <memory>
#include <optional>
#include <sys/stat.h>
#include <vector>

#include "commands.h"
#include "particle_input.h"
#include "sampling_shape.h"
#include "particlemesh/core/error.h"
#include "particlemesh/io/frame_collection.h"
#include "particlemesh/io/mesh_io.h"
#include "particlemesh/mesh/topology_report.h"
#include "particlemesh/spatial/local_spacing.h"
#include "particlemesh/spatial/spacing.h"
#include "report_json.h"

namespace particlemesh::cli {

namespace {

std::string number(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.9g", v);
  return buf;
}

/// The particle summary, as JSON (the text form is printed from it).
nlohmann::json particle_summary(const std::string& path, const ParticleInput& in) {
  const PointCloud& c = in.cloud;
  nlohmann::json j;
  j["file"] = path;
  j["particles"] = c.size();
  double lo[3], hi[3];
  for (int a = 0; a < 3; ++a) lo[a] = hi[a] = c.positions[0][a];
  for (const Vec3& p : c.positions)
    for (int a = 0; a < 3; ++a) {
      lo[a] = std::min(lo[a], p[a]);
      hi[a] = std::max(hi[a], p[a]);
    }
  j["bounds"] = {{"min", {lo[0], lo[1], lo[2]}}, {"max", {hi[0], hi[1], hi[2]}}};
  try {
    const SpacingEstimate s = estimate_spacing(c.positions.data(), c.size());
    j["spacing"] = s.spacing;
    j["duplicate_points"] = s.duplicate_points;
    j["near_duplicates"] = s.near_duplicates;
    j["spacing_apart"] = s.spacing_apart;
  } catch (const Error& e) {
    // Too few or coinciding points: said, not fatal (the file itself read).
    j["spacing"] = nullptr;
    j["spacing_error"] = e.what();
  }
  // The local spacing measures a particle's neighbourhood from six neighbours on (fewer: the
  // irregularity and the thickness come out 0, which would read as an even, clean sampling).
  constexpr size_t kMeasurable = 7;
  if (!j["spacing"].is_null() && c.size() - j["duplicate_points"].get<size_t>() < kMeasurable) {
    j["sampling"] = nullptr;
    j["sampling_error"] = "fewer than " + std::to_string(kMeasurable) + " distinct particles: no neighbourhood to measure";
  } else if (!j["spacing"].is_null()) {
    try {
      LocalSpacing ls = estimate_local_spacing(c.positions.data(), c.size());
      // The spread of the local spacings, in units of the median nearest-neighbour distance.
      std::vector<double>& h = ls.spacing;
      auto at = [&](double f) {
        const auto k = h.begin() + ptrdiff_t(f * double(h.size() - 1));
        std::nth_element(h.begin(), k, h.end());
        return *k / ls.median_nn;
      };
      j["sampling"] = {{"local_spacing", {{"p10", at(0.1)}, {"median", at(0.5)}, {"p90", at(0.9)}}},
                       {"irregularity", ls.irregularity},
                       {"reach_factor", ls.reach_factor},
                       {"thickness", ls.thickness}};
    } catch (const Error& e) {
      j["sampling"] = nullptr;
      // Strays far from the rest: say how triangulate and polygonize go on without them.
      const std::string advised = with_far_outlier_advice(e, true);
      j["sampling_error"] = advised.empty() ? std::string(e.what()) : advised;
    }
  }
  j["normals"] = c.has_normals();
  j["channels"] = nlohmann::json::array();
  for (const VertexAttribute& a : c.attributes) {
    double mn = std::numeric_limits<double>::infinity(), mx = -mn;
    size_t non_finite = 0;
    for (const float v : a.values) {
      if (!std::isfinite(v)) {
        ++non_finite;
        continue;
      }
      mn = std::min(mn, double(v));
      mx = std::max(mx, double(v));
    }
    nlohmann::json c = {{"name", a.name}, {"components", a.components}, {"min", nullptr}, {"max", nullptr}};
    if (mn <= mx) c["min"] = mn, c["max"] = mx;
    if (non_finite > 0) c["non_finite"] = non_finite;  // NaN or infinite values, left out of the range
    j["channels"].push_back(c);
  }
  if (!in.report.is_null()) j["input"] = in.report;
  return j;
}

std::string describe_particles(const nlohmann::json& j, const std::string& read_summary) {
  std::string out = j["file"].get<std::string>() + "\n";
  auto line = [&](const std::string& key, const std::string& value) {
    std::string k = "  " + key;
    k.resize(16, ' ');
    out += k + value + "\n";
  };
  if (j.contains("not_a_mesh"))
    line("not a mesh", j["not_a_mesh"].get<std::string>() + "; read as particles");
  auto point = [](const nlohmann::json& p) {
    return "(" + number(p[0].get<double>()) + ", " + number(p[1].get<double>()) + ", " + number(p[2].get<double>()) + ")";
  };
  line("particles", std::to_string(j["particles"].get<size_t>()) +
                        (j.contains("duplicate_points") && j["duplicate_points"].get<size_t>() > 0
                             ? " (" + std::to_string(j["duplicate_points"].get<size_t>()) + " exact duplicates)"
                             : ""));
  line("bounds", point(j["bounds"]["min"]) + " to " + point(j["bounds"]["max"]));
  line("spacing", j["spacing"].is_null() ? "cannot be estimated: " + j["spacing_error"].get<std::string>()
                                         : number(j["spacing"].get<double>()) + " (median nearest-neighbour distance)");
  if (j.contains("near_duplicates") && j["near_duplicates"].get<size_t>() > 0)
    line("near copies", std::to_string(j["near_duplicates"].get<size_t>()) +
                            " particles lie ten times nearer to another than to every other (a scanner's first and last "
                            "returns, a cloud merged with a shifted copy): the spacing above is their offset; triangulate "
                            "sets them aside and measures the rest (spacing " + number(j["spacing_apart"].get<double>()) +
                            "), unlike the sampling below");
  if (j.contains("sampling") && !j["sampling"].is_null()) {
    const auto& sm = j["sampling"];
    char text[400];
    const double irregularity = sm["irregularity"].get<double>(), reach = sm["reach_factor"].get<double>();
    std::snprintf(text, sizeof text, "local spacing %.2g-%.2g x the spacing (10%%-90%%, median %.2g); nearest-neighbour "
                  "distances vary by %.0f%%: %s", sm["local_spacing"]["p10"].get<double>(),
                  sm["local_spacing"]["p90"].get<double>(), sm["local_spacing"]["median"].get<double>(),
                  100 * irregularity,
                  reach == 1 ? "an even sampling"
                             : "irregular, as particles dropped at random, for which triangulate lengthens its edge limits");
    std::string first = text;
    if (reach > 1) {
      std::snprintf(text, sizeof text, " %.3g x", reach);
      first += text;
    }
    line("sampling", first);
    const double thickness = sm["thickness"].get<double>();
    std::snprintf(text, sizeof text, "thickness %.2f: %s", thickness, thickness_meaning(thickness, has_pcl_preprocessing()));
    line("", text);
  } else if (j.contains("sampling_error")) {
    line("sampling", "cannot be measured: " + j["sampling_error"].get<std::string>());
  }
  line("normals", j["normals"].get<bool>() ? "yes" : "no");
  if (j["channels"].empty()) line("channels", "none");
  bool first = true;
  for (const auto& a : j["channels"]) {
    const int k = a["components"].get<int>();
    std::string range = a["min"].is_null() ? "no finite value"
                                           : number(a["min"].get<double>()) + " to " + number(a["max"].get<double>());
    if (a.contains("non_finite")) range += " (" + std::to_string(a["non_finite"].get<size_t>()) + " NaN or infinite)";
    line(first ? "channels" : "",
         a["name"].get<std::string>() + (k > 1 ? " (" + std::to_string(k) + " components)" : "") + ": " + range);
    first = false;
  }
  if (!read_summary.empty()) out += read_summary;
  return out;
}

/// A collection's frames (by time) and whether each file exists; JSON, printed from it.
nlohmann::json collection_summary(const std::string& path) {
  nlohmann::json j;
  j["file"] = path;
  j["frames"] = nlohmann::json::array();
  size_t n = 0;
  for (const CollectionFrame& f : read_frame_collection(path)) {
    struct stat st {};
    const bool exists = ::stat(f.path.c_str(), &st) == 0 && S_ISREG(st.st_mode);
    j["frames"].push_back({{"frame", n++}, {"time", f.time}, {"path", f.path}, {"exists", exists}});
  }
  return j;
}

std::string describe_collection(const nlohmann::json& j) {
  const auto& frames = j["frames"];
  size_t missing = 0;
  for (const auto& f : frames) missing += !f["exists"].get<bool>();
  const double first = frames.front()["time"].get<double>(), last = frames.back()["time"].get<double>();
  std::string out = j["file"].get<std::string>() + ": a collection of " + std::to_string(frames.size()) +
                    " frame" + (frames.size() == 1 ? "" : "s") + ", times " + number(first) + " to " + number(last) +
                    (missing ? ", " + std::to_string(missing) + " missing" : "") + "\n";
  // The first and last frames when there are many.
  const size_t shown = 20;
  for (size_t i = 0; i < frames.size(); ++i) {
    if (frames.size() > shown && i == shown / 2) {
      out += "  ... " + std::to_string(frames.size() - shown) + " more\n";
      i = frames.size() - shown / 2;
    }
    const auto& f = frames[i];
    char head[64];
    std::snprintf(head, sizeof head, "  frame %-5zu t = %-12s ", i, number(f["time"].get<double>()).c_str());
    out += head + f["path"].get<std::string>() + (f["exists"].get<bool>() ? "" : "  (missing: not a file)") + "\n";
  }
  return out;
}

}  // namespace

void add_inspect(CLI::App& root, std::vector<Command>& commands) {
  struct Args {
    std::string input;
    bool json = false;
  };
  auto args = std::make_shared<Args>();
  CLI::App* app = root.add_subcommand(
      "inspect",
      "Print the topology report of a mesh (.ply, .obj, .off, .stl, VTK), or for a file of particles (no triangles: "
      "any input the meshing commands read) their count, bounds, spacing, normals and channels with their ranges, "
      "or for a collection (.pvd, .series) its frames by time and which files are missing");
  app->add_option("file", args->input, "Mesh, particle file or frame collection")->required();
  app->add_flag("--json", args->json, "Print the report as JSON");
  commands.push_back({app, [args] {
                        if (is_frame_collection(args->input)) {
                          const nlohmann::json j = collection_summary(args->input);
                          std::printf("%s", args->json ? (j.dump(2) + "\n").c_str() : describe_collection(j).c_str());
                          return 0;
                        }
                        // Why the file is not read as a mesh when the mesh reader refused it.
                        std::exception_ptr mesh_error;
                        std::string not_a_mesh;
                        if (reads_format(args->input, false)) {
                          std::optional<TriMesh> mesh;
                          try {
                            mesh = read_mesh(args->input);
                          } catch (const Error& e) {
                            // A malformed mesh may still be particles, read as the meshing
                            // commands read them (meshio writes a point cloud's vertex cells
                            // as 1-corner PLY faces, which those commands skip).
                            if (e.status() != Status::FormatError) throw;
                            mesh_error = std::current_exception();
                            not_a_mesh = e.what();
                            const std::string prefix = "'" + args->input + "': ";
                            if (not_a_mesh.compare(0, prefix.size(), prefix) == 0) not_a_mesh.erase(0, prefix.size());
                          }
                          // A mesh file with vertices and no triangles is particles (a
                          // vertex-only PLY, a VTK particle file); an empty mesh stays a mesh.
                          if (mesh && (!mesh->triangles.empty() || mesh->positions.empty())) {
                            const TopologyReport r = topology_report(*mesh);
                            // Values per triangle corner (an OBJ's texture coordinates), by name.
                            std::vector<std::string> corners;
                            for (const VertexAttribute& a : mesh->corner_attributes)
                              corners.push_back(a.name + " (" + std::to_string(a.components) + " per corner)");
                            if (args->json) {
                              nlohmann::json j = to_json(r);
                              if (!corners.empty()) j["corner_attributes"] = corners;
                              if (!mesh->not_read.empty()) j["not_read"] = mesh->not_read;
                              std::printf("%s\n", j.dump(2).c_str());
                            } else {
                              std::string list;
                              for (const std::string& c : corners) list += (list.empty() ? "" : ", ") + c;
                              std::printf("%s\n%s%s%s", args->input.c_str(), describe(r).c_str(),
                                          list.empty() ? "" : ("  per corner    " + list + "\n").c_str(),
                                          not_read_line(mesh->not_read).c_str());
                            }
                            return 0;
                          }
                        }
                        auto read = [&] {
                          if (!mesh_error) return read_particles(args->input, ParticleInputArgs{}, 0);
                          try {
                            return read_particles(args->input, ParticleInputArgs{}, 0);
                          } catch (const Error& e) {
                            if (e.status() == Status::Cancelled) throw;
                            std::rethrow_exception(mesh_error);  // neither: the mesh reader's word
                          }
                        };
                        const ParticleInput in = read();
                        nlohmann::json j = particle_summary(args->input, in);
                        if (mesh_error) j["not_a_mesh"] = not_a_mesh;
                        if (args->json)
                          std::printf("%s\n", j.dump(2).c_str());
                        else
                          std::printf("%s", describe_particles(j, in.summary).c_str());
                        return 0;
                      }});
}

}  // namespace particlemesh::cli
