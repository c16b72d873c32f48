// The topology report written the plain way: serial, one global sort of all half-edges, the
// boundary loops walked around vertex fans. Kept in the tests only, as the reference the
// parallel topology_report() (native/src/mesh/topology_report.cpp) must agree with field for
// field, the loop sizes included.
#pragma once

#include <algorithm>
#include <numeric>
#include <vector>

#include "core/disjoint_sets.h"
#include "particlemesh/mesh/topology_report.h"

namespace particlemesh::reference {

namespace ref_detail {

struct HalfEdge {
  uint64_t key;   // (min << 32) | max
  uint32_t face;
  uint8_t corner; // the edge runs from corner to corner+1 of the face
  bool forward;   // from min to max
  bool operator<(const HalfEdge& o) const {
    return key != o.key ? key < o.key : (face != o.face ? face < o.face : corner < o.corner);
  }
};

uint64_t edge_key(uint32_t a, uint32_t b) {
  return a < b ? (uint64_t(a) << 32) | b : (uint64_t(b) << 32) | a;
}

}  // namespace ref_detail
using namespace ref_detail;

inline TopologyReport topology_report(const TriMesh& mesh) {
  TopologyReport r;
  const auto& T = mesh.triangles;
  const size_t F = T.size();
  const size_t V = mesh.positions.size();
  r.vertices = V;
  r.triangles = F;
  for (const Triangle& t : T)
    for (uint32_t v : t)
      if (v >= V) {
        // A report must not read out of bounds; treat the mesh as unusable.
        r.degenerate_triangles = F;
        return r;
      }

  // Degenerate and duplicate triangles.
  std::vector<uint8_t> degenerate(F, 0);
  for (size_t f = 0; f < F; ++f) {
    const Triangle& t = T[f];
    if (t[0] == t[1] || t[1] == t[2] || t[0] == t[2]) {
      degenerate[f] = 1;
    } else {
      const Vec3 n = cross(mesh.positions[t[1]] - mesh.positions[t[0]],
                           mesh.positions[t[2]] - mesh.positions[t[0]]);
      if (squared_norm(n) == 0) degenerate[f] = 1;
    }
    r.degenerate_triangles += degenerate[f];
  }
  {
    std::vector<Triangle> sorted(T);
    for (auto& t : sorted) std::sort(t.begin(), t.end());
    std::sort(sorted.begin(), sorted.end());
    for (size_t i = 1; i < sorted.size(); ++i) r.duplicate_triangles += sorted[i] == sorted[i - 1];
  }

  // Undirected edges with their triangles.
  std::vector<HalfEdge> he;
  he.reserve(3 * F);
  for (uint32_t f = 0; f < F; ++f)
    for (uint8_t c = 0; c < 3; ++c) {
      const uint32_t a = T[f][c], b = T[f][(c + 1) % 3];
      if (a == b) continue;
      he.push_back({edge_key(a, b), f, c, a < b});
    }
  std::sort(he.begin(), he.end());

  particlemesh::detail::DisjointSets faces(F);
  std::vector<uint8_t> used(V, 0);
  for (const Triangle& t : T)
    for (uint32_t v : t) used[v] = 1;
  r.vertices_used = size_t(std::count(used.begin(), used.end(), uint8_t(1)));

  // Per edge group: multiplicity, orientation, and component joins.
  std::vector<uint32_t> group_start;
  for (size_t i = 0; i < he.size(); ++i)
    if (i == 0 || he[i].key != he[i - 1].key) group_start.push_back(uint32_t(i));
  group_start.push_back(uint32_t(he.size()));
  const size_t E = group_start.size() - 1;
  r.edges = E;
  std::vector<uint8_t> edge_kind(E);  // 1 boundary, 2 manifold, 3 non-manifold
  std::vector<uint8_t> edge_conflict(E, 0);
  for (size_t e = 0; e < E; ++e) {
    const uint32_t b = group_start[e], en = group_start[e + 1];
    const uint32_t m = en - b;
    for (uint32_t i = b + 1; i < en; ++i) faces.unite(he[b].face, he[i].face);
    if (m == 1) {
      edge_kind[e] = 1;
      ++r.boundary_edges;
    } else if (m == 2) {
      edge_kind[e] = 2;
      ++r.manifold_edges;
      if (he[b].forward == he[b + 1].forward) {
        edge_conflict[e] = 1;
        ++r.orientation_conflicts;
      }
    } else {
      edge_kind[e] = 3;
      ++r.nonmanifold_edges;
    }
  }

  // Components, numbered by their lowest triangle.
  std::vector<uint32_t> comp(F);
  std::vector<uint32_t> root_to_comp(F, UINT32_MAX);
  size_t ncomp = 0;
  for (uint32_t f = 0; f < F; ++f) {
    const uint32_t root = faces.find(f);
    if (root_to_comp[root] == UINT32_MAX) root_to_comp[root] = uint32_t(ncomp++);
    comp[f] = root_to_comp[root];
  }
  std::vector<ComponentReport> C(ncomp);
  for (uint32_t f = 0; f < F; ++f) ++C[comp[f]].triangles;
  for (size_t e = 0; e < E; ++e) {
    auto& c = C[comp[he[group_start[e]].face]];
    ++c.edges;
    if (edge_kind[e] == 1) ++c.boundary_edges;
    if (edge_kind[e] == 3) ++c.nonmanifold_edges;
    if (edge_conflict[e]) c.consistently_oriented = true;  // reused below as "has conflict"
  }
  {
    std::vector<uint64_t> cv;
    cv.reserve(3 * F);
    for (uint32_t f = 0; f < F; ++f)
      for (uint32_t v : T[f]) cv.push_back((uint64_t(comp[f]) << 32) | v);
    std::sort(cv.begin(), cv.end());
    cv.erase(std::unique(cv.begin(), cv.end()), cv.end());
    for (uint64_t x : cv) ++C[x >> 32].vertices;
  }

  // Vertex fans: the link of a vertex (the opposite edges of its triangles) must be one path
  // or one cycle.
  std::vector<uint32_t> vf_off(V + 1, 0);
  for (const Triangle& t : T)
    for (uint32_t v : t) ++vf_off[v + 1];
  std::partial_sum(vf_off.begin(), vf_off.end(), vf_off.begin());
  std::vector<uint32_t> vf(vf_off[V]);
  {
    std::vector<uint32_t> fill(vf_off.begin(), vf_off.end() - 1);
    for (uint32_t f = 0; f < F; ++f)
      for (uint32_t v : T[f]) vf[fill[v]++] = f;
  }
  std::vector<uint8_t> vertex_bad(V, 0);
  { const size_t vb = 0, ve = V;
    std::vector<std::pair<uint32_t, uint32_t>> link;
    std::vector<uint32_t> ids, parent, degree;
    for (size_t v = vb; v < ve; ++v) {
      if (!used[v]) continue;
      link.clear();
      ids.clear();
      bool bad = false;
      for (uint32_t i = vf_off[v]; i < vf_off[v + 1]; ++i) {
        const Triangle& t = T[vf[i]];
        uint32_t x = UINT32_MAX, y = UINT32_MAX;
        int self = 0;
        for (uint32_t w : t) {
          if (w == v) { ++self; continue; }
          (x == UINT32_MAX ? x : y) = w;
        }
        if (self != 1 || y == UINT32_MAX || x == y) { bad = true; continue; }
        link.emplace_back(x, y);
        ids.push_back(x);
        ids.push_back(y);
      }
      std::sort(ids.begin(), ids.end());
      ids.erase(std::unique(ids.begin(), ids.end()), ids.end());
      auto local = [&](uint32_t w) {
        return uint32_t(std::lower_bound(ids.begin(), ids.end(), w) - ids.begin());
      };
      parent.resize(ids.size());
      std::iota(parent.begin(), parent.end(), 0u);
      degree.assign(ids.size(), 0);
      auto find = [&](uint32_t x) {
        while (parent[x] != x) x = parent[x] = parent[parent[x]];
        return x;
      };
      size_t parts = ids.size();
      for (auto [x, y] : link) {
        const uint32_t a = local(x), b = local(y);
        if (++degree[a] > 2 || ++degree[b] > 2) bad = true;
        const uint32_t ra = find(a), rb = find(b);
        if (ra != rb) {
          parent[ra] = rb;
          --parts;
        }
      }
      if (parts != 1) bad = true;
      vertex_bad[v] = bad;
    }
  }
  r.nonmanifold_vertices = size_t(std::count(vertex_bad.begin(), vertex_bad.end(), uint8_t(1)));
  std::vector<uint8_t> comp_bad_vertex(ncomp, 0);
  for (uint32_t f = 0; f < F; ++f)
    for (uint32_t v : T[f])
      if (vertex_bad[v]) comp_bad_vertex[comp[f]] = 1;

  // Boundary loops.
  std::vector<uint32_t> loops_per_comp(ncomp, 0);
  const bool traceable = r.nonmanifold_edges == 0 && r.orientation_conflicts == 0;
  if (traceable && r.boundary_edges > 0) {
    // Directed half-edge (from, to) -> face, for walking around a vertex's fan.
    auto find_half = [&](uint32_t from, uint32_t to) -> int64_t {
      const uint64_t key = edge_key(from, to);
      auto it = std::lower_bound(he.begin(), he.end(), key,
                                 [](const HalfEdge& h, uint64_t k) { return h.key < k; });
      for (; it != he.end() && it->key == key; ++it) {
        const Triangle& t = T[it->face];
        if (t[it->corner] == from && t[(it->corner + 1) % 3] == to) return it->face;
      }
      return -1;
    };
    std::vector<size_t> bidx;  // index into he of each boundary half-edge
    for (size_t e = 0; e < E; ++e)
      if (edge_kind[e] == 1) bidx.push_back(group_start[e]);
    // Map directed boundary edge -> position in bidx via the half-edge's start vertex.
    std::vector<uint8_t> visited(bidx.size(), 0);
    auto boundary_slot = [&](uint32_t from, uint32_t to) -> int64_t {
      const uint64_t key = edge_key(from, to);
      auto it = std::lower_bound(bidx.begin(), bidx.end(), key,
                                 [&](size_t h, uint64_t k) { return he[h].key < k; });
      if (it == bidx.end() || he[*it].key != key) return -1;
      const HalfEdge& h = he[*it];
      const Triangle& t = T[h.face];
      if (t[h.corner] != from) return -1;
      return it - bidx.begin();
    };
    for (size_t start = 0; start < bidx.size(); ++start) {
      if (visited[start]) continue;
      size_t cur = start;
      size_t guard = 0, edges = 0;
      while (!visited[cur] && guard++ <= bidx.size()) {
        visited[cur] = 1;
        ++edges;
        const HalfEdge& h = he[bidx[cur]];
        const Triangle& t = T[h.face];
        const uint32_t b = t[(h.corner + 1) % 3];
        // Rotate around b from face h.face until an outgoing boundary half-edge appears.
        uint32_t f = h.face;
        int64_t next = -1;
        for (size_t steps = 0; steps <= vf_off[b + 1] - vf_off[b]; ++steps) {
          const Triangle& ft = T[f];
          const int cb = ft[0] == b ? 0 : (ft[1] == b ? 1 : 2);
          const uint32_t c = ft[(cb + 1) % 3];
          const int64_t slot = boundary_slot(b, c);
          if (slot >= 0) { next = slot; break; }
          const int64_t g = find_half(c, b);
          if (g < 0) break;
          f = uint32_t(g);
        }
        if (next < 0) break;
        cur = size_t(next);
      }
      ++r.boundary_loops;
      ++loops_per_comp[comp[he[bidx[start]].face]];
      r.boundary_loop_edges.push_back(edges);
    }
  } else if (r.boundary_edges > 0) {
    particlemesh::detail::DisjointSets verts(V);
    std::vector<uint8_t> on_boundary(V, 0);
    for (size_t e = 0; e < E; ++e) {
      if (edge_kind[e] != 1) continue;
      const uint32_t a = uint32_t(he[group_start[e]].key >> 32), b = uint32_t(he[group_start[e]].key);
      verts.unite(a, b);
      on_boundary[a] = on_boundary[b] = 1;
    }
    std::vector<uint8_t> counted(V, 0);
    std::vector<size_t> edges_at(V, 0);
    for (size_t e = 0; e < E; ++e) {
      if (edge_kind[e] != 1) continue;
      const uint32_t root = verts.find(uint32_t(he[group_start[e]].key >> 32));
      ++edges_at[root];
      if (!counted[root]) {
        counted[root] = 1;
        ++r.boundary_loops;
        ++loops_per_comp[comp[he[group_start[e]].face]];
      }
    }
    for (uint32_t v = 0; v < V; ++v)
      if (counted[v]) r.boundary_loop_edges.push_back(edges_at[v]);
  }
  std::sort(r.boundary_loop_edges.begin(), r.boundary_loop_edges.end());

  // Finish the per-component records.
  for (size_t c = 0; c < ncomp; ++c) {
    auto& cr = C[c];
    const bool conflict = cr.consistently_oriented;
    cr.consistently_oriented = !conflict && cr.nonmanifold_edges == 0;
    cr.boundary_loops = loops_per_comp[c];
    cr.euler_characteristic = int64_t(cr.vertices) - int64_t(cr.edges) + int64_t(cr.triangles);
    cr.manifold = cr.nonmanifold_edges == 0 && !comp_bad_vertex[c];
    cr.closed = cr.manifold && cr.boundary_edges == 0;
    if (cr.manifold) {
      const int64_t twice = 2 - cr.euler_characteristic - int64_t(cr.boundary_loops);
      cr.genus = twice >= 0 && twice % 2 == 0 ? int(twice / 2) : -1;
    }
  }
  // Signed volumes of closed components, about each component's first vertex for accuracy.
  {
    std::vector<Vec3> anchor(ncomp);
    std::vector<uint8_t> has_anchor(ncomp, 0);
    std::vector<double> vol(ncomp, 0.0);
    for (uint32_t f = 0; f < F; ++f) {
      const uint32_t c = comp[f];
      if (!C[c].closed) continue;
      if (!has_anchor[c]) { anchor[c] = mesh.positions[T[f][0]]; has_anchor[c] = 1; }
      const Vec3 a = mesh.positions[T[f][0]] - anchor[c];
      const Vec3 b = mesh.positions[T[f][1]] - anchor[c];
      const Vec3 d = mesh.positions[T[f][2]] - anchor[c];
      vol[c] += dot(a, cross(b, d)) / 6.0;
    }
    for (size_t c = 0; c < ncomp; ++c) C[c].signed_volume = vol[c];
  }

  r.components = ncomp;
  r.euler_characteristic = int64_t(r.vertices_used) - int64_t(r.edges) + int64_t(r.triangles);
  r.manifold = r.nonmanifold_edges == 0 && r.nonmanifold_vertices == 0;
  r.closed = r.manifold && r.boundary_edges == 0 && F > 0;
  r.consistently_oriented = r.orientation_conflicts == 0 && r.nonmanifold_edges == 0;
  r.outward = true;
  for (const auto& c : C) {
    if (c.closed) {
      ++r.closed_components;
      if (!(c.signed_volume > 0)) r.outward = false;
    }
  }
  if (r.closed_components == 0) r.outward = false;
  std::vector<size_t> order(ncomp);
  std::iota(order.begin(), order.end(), size_t(0));
  std::stable_sort(order.begin(), order.end(),
                   [&](size_t a, size_t b) { return C[a].triangles > C[b].triangles; });
  r.per_component.reserve(ncomp);
  for (size_t i : order) r.per_component.push_back(C[i]);
  return r;
}

}  // namespace particlemesh
