#include "particlemesh/smooth/taubin.h"

#include <cmath>
#include <cstdio>
#include <string>

#include "core/format_number.h"
#include "core/parallel.h"
#include "particlemesh/core/error.h"
#include "particlemesh/mesh/edges.h"

namespace PM_NAMESPACE {

namespace {

std::string num(double v) { return detail::format_number(v, 17); }

}  // namespace

void validate_taubin(const TaubinOptions& o) {
  if (o.iterations < 0 || o.iterations > 10000)
    throw Error(Status::InvalidArgument,
                "taubin iterations is " + std::to_string(o.iterations) + " (must be in [0, 10000])");
  if (!(o.lambda > 0 && o.lambda <= 1))
    throw Error(Status::InvalidArgument, "taubin lambda is " + num(o.lambda) + " (must be in (0, 1])");
  if (!(o.mu >= -1 && o.mu < -o.lambda))
    throw Error(Status::InvalidArgument,
                "taubin mu is " + num(o.mu) + " (must be in [-1, -lambda) = [-1, " + num(-o.lambda) + "))");
  if (o.threads < 0) throw Error(Status::InvalidArgument, "threads must be >= 0 (0 = all cores)");
}

void taubin_smooth(TriMesh& mesh, const TaubinOptions& o) {
  validate_taubin(o);
  if (o.iterations == 0 || mesh.triangles.empty()) return;
  const size_t nv = mesh.positions.size();
  detail::with_threads(o.threads, [&] {
    // Edge neighbours as a compressed adjacency, each vertex's neighbours in increasing index
    // (mesh_edges lists edges (a, b), a < b, ordered by a then b).
    const MeshEdges me = mesh_edges(mesh.triangles, nv, o.threads);
    std::vector<uint32_t> start(nv + 1, 0);
    for (const auto& e : me.edges) {
      ++start[e[0] + 1];
      ++start[e[1] + 1];
    }
    for (size_t v = 0; v < nv; ++v) start[v + 1] += start[v];
    std::vector<uint32_t> adj(start[nv]);
    std::vector<uint32_t> fill(start.begin(), start.end() - 1);
    // Edges sorted by (a, b): for vertex v the neighbours a < v come first (from edges (a, v),
    // met in increasing a), then those b > v (edges (v, b), increasing b).
    for (const auto& e : me.edges) adj[fill[e[1]]++] = e[0];
    for (const auto& e : me.edges) adj[fill[e[0]]++] = e[1];
    std::vector<Vec3> next(nv);
    auto step = [&](double f) {
      detail::parallel_blocks(nv, 4096, [&](size_t b, size_t e) {
        for (size_t v = b; v < e; ++v) {
          const uint32_t s0 = start[v], s1 = start[v + 1];
          if (s0 == s1) {
            next[v] = mesh.positions[v];
            continue;
          }
          Vec3 sum{};
          for (uint32_t k = s0; k < s1; ++k) sum += mesh.positions[adj[k]] - mesh.positions[v];
          next[v] = mesh.positions[v] + sum * (f / double(s1 - s0));
        }
      });
      mesh.positions.swap(next);
    };
    for (int it = 0; it < o.iterations; ++it) {
      step(o.lambda);
      step(o.mu);
    }
    // Normals: area-weighted mean of the triangles' normals (the cross product's length is
    // twice the area), summed per vertex in triangle order.
    std::vector<Vec3> n(nv, Vec3{});
    std::vector<char> used(nv, 0);
    for (const Triangle& t : mesh.triangles) {
      const Vec3 c = cross(mesh.positions[t[1]] - mesh.positions[t[0]], mesh.positions[t[2]] - mesh.positions[t[0]]);
      for (int k = 0; k < 3; ++k) {
        n[t[size_t(k)]] += c;
        used[t[size_t(k)]] = 1;
      }
    }
    if (mesh.normals.size() != nv) mesh.normals.assign(nv, Vec3{});
    for (size_t v = 0; v < nv; ++v)
      if (used[v]) {
        const double l = norm(n[v]);
        if (l > 0 && std::isfinite(l)) mesh.normals[v] = n[v] / l;
      }
  });
}

}  // namespace particlemesh
