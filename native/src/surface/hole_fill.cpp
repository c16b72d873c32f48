#include "surface/hole_fill.h"

#include <algorithm>
#include <cmath>
#include <utility>

#include "surface/raw_triangulation.h"
#include "surface/triangle_angles.h"

namespace PM_NAMESPACE::detail {

double FillOptions::edge_limit(uint32_t a, uint32_t b) const { return pair_limit((*max_edge)[a], (*max_edge)[b]); }

double FillOptions::fill_limit(uint32_t a, uint32_t b) const {
  return std::min(fill_edge_factor * edge_limit(a, b), edge_cap);
}

bool fill_loop(EditableSurface& s, const std::vector<uint32_t>& L, const FillOptions& o, FillStats& stats,
               double max_fold) {
  const std::vector<Vec3>& P = s.positions();
  const size_t m = L.size();
  if (m < 3) return false;
  const bool smooth = m > o.small_hole;
  auto diag_ok = [&](size_t i, size_t j) {
    if ((j == i + 1) || (i == 0 && j == m - 1)) return true;
    const double limit2 = std::pow(o.fill_limit(L[i], L[j]), 2);
    return squared_distance(P[L[i]], P[L[j]]) <= limit2 && !s.edge_exists(L[i], L[j]) && !o.view.along_ray(P[L[i]], P[L[j]]);
  };
  // The surface's triangle across each loop edge L[i] -> L[i+1], for the dihedral angles.
  std::vector<Vec3> outside(m);
  for (size_t i = 0; i < m; ++i) {
    const uint32_t a = L[i], b = L[(i + 1) % m];
    s.for_each_tri(a, [&](uint32_t t) {
      const Triangle& T = s.triangle(t);
      if (T[(corner_of(T, a) + 1) % 3] == b) outside[i] = s.face_normal(T);
    });
  }
  auto bend = [](const Vec3& a, const Vec3& b) { return std::acos(std::clamp(dot(a, b), -1.0, 1.0)); };
  // (worst value, total) of the best triangulation of the chain i..k, and its apex.
  std::vector<double> worst(m * m, INFINITY), total(m * m, INFINITY);
  std::vector<uint32_t> apex(m * m, 0);
  for (size_t i = 0; i + 1 < m; ++i) worst[i * m + i + 1] = total[i * m + i + 1] = 0;
  auto chain_normal = [&](size_t i, size_t j) {
    return j == i + 1 ? outside[i] : s.face_normal({L[j], L[apex[i * m + j]], L[i]});  // the fill's (L[k], L[j], L[i])
  };
  for (size_t len = 2; len < m; ++len)
    for (size_t i = 0; i + len < m; ++i) {
      const size_t k = i + len;
      if (!diag_ok(i, k)) continue;
      for (size_t j = i + 1; j < k; ++j) {
        const double wl = worst[i * m + j], wr = worst[j * m + k];
        if (!std::isfinite(wl) || !std::isfinite(wr)) continue;
        const Vec3 f = cross(P[L[j]] - P[L[k]], P[L[i]] - P[L[k]]);
        const double area = 0.5 * norm(f);
        if (!(area > 0)) continue;
        if (m == 3 && s.triangle_exists(L[0], L[1], L[2])) continue;  // the loop of a lone triangle
        // The triangle's folds: against the surface across each loop edge it holds, for
        // every loop (the short outline of a small isolated patch is its outside, and
        // capping it would lay a reversed copy on the patch: a flat, closed pillow), and
        // for larger loops also against the fill triangles across its diagonals.
        const Vec3 nrm = f / (2 * area);
        double fold = 0;
        if (smooth || j == i + 1) fold = bend(nrm, chain_normal(i, j));
        if (smooth || k == j + 1) fold = std::max(fold, bend(nrm, chain_normal(j, k)));
        if (i == 0 && k == m - 1) fold = std::max(fold, bend(nrm, outside[m - 1]));
        if (fold > max_fold) continue;
        const double value = smooth ? fold : max_angle(P[L[k]], P[L[j]], P[L[i]]);
        const double add = smooth ? area : value;
        const double w = std::max({wl, wr, value}), tt = total[i * m + j] + total[j * m + k] + add;
        if (w < worst[i * m + k] || (w == worst[i * m + k] && tt < total[i * m + k])) {
          worst[i * m + k] = w;
          total[i * m + k] = tt;
          apex[i * m + k] = uint32_t(j);
        }
      }
    }
  if (!std::isfinite(worst[m - 1])) return false;
  std::vector<std::pair<size_t, size_t>> todo{{0, m - 1}};
  std::vector<Triangle> added;
  while (!todo.empty()) {
    auto [i, k] = todo.back();
    todo.pop_back();
    if (k <= i + 1) continue;
    const size_t j = apex[i * m + k];
    added.push_back({L[k], L[j], L[i]});
    todo.push_back({i, j});
    todo.push_back({j, k});
  }
  for (const Triangle& T : added) s.add_triangle(T);
  ++stats.holes_filled;
  stats.hole_triangles += added.size();
  return true;
}

size_t fill_loops(EditableSurface& s, size_t max_size, const FillOptions& o, FillStats& stats) {
  if (s.closed()) return 0;
  size_t filled = 0;
  for (const auto& L : s.trace_loops())
    if (L.size() <= max_size && fill_loop(s, L, o, stats)) ++filled;
  return filled;
}

// Sharp creases and corners need the sharper folds: a 60-degree wedge bends its surface by
// 120 degrees, and the holes where it meets another face, or where jitter tilted the triangles
// around a gap, had no fill within 137 degrees (prisms of 45-75-degree wedges, and jittered
// resamplings of real models, were left open). The component rule keeps the 137-degree limit
// where it matters: a small isolated patch (a depth scan's flat rows) is a disk of about
// 0.18 m^2 triangles inside its outline m, and capping that outline lays a reversed copy on it.
size_t fill_folded_loops(EditableSurface& s, size_t max_size, const FillOptions& o, FillStats& stats) {
  if (s.closed()) return 0;
  std::vector<std::vector<uint32_t>> loops;
  for (auto& L : s.trace_loops())
    if (L.size() <= max_size) loops.push_back(std::move(L));
  if (loops.empty()) return 0;
  std::vector<uint32_t> piece, count;
  s.surface_pieces(piece, count);
  size_t filled = 0;
  for (const auto& L : loops) {
    const uint64_t m = L.size();
    if (count[piece[L[0]]] > m * m && fill_loop(s, L, o, stats, kMaxCreaseDihedral)) ++filled;
  }
  return filled;
}

double loop_width(const std::vector<Vec3>& P, const std::vector<uint32_t>& L, const FillOptions& o) {
  const size_t m = L.size();
  auto span = [&](size_t i, size_t k) { return distance(P[L[i]], P[L[k]]) / o.edge_limit(L[i], L[k]); };
  std::vector<double> w(m * m, INFINITY);
  for (size_t i = 0; i + 1 < m; ++i) w[i * m + i + 1] = span(i, i + 1);
  for (size_t len = 2; len < m; ++len)
    for (size_t i = 0; i + len < m; ++i) {
      const size_t k = i + len;
      const double d = span(i, k);
      for (size_t j = i + 1; j < k; ++j) w[i * m + k] = std::min(w[i * m + k], std::max({w[i * m + j], w[j * m + k], d}));
    }
  return w[m - 1];
}

}  // namespace particlemesh::detail
