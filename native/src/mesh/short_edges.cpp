#include "mesh/short_edges.h"

#include "core/parallel.h"
#include "mesh/compact_vertices.h"

#include <algorithm>
#include <cmath>
#include <iterator>
#include <limits>

namespace PM_NAMESPACE::detail {

namespace {

constexpr uint32_t kNone = std::numeric_limits<uint32_t>::max();

struct Candidate {
  double length2;
  uint32_t a, b;  // a < b
};

}  // namespace

ShortEdgeCollapse collapse_short_edges(TriMesh& mesh, double max_length, double min_cos,
                                       const std::function<Vec3(const Vec3&, const Vec3&)>& place,
                                       const std::function<void()>& check) {
  ShortEdgeCollapse out;
  std::vector<Vec3>& P = mesh.positions;
  std::vector<Triangle>& T = mesh.triangles;
  const size_t nv = P.size(), nt = T.size();
  if (!(max_length > 0) || nt == 0) return out;
  const double limit2 = max_length * max_length;

  // Each short edge once: from the triangle that runs it from its lower vertex to its higher
  // (a closed oriented surface runs every edge once each way).
  std::vector<Candidate> cand;
  for (const Triangle& t : T)
    for (int k = 0; k < 3; ++k) {
      const uint32_t a = t[k], b = t[(k + 1) % 3];
      if (a >= b) continue;
      const double l2 = squared_norm(P[a] - P[b]);
      if (l2 < limit2) cand.push_back({l2, a, b});
    }
  if (cand.empty()) return out;
  std::sort(cand.begin(), cand.end(), [](const Candidate& x, const Candidate& y) {
    return x.length2 != y.length2 ? x.length2 < y.length2 : x.a != y.a ? x.a < y.a : x.b < y.b;
  });
  cand.erase(std::unique(cand.begin(), cand.end(),
                         [](const Candidate& x, const Candidate& y) { return x.a == y.a && x.b == y.b; }),
             cand.end());
  // Where each edge's merged vertex would go, from its ends as they are now, in parallel (the
  // caller's placement can be costly: polygonize's evaluates the field). The collapses below
  // use it while neither end has moved, and place the vertex again otherwise: the same
  // result, whatever the thread count.
  if (check) check();
  std::vector<Vec3> planned(cand.size());
  parallel_blocks(cand.size(), 1024, [&](size_t begin, size_t end) {
    for (size_t k = begin; k < end; ++k) planned[k] = place(P[cand[k].a], P[cand[k].b]);
  });
  if (check) check();

  // Each vertex's triangles (ascending), fixed; a vertex that took in others reaches theirs
  // through its chain (`next`), and a removed triangle is skipped.
  std::vector<uint32_t> first(nv + 1, 0), list(3 * nt);
  for (const Triangle& t : T)
    for (uint32_t v : t) ++first[v + 1];
  for (size_t v = 0; v < nv; ++v) first[v + 1] += first[v];
  {
    std::vector<uint32_t> fill(first.begin(), first.end() - 1);
    for (size_t i = 0; i < nt; ++i)
      for (uint32_t v : T[i]) list[fill[v]++] = uint32_t(i);
  }
  std::vector<uint32_t> next(nv, kNone), tail(nv);
  for (size_t v = 0; v < nv; ++v) tail[v] = uint32_t(v);
  std::vector<uint8_t> removed_v(nv, 0), removed_t(nt, 0), moved(nv, 0);
  auto for_triangles = [&](uint32_t v, auto&& fn) {
    for (uint32_t u = v; u != kNone; u = next[u])
      for (uint32_t j = first[u]; j < first[u + 1]; ++j)
        if (!removed_t[list[j]]) fn(list[j]);
  };
  // A vertex on a boundary or a non-manifold edge: some neighbour is met other than exactly
  // twice among its triangles' corners.
  std::vector<uint32_t> na, nb, common;
  auto neighbours = [&](uint32_t v, std::vector<uint32_t>& n) {
    n.clear();
    for_triangles(v, [&](uint32_t i) {
      for (uint32_t u : T[i])
        if (u != v) n.push_back(u);
    });
    std::sort(n.begin(), n.end());
    for (size_t i = 0; i < n.size(); i += 2)
      if (i + 1 >= n.size() || n[i] != n[i + 1] || (i + 2 < n.size() && n[i + 2] == n[i])) return false;
    n.erase(std::unique(n.begin(), n.end()), n.end());
    return true;
  };
  auto triangle_count = [&](uint32_t v) {
    size_t c = 0;
    for_triangles(v, [&](uint32_t) { ++c; });
    return c;
  };

  const bool has_normals = mesh.normals.size() == nv;
  for (size_t k = 0; k < cand.size(); ++k) {
    if (check && (k & 4095) == 4095) check();
    const uint32_t a = cand[k].a, b = cand[k].b;
    if (removed_v[a] || removed_v[b]) continue;
    if (!(squared_norm(P[a] - P[b]) < limit2)) continue;
    // The two triangles of the edge, one running a -> b and one b -> a; c, d their third corners.
    uint32_t shared[2], third[2];
    int count = 0, forward = 0;
    for_triangles(a, [&](uint32_t i) {
      const Triangle& t = T[i];
      for (int j = 0; j < 3; ++j)
        if (t[j] == b) {
          if (count < 2) {
            shared[count] = i;
            third[count] = t[0] ^ t[1] ^ t[2] ^ a ^ b;
          }
          ++count;
          forward += t[(j + 2) % 3] == a;  // a, then b
        }
    });
    if (count != 2 || forward != 1 || third[0] == third[1]) continue;
    if (!neighbours(a, na) || !neighbours(b, nb)) continue;
    common.clear();
    std::set_intersection(na.begin(), na.end(), nb.begin(), nb.end(), std::back_inserter(common));
    const uint32_t c = std::min(third[0], third[1]), d = std::max(third[0], third[1]);
    if (common.size() != 2 || common[0] != c || common[1] != d) continue;
    // Neighbours after: a and b's less each other and the shared two; c and d one fewer.
    if (na.size() + nb.size() < 7 || triangle_count(c) < 4 || triangle_count(d) < 4) continue;
    const Vec3 p = moved[a] || moved[b] ? place(P[a], P[b]) : planned[k];
    if (!is_finite(p)) continue;
    // No other triangle at a or b turns too far or loses its area with them at p.
    bool ok = true;
    auto keeps_facing = [&](uint32_t v) {
      for_triangles(v, [&](uint32_t i) {
        if (!ok || i == shared[0] || i == shared[1]) return;
        Vec3 q[3], r[3];
        for (int j = 0; j < 3; ++j) {
          q[j] = P[T[i][j]];
          r[j] = T[i][j] == a || T[i][j] == b ? p : q[j];
        }
        const Vec3 n0 = cross(q[1] - q[0], q[2] - q[0]), n1 = cross(r[1] - r[0], r[2] - r[0]);
        const double l0 = norm(n0), l1 = norm(n1);
        if (!(l1 > 0) || !(dot(n0, n1) > min_cos * l0 * l1)) ok = false;
      });
    };
    keeps_facing(a);
    if (ok) keeps_facing(b);
    if (!ok) continue;

    // Collapse: b into a.
    P[a] = p;
    if (has_normals) {
      const Vec3 s = mesh.normals[a] + mesh.normals[b];
      const double l = norm(s);
      mesh.normals[a] = l > 0 ? s / l : mesh.normals[a];
    }
    for (VertexAttribute& at : mesh.attributes) {
      const size_t m = size_t(std::max(at.components, 1));
      if (at.values.size() != nv * m) continue;
      for (size_t j = 0; j < m; ++j)
        at.values[a * m + j] = float(0.5 * (double(at.values[a * m + j]) + double(at.values[b * m + j])));
    }
    removed_t[shared[0]] = removed_t[shared[1]] = 1;
    for_triangles(b, [&](uint32_t i) {
      for (uint32_t& u : T[i])
        if (u == b) u = a;
    });
    next[tail[a]] = b;
    tail[a] = tail[b];
    removed_v[b] = 1;
    moved[a] = 1;
    ++out.collapsed;
  }
  if (out.collapsed == 0) return out;

  // The removed vertices and triangles taken out, the rest in order.
  std::vector<uint32_t> remap(nv, kNone);
  uint32_t kept = 0;
  for (size_t v = 0; v < nv; ++v)
    if (!removed_v[v]) {
      remap[v] = kept;
      if (moved[v]) out.moved.push_back(kept);
      ++kept;
    }
  compact_vertices(mesh, remap, kept, kNone);
  size_t w = 0;
  for (size_t i = 0; i < nt; ++i)
    if (!removed_t[i]) T[w++] = {remap[T[i][0]], remap[T[i][1]], remap[T[i][2]]};
  T.resize(w);
  return out;
}

}  // namespace particlemesh::detail
