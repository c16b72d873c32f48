#include "report_json.h"

#include <cmath>
#include <cstdio>
#include <sstream>


namespace particlemesh::cli {

nlohmann::json to_json(const TopologyReport& r) {
  nlohmann::json comps = nlohmann::json::array();
  for (const auto& c : r.per_component) {
    comps.push_back({{"triangles", c.triangles},
                     {"vertices", c.vertices},
                     {"edges", c.edges},
                     {"boundary_edges", c.boundary_edges},
                     {"nonmanifold_edges", c.nonmanifold_edges},
                     {"boundary_loops", c.boundary_loops},
                     {"euler_characteristic", c.euler_characteristic},
                     {"closed", c.closed},
                     {"manifold", c.manifold},
                     {"consistently_oriented", c.consistently_oriented},
                     {"genus", c.genus},
                     {"signed_volume", c.signed_volume},
                     {"nesting_depth", c.nesting_depth}});
  }
  return {{"vertices", r.vertices},
          {"triangles", r.triangles},
          {"vertices_used", r.vertices_used},
          {"edges", r.edges},
          {"boundary_edges", r.boundary_edges},
          {"manifold_edges", r.manifold_edges},
          {"nonmanifold_edges", r.nonmanifold_edges},
          {"nonmanifold_vertices", r.nonmanifold_vertices},
          {"degenerate_triangles", r.degenerate_triangles},
          {"duplicate_triangles", r.duplicate_triangles},
          {"orientation_conflicts", r.orientation_conflicts},
          {"boundary_loops", r.boundary_loops},
          {"components", r.components},
          {"closed_components", r.closed_components},
          {"euler_characteristic", r.euler_characteristic},
          {"manifold", r.manifold},
          {"closed", r.closed},
          {"consistently_oriented", r.consistently_oriented},
          {"outward", r.outward},
          {"per_component", comps}};
}

nlohmann::json to_json(const TriangulateStats& s) {
  return {{"spacing", s.spacing},
          {"spacing_estimated", s.spacing_estimated},
          {"max_edge", s.max_edge},
          {"points", s.points},
          {"duplicate_points", s.duplicate_points},
          {"near_duplicates", s.near_duplicates},
          {"max_neighbors_seen", s.max_neighbors_seen},
          {"triplets", s.triplets},
          {"candidates", s.candidates},
          {"degenerate_triplets", s.degenerate},
          {"ties", s.ties},
          {"kept", s.kept},
          {"sampling_irregularity", s.sampling_irregularity},
          {"reach_factor", s.reach_factor},
          {"sampling_thickness", s.sampling_thickness},
          {"uncapped_spacing_p90", s.uncapped_spacing_p90},
          {"capped_spacing_over_nn", s.capped_spacing_over_nn},
          {"shortened_limits", s.shortened_limits},
          {"seconds", {{"spacing", s.seconds_spacing}, {"neighbors", s.seconds_neighbors}, {"test", s.seconds_test}}}};
}

nlohmann::json to_json(const SurfaceStats& s) {
  nlohmann::json loops = nlohmann::json::array();
  for (const auto& l : s.open_loops) loops.push_back({{"edges", l.edges}, {"width_over_L", std::isfinite(l.width) ? nlohmann::json(l.width) : nlohmann::json(nullptr)}});
  return {{"open_loops", loops},
          {"normals_estimated", s.normals_estimated},
          {"candidates", s.candidates},
          {"rejected_conormal", s.rejected_conormal},
          {"looks_like_volume", s.looks_like_volume},
          {"grown", s.grown},
          {"seeds", s.seeds},
          {"pinches_resolved", s.pinches_resolved},
          {"small_handles_removed", s.small_handles_removed},
          {"holes_filled", s.holes_filled},
          {"hole_triangles", s.hole_triangles},
          {"holes_left", s.holes_left},
          {"largest_hole_left", s.largest_hole_left},
          {"narrow_loops", {{"count", s.narrow_loops.count}, {"width_over_L", s.narrow_loops.width},
                            {"edges", s.narrow_loops.edges}}},
          {"components_flipped", s.components_flipped},
          {"flat_pieces_opened", s.flat_pieces_opened},
          {"nearly_closed_turned", s.nearly_closed_turned},
          {"folded_triangles", s.folded_triangles},
          {"unused_points", s.unused_points},
          {"components_removed", s.components_removed},
          {"component_triangles_removed", s.component_triangles_removed},
          {"stray_pieces", {{"count", s.stray_pieces.count}, {"triangles", s.stray_pieces.triangles},
                            {"largest", s.stray_pieces.largest}}},
          {"local_spacing", {{"unit", "r0"}, {"min", s.local_spacing.min}, {"p10", s.local_spacing.p10},
                             {"median", s.local_spacing.median}, {"p90", s.local_spacing.p90}, {"max", s.local_spacing.max}}},
          {"viewpoint_used", s.viewpoint_used},
          {"rejected_shadow", s.rejected_shadow},
          {"seconds", {{"normals", s.seconds_normals}, {"extraction", s.seconds_extraction}, {"repair", s.seconds_repair}, {"orient", s.seconds_orient}}}};
}

void print_mesh_and_times(const TopologyReport& r, const char* work, double t_read, double t_work, double t_write) {
  std::printf("%s", describe(r).c_str());
  std::printf("  time          %.2f s (read %.2f, %s %.2f, write %.2f)\n", t_read + t_work + t_write, t_read, work, t_work,
              t_write);
}

std::string describe(const TopologyReport& r) {
  std::ostringstream o;
  o << "  vertices      " << r.vertices << " (" << r.vertices_used << " used)\n";
  o << "  triangles     " << r.triangles << "\n";
  o << "  edges         " << r.edges << ": " << r.boundary_edges << " boundary, " << r.manifold_edges
    << " shared by 2, " << r.nonmanifold_edges << " shared by >2\n";
  o << "  components    " << r.components << " (" << r.closed_components << " closed), "
    << r.boundary_loops << " boundary loop" << (r.boundary_loops == 1 ? "" : "s") << "\n";
  o << "  euler char.   " << r.euler_characteristic;
  if (!r.per_component.empty() && r.per_component.size() <= 8) {
    o << "  (genus per component:";
    for (const auto& c : r.per_component) o << ' ' << (c.genus >= 0 ? std::to_string(c.genus) : std::string("-"));
    o << ')';
  }
  o << "\n";
  o << "  manifold      " << (r.manifold ? "yes" : "no") << " (" << r.nonmanifold_vertices
    << " non-manifold vertices)\n";
  o << "  oriented      " << (r.consistently_oriented ? "consistently" : "no") << " ("
    << r.orientation_conflicts << " conflicts)" << (r.closed_components ? (r.outward ? ", closed parts face outward" : ", some closed part faces into its solid") : "") << "\n";
  if (r.degenerate_triangles || r.duplicate_triangles)
    o << "  defects       " << r.degenerate_triangles << " degenerate, " << r.duplicate_triangles << " duplicate triangles\n";
  return o.str();
}

std::string json_text(const nlohmann::json& j) { return j.dump(2) + "\n"; }

}  // namespace particlemesh::cli
