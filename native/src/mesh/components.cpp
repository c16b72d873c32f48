#include "particlemesh/mesh/components.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <string>

#include "core/disjoint_sets.h"
#include "mesh/orientation.h"
#include "particlemesh/core/error.h"
#include "mesh/compact_vertices.h"

namespace PM_NAMESPACE {

namespace {

constexpr uint32_t kUnused = std::numeric_limits<uint32_t>::max();

void check_indices(const TriMesh& mesh) {
  const size_t nv = mesh.positions.size();
  for (size_t t = 0; t < mesh.triangles.size(); ++t)
    for (int k = 0; k < 3; ++k)
      if (mesh.triangles[t][size_t(k)] >= nv)
        throw Error(Status::InvalidArgument, "triangles[" + std::to_string(t) + "] uses vertex " +
                                                 std::to_string(mesh.triangles[t][size_t(k)]) + " of " +
                                                 std::to_string(nv));
}

}  // namespace

MeshComponents mesh_components(const TriMesh& mesh) {
  check_indices(mesh);
  const size_t nv = mesh.positions.size();
  detail::DisjointSets sets(nv);
  for (const Triangle& t : mesh.triangles) {
    sets.unite(t[0], t[1]);
    sets.unite(t[0], t[2]);
  }
  auto find = [&](uint32_t x) { return sets.find(x); };
  MeshComponents c;
  c.vertex_component.assign(nv, kUnused);
  std::vector<uint32_t> root_id(nv, kUnused);
  std::vector<Vec3> origin;  // per component: a vertex of it, the origin of its volume sum
  for (const Triangle& t : mesh.triangles) {
    const uint32_t r = find(t[0]);
    if (root_id[r] == kUnused) {
      root_id[r] = uint32_t(c.triangles.size());
      c.triangles.push_back(0);
      c.area.push_back(0);
      c.volume.push_back(0);
      origin.push_back(mesh.positions[t[0]]);
    }
    const uint32_t id = root_id[r];
    const Vec3 o = origin[id];
    const Vec3 a = mesh.positions[t[0]] - o, b = mesh.positions[t[1]] - o, d = mesh.positions[t[2]] - o;
    ++c.triangles[id];
    c.area[id] += 0.5 * norm(cross(b - a, d - a));
    // Relative to a vertex of the piece: no cancellation far from the world origin.
    c.volume[id] += detail::signed_volume6(o, mesh.positions[t[0]], mesh.positions[t[1]], mesh.positions[t[2]]) / 6.0;
  }
  for (size_t v = 0; v < nv; ++v) {
    const uint32_t r = root_id[find(uint32_t(v))];
    c.vertex_component[v] = r;  // kUnused for a vertex without triangles
  }
  return c;
}

size_t remove_small_components(TriMesh& mesh, double min_volume) {
  if (std::isnan(min_volume)) throw Error(Status::InvalidArgument, "min_volume is NaN");
  check_indices(mesh);
  if (!(min_volume > 0) || mesh.triangles.empty()) return 0;
  const MeshComponents c = mesh_components(mesh);
  std::vector<char> drop(c.triangles.size(), 0);
  size_t dropped = 0;
  for (size_t i = 0; i < drop.size(); ++i)
    if (std::abs(c.volume[i]) < min_volume) {
      drop[i] = 1;
      ++dropped;
    }
  if (dropped == 0) return 0;
  // Keep the vertices of kept pieces and the vertices no triangle used (they were not part
  // of any piece), in their order.
  const size_t nv = mesh.positions.size();
  std::vector<uint32_t> remap(nv, kUnused);
  uint32_t next = 0;
  for (size_t v = 0; v < nv; ++v) {
    const uint32_t id = c.vertex_component[v];
    if (id != kUnused && drop[id]) continue;
    remap[v] = next++;
  }
  detail::compact_vertices(mesh, remap, next, kUnused);
  size_t w = 0;
  for (size_t f = 0; f < mesh.triangles.size(); ++f) {
    const Triangle t = mesh.triangles[f];
    if (drop[c.vertex_component[t[0]]]) continue;
    // The kept triangles' values per corner move with them.
    for (VertexAttribute& a : mesh.corner_attributes) {
      const size_t k = 3 * size_t(a.components);
      if (a.values.size() == k * mesh.triangles.size())
        std::copy_n(a.values.begin() + ptrdiff_t(k * f), k, a.values.begin() + ptrdiff_t(k * w));
    }
    mesh.triangles[w++] = {remap[t[0]], remap[t[1]], remap[t[2]]};
  }
  for (VertexAttribute& a : mesh.corner_attributes)
    if (a.values.size() == 3 * size_t(a.components) * mesh.triangles.size()) a.values.resize(3 * size_t(a.components) * w);
  mesh.triangles.resize(w);
  return dropped;
}

}  // namespace particlemesh
