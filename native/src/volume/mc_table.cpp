#include "volume/mc_table.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <utility>

namespace PM_NAMESPACE::detail {

namespace {

struct P3 {
  double v[3];
};

P3 corner_pos(int c) { return {{double(c & 1), double((c >> 1) & 1), double((c >> 2) & 1)}}; }

// The two axes other than a, in increasing order.
void other_axes(int a, int* o1, int* o2) {
  *o1 = a == 0 ? 1 : 0;
  *o2 = a == 2 ? 1 : 2;
}

int corner_of(const int coord[3]) { return coord[0] + 2 * coord[1] + 4 * coord[2]; }

// The header's table of edges' lower corners is the numbering's: edge 4 axis + u + 2v runs
// from the corner with coordinate 0 on the axis and u, v on the other two (in axis order).
static_assert([] {
  for (int e = 0; e < 12; ++e) {
    const int a = e >> 2, o1 = a == 0 ? 1 : 0, o2 = a == 2 ? 1 : 2;
    int coord[3] = {0, 0, 0};
    coord[o1] = e & 1;
    coord[o2] = (e >> 1) & 1;
    if (mc_edge_lower_corner(e) != coord[0] + 2 * coord[1] + 4 * coord[2]) return false;
  }
  return true;
}());

int edge_index(int axis, int u, int v) { return 4 * axis + u + 2 * v; }

P3 edge_mid(int e) {
  const int a = e >> 2;
  int o1, o2;
  other_axes(a, &o1, &o2);
  P3 p{};
  p.v[a] = 0.5;
  p.v[o1] = double(e & 1);
  p.v[o2] = double((e >> 1) & 1);
  return p;
}

// The edge joining two corners that differ in exactly one coordinate.
int edge_between(int c0, int c1) {
  const int diff = c0 ^ c1;
  const int a = diff == 1 ? 0 : (diff == 2 ? 1 : 2);
  const int lo = c0 & c1;
  int coord[3] = {lo & 1, (lo >> 1) & 1, (lo >> 2) & 1};
  int o1, o2;
  other_axes(a, &o1, &o2);
  return edge_index(a, coord[o1], coord[o2]);
}

P3 sub(const P3& a, const P3& b) { return {{a.v[0] - b.v[0], a.v[1] - b.v[1], a.v[2] - b.v[2]}}; }
P3 crossp(const P3& a, const P3& b) {
  return {{a.v[1] * b.v[2] - a.v[2] * b.v[1], a.v[2] * b.v[0] - a.v[0] * b.v[2],
           a.v[0] * b.v[1] - a.v[1] * b.v[0]}};
}
double dotp(const P3& a, const P3& b) { return a.v[0] * b.v[0] + a.v[1] * b.v[1] + a.v[2] * b.v[2]; }

std::array<std::array<int, 4>, 6> make_face_corners() {
  std::array<std::array<int, 4>, 6> out{};
  for (int f = 0; f < 6; ++f) {
    const int a = f >> 1, side = f & 1;
    int o1, o2;
    other_axes(a, &o1, &o2);
    const int uv[4][2] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
    for (int k = 0; k < 4; ++k) {
      int coord[3];
      coord[a] = side;
      coord[o1] = uv[k][0];
      coord[o2] = uv[k][1];
      out[f][k] = corner_of(coord);
    }
  }
  return out;
}

const std::array<std::array<int, 4>, 6> kFaceCorners = make_face_corners();

// Add the segment cutting off corner k of face f (between the two face edges at k), oriented
// so that the inside corners of the face lie on its right seen from outside the cube.
void add_segment(int f, int e_a, int e_b, int ref_corner, bool ref_inside, int next[12]) {
  const int a = f >> 1, side = f & 1;
  P3 n{};
  n.v[a] = side ? 1.0 : -1.0;
  const P3 pa = edge_mid(e_a), pb = edge_mid(e_b);
  const P3 d = sub(pb, pa);
  const P3 to_ref = sub(corner_pos(ref_corner), pa);
  // Inside on the right: d x n points toward the inside corners.
  double side_inside = dotp(crossp(d, n), to_ref);
  if (!ref_inside) side_inside = -side_inside;
  int from = e_a, to = e_b;
  if (side_inside < 0) std::swap(from, to);
  if (next[from] != -1) throw std::logic_error("marching cubes table: edge with two outgoing segments");
  next[from] = to;
}

// Bit (2 * axis + side) for each cube face the edge lies on.
int edge_faces(int e) {
  const int a = e >> 2;
  int o1, o2;
  other_axes(a, &o1, &o2);
  return (1 << (2 * o1 + (e & 1))) | (1 << (2 * o2 + ((e >> 1) & 1)));
}

double min_angle(const P3& a, const P3& b, const P3& c) {
  auto angle = [](const P3& p, const P3& q, const P3& r) {
    const P3 u = sub(q, p), v = sub(r, p);
    const double nu = std::sqrt(dotp(u, u)), nv = std::sqrt(dotp(v, v));
    return std::acos(std::clamp(dotp(u, v) / (nu * nv), -1.0, 1.0));
  };
  return std::min({angle(a, b, c), angle(b, c, a), angle(c, a, b)});
}

// Triangulate a loop of crossing edges. A diagonal between two vertices on the same cube
// face would lie in that face, where the neighbouring cell may produce the same triangle
// (an edge with four triangles), so only diagonals between vertices with no common face
// are allowed; among those triangulations, the one with the largest smallest angle (at the
// edge midpoints) is taken (dynamic programming over the polygon, at most 12 vertices).
void triangulate_loop(const int* loop, int len, std::vector<uint8_t>& out, int* centers,
                      std::vector<uint8_t>& center_loops) {
  if (len < 3) throw std::logic_error("marching cubes table: a loop with fewer than 3 vertices");
  auto allowed = [&](int i, int j) {
    if (j == i + 1 || (i == 0 && j == len - 1)) return true;
    return (edge_faces(loop[i]) & edge_faces(loop[j])) == 0;
  };
  double best[12][12];
  int split[12][12];
  for (int i = 0; i < len; ++i)
    for (int j = 0; j < len; ++j) {
      best[i][j] = -1;
      split[i][j] = -1;
    }
  for (int i = 0; i + 1 < len; ++i) best[i][i + 1] = 10.0;  // an edge: no triangle yet
  for (int gap = 2; gap < len; ++gap)
    for (int i = 0; i + gap < len; ++i) {
      const int j = i + gap;
      if (!allowed(i, j)) continue;
      for (int m = i + 1; m < j; ++m) {
        if (best[i][m] < 0 || best[m][j] < 0) continue;
        const double q = std::min({best[i][m], best[m][j],
                                   min_angle(edge_mid(loop[i]), edge_mid(loop[m]), edge_mid(loop[j]))});
        if (q > best[i][j] + 1e-12) {
          best[i][j] = q;
          split[i][j] = m;
        }
      }
    }
  if (split[0][len - 1] < 0) {
    // No such triangulation (long loops around several joined ambiguous faces): fan the loop
    // around a vertex inside the cell instead, whose spokes lie on no face.
    const int c = kCenterBase + *centers;
    center_loops.push_back(uint8_t(len));
    for (int k = 0; k < len; ++k) center_loops.push_back(uint8_t(loop[k]));
    ++*centers;
    for (int k = 0; k < len; ++k) {
      out.push_back(uint8_t(c));
      out.push_back(uint8_t(loop[k]));
      out.push_back(uint8_t(loop[(k + 1) % len]));
    }
    return;
  }
  // Emit in loop order (i, m, j) keeps the loop's orientation.
  std::vector<std::pair<int, int>> stack{{0, len - 1}};
  while (!stack.empty()) {
    const auto [i, j] = stack.back();
    stack.pop_back();
    if (j - i < 2) continue;
    const int m = split[i][j];
    out.push_back(uint8_t(loop[i]));
    out.push_back(uint8_t(loop[m]));
    out.push_back(uint8_t(loop[j]));
    stack.push_back({i, m});
    stack.push_back({m, j});
  }
}

}  // namespace

const std::array<int, 4>& mc_face_corners(int f) { return kFaceCorners[f]; }

const McTable& McTable::get() {
  static const McTable table;
  return table;
}

McTable::McTable() {
  offset_.push_back(0);
  center_offset_.push_back(0);
  for (int c = 0; c < 256; ++c) {
    auto inside = [c](int corner) { return (c >> corner) & 1; };
    uint8_t amb = 0;
    for (int f = 0; f < 6; ++f) {
      const auto& q = kFaceCorners[f];
      if (inside(q[0]) == inside(q[2]) && inside(q[1]) == inside(q[3]) && inside(q[0]) != inside(q[1]))
        amb |= uint8_t(1u << f);
    }
    ambiguous_[c] = amb;
    base_[c] = uint32_t(offset_.size() - 1);
    int namb = 0;
    for (int f = 0; f < 6; ++f) namb += (amb >> f) & 1;
    for (unsigned d = 0; d < (1u << namb); ++d) {
      int next[12];
      for (int& x : next) x = -1;
      int j = 0;
      for (int f = 0; f < 6; ++f) {
        const auto& q = kFaceCorners[f];
        if ((amb >> f) & 1) {
          // Ambiguous: cut off the two inside corners (separate) or the two outside corners
          // (the inside corners joined across the face).
          const bool join = (d >> j++) & 1;
          for (int k = 0; k < 4; ++k) {
            const bool kin = inside(q[k]);
            if (kin == join) continue;  // join: cut off outside corners; separate: inside ones
            const int ea = edge_between(q[k], q[(k + 3) % 4]);
            const int eb = edge_between(q[k], q[(k + 1) % 4]);
            add_segment(f, ea, eb, q[k], kin, next);
          }
        } else {
          int crossing[4], nc = 0, ref = -1;
          for (int k = 0; k < 4; ++k) {
            if (inside(q[k]) != inside(q[(k + 1) % 4])) crossing[nc++] = edge_between(q[k], q[(k + 1) % 4]);
            if (inside(q[k])) ref = q[k];
          }
          if (nc == 0) continue;
          if (nc != 2) throw std::logic_error("marching cubes table: unexpected face crossing count");
          add_segment(f, crossing[0], crossing[1], ref, true, next);
        }
      }
      // Trace the loops and fan them.
      bool crossing_edge[12] = {};
      int incoming[12] = {};
      for (int e = 0; e < 12; ++e) {
        const int lo = mc_edge_lower_corner(e);
        const int hi = lo + (1 << (e >> 2));
        crossing_edge[e] = inside(lo) != inside(hi);
        if (next[e] != -1) ++incoming[next[e]];
      }
      for (int e = 0; e < 12; ++e) {
        if (crossing_edge[e] != (next[e] != -1) || incoming[e] != (crossing_edge[e] ? 1 : 0))
          throw std::logic_error("marching cubes table: the face segments do not form loops");
      }
      bool visited[12] = {};
      int centers = 0;
      for (int e = 0; e < 12; ++e) {
        if (!crossing_edge[e] || visited[e]) continue;
        int loop[12], len = 0;
        for (int x = e; !visited[x]; x = next[x]) {
          visited[x] = true;
          loop[len++] = x;
        }
        triangulate_loop(loop, len, tris_, &centers, center_loops_);
      }
      offset_.push_back(uint32_t(tris_.size()));
      center_count_.push_back(uint8_t(centers));
      center_offset_.push_back(uint32_t(center_loops_.size()));
    }
  }
}

}  // namespace particlemesh::detail
