#include "smooth/control_mesh.h"

#include <algorithm>
#include <climits>
#include <cmath>
#include <numeric>
#include <string>

#include "core/disjoint_sets.h"
#include "core/format_number.h"
#include "core/parallel.h"
#include "mesh/orientation.h"
#include "particlemesh/core/error.h"
#include "particlemesh/smooth/subdivide.h"

namespace PM_NAMESPACE::detail {

namespace {

constexpr uint32_t kNone = UINT32_MAX;

std::string edge_name(uint32_t a, uint32_t b) {
  return "edge (" + std::to_string(a) + ", " + std::to_string(b) + ")";
}

void check_sizes(const TriMesh& mesh) {
  const size_t nv = mesh.positions.size(), nf = mesh.triangles.size();
  if (nf == 0) throw Error(Status::InvalidInput, "the mesh has no triangles: nothing to smooth");
  if (nv > size_t(INT32_MAX))
    throw Error(Status::LimitExceeded, "the mesh has " + std::to_string(nv) +
                                           " vertices; at most 2^31 - 1 can be smoothed");
  if (nf > size_t(INT32_MAX) / 3)
    throw Error(Status::LimitExceeded, "the mesh has " + std::to_string(nf) +
                                           " triangles; at most (2^31 - 1) / 3 can be smoothed");
  for (const auto& a : mesh.attributes) {
    if (a.components < 1 || a.components > 4096 || a.values.size() != nv * size_t(a.components))
      throw Error(Status::InvalidInput, "attribute '" + a.name + "' has " + std::to_string(a.values.size()) +
                                            " values with " + std::to_string(a.components) +
                                            " components, expected " + std::to_string(nv) + " vertices x " +
                                            "components (1..4096)");
  }
}

void check_triangles(const TriMesh& mesh) {
  const size_t nv = mesh.positions.size();
  for (size_t f = 0; f < mesh.triangles.size(); ++f) {
    const Triangle& t = mesh.triangles[f];
    for (int c = 0; c < 3; ++c)
      if (t[c] >= nv)
        throw Error(Status::InvalidInput, "triangles[" + std::to_string(f) + "] refers to vertex " +
                                              std::to_string(t[c]) + " of " + std::to_string(nv));
    if (t[0] == t[1] || t[1] == t[2] || t[0] == t[2])
      throw Error(Status::InvalidInput, "triangles[" + std::to_string(f) + "] = (" + std::to_string(t[0]) + ", " +
                                            std::to_string(t[1]) + ", " + std::to_string(t[2]) +
                                            ") repeats a vertex (degenerate)");
  }
}

/// The signed volume (times 6) of a repaired component with its triangles flipped as
/// recorded, summed in flood-fill order.
double component_volume(const std::vector<Triangle>& tris, const std::vector<Vec3>& positions,
                        const ControlMesh::VolumeDecision& d) {
  double volume = 0;
  for (size_t i = 0; i < d.triangles.size(); ++i) {
    const Triangle& t = tris[d.triangles[i]];
    const double v6 = signed_volume6(Vec3{}, positions[t[0]], positions[t[1]], positions[t[2]]);
    volume += d.flips[i] ? -v6 : v6;
  }
  return volume;
}

}  // namespace

bool same_volume_decisions(const ControlMesh& control, const std::vector<Triangle>& triangles,
                           const std::vector<Vec3>& positions) {
  for (const auto& d : control.volume_decisions)
    if ((component_volume(triangles, positions, d) < 0) != d.turned) return false;
  return true;
}

void compact_vertex_values(const std::vector<Vec3>& positions, const std::vector<VertexAttribute>& attributes,
                           const std::vector<uint32_t>& original_vertex, std::vector<Vec3>* out_positions,
                           std::vector<VertexAttribute>* out_attributes) {
  const size_t nv = positions.size(), nc = original_vertex.size();
  for (const auto& a : attributes) {
    if (a.components < 1 || a.components > 4096 || a.values.size() != nv * size_t(a.components))
      throw Error(Status::InvalidInput, "attribute '" + a.name + "' has " + std::to_string(a.values.size()) +
                                            " values with " + std::to_string(a.components) +
                                            " components, expected " + std::to_string(nv) + " vertices x " +
                                            "components (1..4096)");
  }
  for (const uint32_t v : original_vertex) {
    const Vec3& p = positions[v];
    if (!is_finite(p)) throw Error(Status::InvalidInput, "positions[" + std::to_string(v) + "] is not finite");
    // Finite is not enough: Loop's and butterfly's sums of coordinates near DBL_MAX overflow
    // to infinity (found by fuzzing).
    if (std::max({std::abs(p.x), std::abs(p.y), std::abs(p.z)}) > kMaxSmoothCoordinate)
      throw Error(Status::InvalidInput, "positions[" + std::to_string(v) + "] = (" + detail::format_number(p.x) + ", " +
                                            detail::format_number(p.y) + ", " + detail::format_number(p.z) +
                                            ") is too large to smooth (coordinates must be at most 1e50 in magnitude)");
  }
  out_positions->resize(nc);
  for (size_t i = 0; i < nc; ++i) (*out_positions)[i] = positions[original_vertex[i]];
  out_attributes->clear();
  for (const auto& a : attributes) {
    VertexAttribute c{a.name, a.components, {}};
    const size_t k = size_t(a.components);
    c.values.resize(nc * k);
    for (size_t i = 0; i < nc; ++i)
      for (size_t j = 0; j < k; ++j) {
        const float x = a.values[size_t(original_vertex[i]) * k + j];
        if (!std::isfinite(x))
          throw Error(Status::InvalidInput, "attribute '" + a.name + "' of vertex " +
                                                std::to_string(original_vertex[i]) + " is not finite");
        if (std::abs(x) > kMaxSmoothAttribute)
          throw Error(Status::InvalidInput, "attribute '" + a.name + "' of vertex " +
                                                std::to_string(original_vertex[i]) + " is " + detail::format_number(x) +
                                                ": too large to smooth (at most 1e30 in magnitude)");
        c.values[i * k + j] = x;
      }
    out_attributes->push_back(std::move(c));
  }
}

ControlMesh prepare_control_mesh(const TriMesh& mesh, bool allow_nonmanifold) {
  check_sizes(mesh);
  check_triangles(mesh);
  const auto& tris = mesh.triangles;
  const size_t nv = mesh.positions.size(), nf = tris.size();
  ControlMesh cm;

  // 1. Referenced vertices, kept in input order; their values must be finite.
  std::vector<uint8_t> used(nv, 0);
  for (const auto& t : tris) used[t[0]] = used[t[1]] = used[t[2]] = 1;
  cm.control_index.assign(nv, ControlMesh::kDropped);
  for (size_t v = 0; v < nv; ++v)
    if (used[v]) {
      cm.control_index[v] = uint32_t(cm.original_vertex.size());
      cm.original_vertex.push_back(uint32_t(v));
    }
  cm.dropped_vertices = nv - cm.original_vertex.size();
  compact_vertex_values(mesh.positions, mesh.attributes, cm.original_vertex, &cm.positions, &cm.attributes);

  // 2. Half-edges h = 3 f + c, from tris[f][c] to tris[f][c + 1], grouped by undirected edge.
  auto from = [&](uint32_t h) { return tris[h / 3][h % 3]; };
  auto to = [&](uint32_t h) { return tris[h / 3][(h % 3 + 1) % 3]; };
  auto opposite = [&](uint32_t h) { return tris[h / 3][(h % 3 + 2) % 3]; };
  auto lo_of = [&](uint32_t h) { return std::min(from(h), to(h)); };
  auto hi_of = [&](uint32_t h) { return std::max(from(h), to(h)); };
  // Counting sort by the lower vertex, then each (short) bucket by (higher vertex, h): the
  // order is fixed by the data alone, and it is several times faster than a comparison sort.
  std::vector<uint32_t> bucket(nv + 1, 0);
  for (uint32_t h = 0; h < 3 * nf; ++h) ++bucket[lo_of(h) + 1];
  for (size_t v = 0; v < nv; ++v) bucket[v + 1] += bucket[v];
  std::vector<uint32_t> half(3 * nf);
  {
    std::vector<uint32_t> fill(bucket.begin(), bucket.end() - 1);
    for (uint32_t h = 0; h < 3 * nf; ++h) half[fill[lo_of(h)]++] = h;
  }
  parallel_blocks(nv, 4096, [&](size_t b, size_t e) {
    for (size_t v = b; v < e; ++v)
      std::sort(half.begin() + bucket[v], half.begin() + bucket[v + 1], [&](uint32_t x, uint32_t y) {
        const uint32_t hx = hi_of(x), hy = hi_of(y);
        return hx != hy ? hx < hy : x < y;
      });
  });

  std::vector<uint32_t> twin(3 * nf, kNone);
  std::vector<uint8_t> same_direction(3 * nf, 0);
  DisjointSets corners(3 * nf);  // corner 3 f + c is vertex tris[f][c] in triangle f
  cm.edges.reserve(3 * nf / 2 + 1);
  for (size_t i = 0; i < half.size();) {
    const uint32_t lo = lo_of(half[i]), hi = hi_of(half[i]);
    size_t j = i + 1;
    while (j < half.size() && hi_of(half[j]) == hi && lo_of(half[j]) == lo) ++j;
    cm.edges.push_back({lo, hi});
    const size_t n = j - i;
    if (n == 1) {
      ++cm.boundary_edges;
    } else if (n > 2) {
      if (!allow_nonmanifold)
        throw Error(Status::InvalidInput, edge_name(lo, hi) + " is shared by " + std::to_string(n) +
                                              " triangles (non-manifold); the butterfly scheme needs every edge in "
                                              "one or two triangles (the Loop scheme smooths such meshes)");
      // No twins: the orientation's flood fill does not cross it (each sheet is oriented on
      // its own), and OpenSubdiv makes it an infinitely sharp crease.
      ++cm.nonmanifold_edges;
    } else {
      const uint32_t h0 = half[i], h1 = half[i + 1];
      if (opposite(h0) == opposite(h1))
        throw Error(Status::InvalidInput, "triangles[" + std::to_string(h0 / 3) + "] and triangles[" +
                                              std::to_string(h1 / 3) + "] use the same three vertices");
      const bool same = from(h0) == from(h1);
      twin[h0] = h1;
      twin[h1] = h0;
      same_direction[h0] = same_direction[h1] = same;
      // The edge joins the corners of its two end vertices in both triangles.
      const uint32_t f0 = h0 / 3 * 3, f1 = h1 / 3 * 3, c0 = h0 % 3, c1 = h1 % 3;
      corners.unite(f0 + c0, f1 + (same ? c1 : (c1 + 1) % 3));
      corners.unite(f0 + (c0 + 1) % 3, f1 + (same ? (c1 + 1) % 3 : c1));
    }
    i = j;
  }

  // 3. Every vertex must be a single fan: all its corners connected through shared edges.
  {
    std::vector<uint32_t> fan(nv, kNone);
    constexpr uint32_t kSeveral = kNone - 1;
    for (uint32_t corner = 0; corner < 3 * nf; ++corner) {
      const uint32_t v = tris[corner / 3][corner % 3];
      const uint32_t root = corners.find(corner);
      if (fan[v] == kNone) {
        fan[v] = root;
      } else if (fan[v] != root && fan[v] != kSeveral) {
        if (!allow_nonmanifold)
          throw Error(Status::InvalidInput, "vertex " + std::to_string(v) +
                                                " joins separate fans of triangles (non-manifold vertex); the "
                                                "butterfly scheme needs a single fan (the Loop scheme smooths such "
                                                "meshes)");
        fan[v] = kSeveral;
        ++cm.nonmanifold_vertices;
      }
    }
  }

  // 4. Orientation: flood fill each edge-connected component from its lowest triangle.
  std::vector<uint8_t> flip(nf, 0);
  {
    std::vector<uint32_t> component(nf, kNone);
    std::vector<uint32_t> queue;
    queue.reserve(nf);
    uint32_t next_id = 0;
    for (uint32_t seed = 0; seed < nf; ++seed) {
      if (component[seed] != kNone) continue;
      const uint32_t id = next_id++;
      const size_t begin = queue.size();
      component[seed] = id;
      queue.push_back(seed);
      bool conflict = false, closed = true;
      for (size_t q = begin; q < queue.size(); ++q) {
        const uint32_t f = queue[q];
        for (uint32_t c = 0; c < 3; ++c) {
          const uint32_t h = 3 * f + c, t = twin[h];
          if (t == kNone) {
            closed = false;
            continue;
          }
          conflict |= same_direction[h] != 0;
          const uint32_t g = t / 3;
          const uint8_t want = flip[f] ^ same_direction[h];
          if (component[g] == kNone) {
            component[g] = id;
            flip[g] = want;
            queue.push_back(g);
          } else if (flip[g] != want) {
            throw Error(Status::InvalidInput,
                        "the triangles connected to triangles[" + std::to_string(seed) +
                            "] form a non-orientable surface (like a Moebius strip): they cannot be "
                            "oriented consistently");
          }
        }
      }
      if (!conflict) continue;  // consistent already: the caller's winding stays
      if (closed) {
        // Turn a repaired closed component outward: positive signed volume.
        ControlMesh::VolumeDecision d;
        d.triangles.assign(queue.begin() + ptrdiff_t(begin), queue.end());
        for (const uint32_t f : d.triangles) d.flips.push_back(flip[f]);
        d.turned = component_volume(tris, mesh.positions, d) < 0;
        if (d.turned)
          for (size_t q = begin; q < queue.size(); ++q) flip[queue[q]] ^= 1;
        cm.volume_decisions.push_back(std::move(d));
      }
    }
  }

  // 5. Triangles in control indices, flipped where the repair says so.
  cm.triangles.resize(nf);
  parallel_blocks(nf, 4096, [&](size_t b, size_t e) {
    for (size_t f = b; f < e; ++f) {
      const Triangle& t = tris[f];
      Triangle c{cm.control_index[t[0]], cm.control_index[t[1]], cm.control_index[t[2]]};
      if (flip[f]) std::swap(c[1], c[2]);
      cm.triangles[f] = c;
    }
  });
  cm.reoriented_triangles = size_t(std::count(flip.begin(), flip.end(), uint8_t(1)));
  return cm;
}

std::vector<Vec3> area_weighted_normals(const std::vector<Vec3>& positions,
                                        const std::vector<Triangle>& triangles) {
  // Scattering in triangle order on one thread keeps the sums (and so the bits) independent
  // of the thread count; it costs a few ns per triangle.
  std::vector<Vec3> n(positions.size());
  for (const auto& t : triangles) {
    const Vec3 c = cross(positions[t[1]] - positions[t[0]], positions[t[2]] - positions[t[0]]);
    n[t[0]] += c;
    n[t[1]] += c;
    n[t[2]] += c;
  }
  parallel_blocks(n.size(), 8192, [&](size_t b, size_t e) {
    for (size_t i = b; i < e; ++i) n[i] = normalized(n[i]);
  });
  return n;
}

}  // namespace particlemesh::detail
