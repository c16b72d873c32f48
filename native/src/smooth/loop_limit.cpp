#include "smooth/loop_limit.h"

#include <algorithm>

#include <atomic>

#include <opensubdiv/sdc/loopScheme.h>
#include <opensubdiv/sdc/scheme.h>

#include "core/huge_pages.h"
#include "core/parallel.h"
#include "mesh/corner_buckets.h"

namespace PM_NAMESPACE::detail {

namespace {

/// The interface Sdc::Scheme expects of a mask (as PrimvarRefiner's own).
class Mask {
 public:
  typedef double Weight;
  Mask(Weight* v, Weight* e, Weight* f) : v_(v), e_(e), f_(f) {}
  int GetNumVertexWeights() const { return nv_; }
  int GetNumEdgeWeights() const { return ne_; }
  int GetNumFaceWeights() const { return nf_; }
  void SetNumVertexWeights(int n) { nv_ = n; }
  void SetNumEdgeWeights(int n) { ne_ = n; }
  void SetNumFaceWeights(int n) { nf_ = n; }
  Weight const& VertexWeight(int i) const { return v_[i]; }
  Weight const& EdgeWeight(int i) const { return e_[i]; }
  Weight const& FaceWeight(int i) const { return f_[i]; }
  Weight& VertexWeight(int i) { return v_[i]; }
  Weight& EdgeWeight(int i) { return e_[i]; }
  Weight& FaceWeight(int i) { return f_[i]; }
  bool AreFaceWeightsForFaceCenters() const { return centers_; }
  void SetFaceWeightsForFaceCenters(bool on) { centers_ = on; }

 private:
  Weight *v_, *e_, *f_;
  int nv_ = 0, ne_ = 0, nf_ = 0;
  bool centers_ = false;
};

/// A smooth interior vertex of the given valence, as Sdc::Scheme sees it.
struct SmoothVertex {
  int valence;
  int GetNumEdges() const { return valence; }
  int GetNumFaces() const { return valence; }
  float GetSharpness() const { return 0.0f; }
  float* GetSharpnessPerEdge(float* s) const {
    std::fill(s, s + valence, 0.0f);
    return s;
  }
};

/// One corner of a vertex in a triangle: the triangle's next and previous vertex after it.
struct Corner {
  uint32_t to, from;
};

/// The ring of a vertex from its corners (any order): from the first corner's next vertex,
/// through the corner whose next vertex is the previous corner's previous one
/// (counter-clockwise with the winding), rotated to start at the lowest neighbour, so that
/// the sums do not depend on the order of the triangles or of their corners. False when the
/// corners are not one closed fan. `used` has room for n flags.
bool walk_fan(const Corner* corners, uint32_t n, uint32_t* ring, uint8_t* used) {
  std::fill(used, used + n, uint8_t(0));
  uint32_t at = 0;
  for (uint32_t k = 0; k < n; ++k) {
    used[at] = 1;
    ring[k] = corners[at].to;
    if (k + 1 == n) break;
    const uint32_t want = corners[at].from;
    uint32_t next = n;
    for (uint32_t j = 0; j < n; ++j)
      if (!used[j] && corners[j].to == want) {
        next = j;
        break;
      }
    if (next == n) return false;
    at = next;
  }
  // The fan closes: the last corner's previous vertex is the first one's next.
  if (corners[at].from != corners[0].to) return false;
  std::rotate(ring, std::min_element(ring, ring + n), ring + n);
  return true;
}

/// walk_fan's ring when the corners come in its order already (each one's previous vertex
/// the next one's next: OpenSubdiv orders a manifold vertex's faces so, and an edge's
/// corners are gathered so), checked in one pass; false (ring unspecified) otherwise. The
/// neighbours of a refined vertex are distinct, so the walk would find the same cycle.
bool chained_fan(const Corner* corners, uint32_t n, uint32_t* ring) {
  for (uint32_t i = 0; i < n; ++i) {
    if (corners[i].from != corners[i + 1 == n ? 0 : i + 1].to) return false;
    ring[i] = corners[i].to;
  }
  std::rotate(ring, std::min_element(ring, ring + n), ring + n);
  return true;
}

/// Vertex v's limit position and unit normal (zero where the tangents' cross product
/// vanishes) from its ring r of n neighbours, in the order PrimvarRefiner::Limit sums them:
/// each output cleared, then the edge weights in ring order, then the vertex weight (the
/// tangents' is 0, added all the same).
inline void limit_point(const uint32_t* r, int n, size_t v, const Vec3* src, const LoopLimitMasks& masks, Vec3& pos,
                        Vec3& normal) {
  const double ew = masks.edge_weight(n), vw = masks.vertex_weight(n);
  const double *w1 = masks.tangent1(n), *w2 = masks.tangent2(n);
  double p[3] = {0, 0, 0}, a[3] = {0, 0, 0}, c[3] = {0, 0, 0};
  for (int i = 0; i < n; ++i) {
    const Vec3& q = src[r[i]];
    p[0] += ew * q.x;
    p[1] += ew * q.y;
    p[2] += ew * q.z;
  }
  const Vec3& s = src[v];
  p[0] += vw * s.x;
  p[1] += vw * s.y;
  p[2] += vw * s.z;
  for (int i = 0; i < n; ++i) {
    const Vec3& q = src[r[i]];
    a[0] += w1[i] * q.x;
    a[1] += w1[i] * q.y;
    a[2] += w1[i] * q.z;
    c[0] += w2[i] * q.x;
    c[1] += w2[i] * q.y;
    c[2] += w2[i] * q.z;
  }
  a[0] += 0.0 * s.x;
  a[1] += 0.0 * s.y;
  a[2] += 0.0 * s.z;
  c[0] += 0.0 * s.x;
  c[1] += 0.0 * s.y;
  c[2] += 0.0 * s.z;
  pos = {p[0], p[1], p[2]};
  const Vec3 t1{a[0], a[1], a[2]}, t2{c[0], c[1], c[2]};
  const Vec3 nn = cross(t1, t2);
  // A vanishing cross product (degenerate control geometry) is marked with a zero normal.
  normal = squared_norm(nn) > 1e-24 * squared_norm(t1) * squared_norm(t2) ? normalized(nn) : Vec3{};
}

/// The same for vertex v's k channels (positions' masks only) into d.
inline void limit_channels(const uint32_t* r, int n, size_t v, const double* src, size_t k,
                           const LoopLimitMasks& masks, double* d) {
  const double* s = src + v * k;
  const double ew = masks.edge_weight(n), vw = masks.vertex_weight(n);
  std::fill(d, d + k, 0.0);
  for (int i = 0; i < n; ++i) {
    const double* q = src + size_t(r[i]) * k;
    for (size_t j = 0; j < k; ++j) d[j] += ew * q[j];
  }
  for (size_t j = 0; j < k; ++j) d[j] += vw * s[j];
}

}  // namespace

bool build_loop_rings(const std::vector<Triangle>& T, size_t V, LoopRings* out) {
  const size_t F = T.size();
  // Corners by vertex, in triangle order (counted and placed per fixed chunk of triangles:
  // the same layout for any thread count).
  std::vector<uint32_t>& off = out->offset;
  std::vector<Corner> corners;
  bucket_corners_by_vertex(T, V, off, corners, [&](size_t f, uint32_t c) {
    return Corner{T[f][(c + 1) % 3], T[f][(c + 2) % 3]};
  });
  out->ring.resize(3 * F);
  std::atomic<bool> ok{true};
  std::atomic<int> max_valence{0};
  parallel_blocks(V, 4096, [&](size_t b, size_t e) {
    int local_max = 0;
    std::vector<uint8_t> used;
    for (size_t v = b; v < e && ok.load(std::memory_order_relaxed); ++v) {
      const uint32_t begin = off[v], n = off[v + 1] - off[v];
      if (n == 0) continue;  // unreferenced: the refined levels have none
      if (n < 3) {
        ok = false;
        break;
      }
      local_max = std::max(local_max, int(n));
      used.resize(n);
      if (!walk_fan(corners.data() + begin, n, out->ring.data() + begin, used.data())) {
        ok = false;
        break;
      }
    }
    int m = max_valence.load();
    while (local_max > m && !max_valence.compare_exchange_weak(m, local_max)) {
    }
  });
  out->max_valence = max_valence.load();
  return ok.load();
}

LoopLimitMasks::LoopLimitMasks(int max_valence) {
  const size_t n = size_t(std::max(max_valence, 3)) + 1;
  vertex_.assign(n, 0.0);
  edge_.assign(n, 0.0);
  start_.assign(n + 1, 0);
  for (size_t k = 0; k < n; ++k) start_[k + 1] = start_[k] + k;
  tan1_.assign(start_[n], 0.0);
  tan2_.assign(start_[n], 0.0);
  const OpenSubdiv::Sdc::Scheme<OpenSubdiv::Sdc::SCHEME_LOOP> scheme;
  std::vector<double> pe(n), pf(n), t1e(n), t1f(n), t2e(n), t2f(n);
  for (size_t k = 3; k < n; ++k) {
    double pv = 0, t1v = 0, t2v = 0;
    Mask pos(&pv, pe.data(), pf.data()), t1(&t1v, t1e.data(), t1f.data()), t2(&t2v, t2e.data(), t2f.data());
    scheme.ComputeVertexLimitMask(SmoothVertex{int(k)}, pos, t1, t2, OpenSubdiv::Sdc::Crease::RULE_SMOOTH);
    vertex_[k] = pv;
    edge_[k] = pe[0];  // the same for every neighbour under the smooth rule
    for (size_t i = 0; i < k; ++i) {
      tan1_[start_[k] + i] = t1e[i];
      tan2_[start_[k] + i] = t2e[i];
    }
  }
}

void loop_limit_positions(const LoopRings& rings, const LoopLimitMasks& masks, const std::vector<Vec3>& src,
                          std::vector<Vec3>& pos, std::vector<Vec3>& normals) {
  const size_t V = rings.offset.size() - 1;
  pos.resize(V);
  normals.resize(V);
  parallel_blocks(V, 4096, [&](size_t b, size_t e) {
    for (size_t v = b; v < e; ++v) {
      const uint32_t begin = rings.offset[v];
      const int n = int(rings.offset[v + 1] - begin);
      if (n == 0) {
        pos[v] = src[v];
        normals[v] = Vec3{};
        continue;
      }
      limit_point(rings.ring.data() + begin, n, v, src.data(), masks, pos[v], normals[v]);
    }
  });
}

void loop_limit_channels(const LoopRings& rings, const LoopLimitMasks& masks, const double* src, int channels,
                         double* dst) {
  const size_t V = rings.offset.size() - 1, k = size_t(channels);
  parallel_blocks(V, 4096, [&](size_t b, size_t e) {
    for (size_t v = b; v < e; ++v) {
      const uint32_t begin = rings.offset[v];
      const int n = int(rings.offset[v + 1] - begin);
      if (n == 0) {
        std::copy(src + v * k, src + v * k + k, dst + v * k);
        continue;
      }
      limit_channels(rings.ring.data() + begin, n, v, src, k, masks, dst + v * k);
    }
  });
}

bool loop_limit_refined(const OpenSubdiv::Far::TopologyLevel& parent, const OpenSubdiv::Far::TopologyLevel& last,
                        const std::vector<Vec3>& src, const double* channels_src, int channels, std::vector<Vec3>& pos,
                        std::vector<Vec3>& normals, double* channels_dst) {
  const size_t V = size_t(last.GetNumVertices()), k = size_t(channels);
  if (src.size() != V) return false;
  // The largest valence: a vertex's child has its valence, an edge's child 6.
  int max_valence = 6;
  for (int v = 0; v < parent.GetNumVertices(); ++v) max_valence = std::max(max_valence, parent.GetVertexFaces(v).size());
  const LoopLimitMasks masks(max_valence);
  resize_huge(pos, V);
  resize_huge(normals, V);
  std::atomic<bool> ok{true};
  using OpenSubdiv::Far::ConstIndexArray;
  using OpenSubdiv::Far::Index;
  // The refined vertices are taken in batches: their rings first (and their neighbours'
  // points prefetched), then their limits, so that the neighbours' cache misses overlap.
  constexpr size_t kBatch = 32;
  struct Scratch {
    std::vector<Corner> corners;  // of the vertex being gathered
    std::vector<uint8_t> used;
    std::vector<uint32_t> ring;   // the batch's rings, one after another
    std::vector<uint32_t> end;    // each batch vertex's ring ends here
    std::vector<uint32_t> child;  // the batch's vertices
  };
  auto flush = [&](Scratch& w) {
    uint32_t begin = 0;
    for (size_t q = 0; q < w.child.size(); ++q) {
      const size_t v = w.child[q];
      const int n = int(w.end[q] - begin);
      limit_point(w.ring.data() + begin, n, v, src.data(), masks, pos[v], normals[v]);
      if (k > 0) limit_channels(w.ring.data() + begin, n, v, channels_src, k, masks, channels_dst + v * k);
      begin = w.end[q];
    }
    w.ring.clear();
    w.end.clear();
    w.child.clear();
  };
  // Child vertex cv's corners are gathered in w.corners: its ring joins the batch.
  auto finish = [&](Index cv, Scratch& w) {
    if (cv < 0 || size_t(cv) >= V) return false;
    const uint32_t n = uint32_t(w.corners.size());
    const size_t v = size_t(cv);
    if (n == 0) {  // an unreferenced vertex's child (the control mesh has none)
      pos[v] = src[v];
      normals[v] = Vec3{};
      if (k > 0) std::copy(channels_src + v * k, channels_src + v * k + k, channels_dst + v * k);
      return true;
    }
    if (n < 3 || n > uint32_t(max_valence)) return false;
    const size_t at = w.ring.size();
    w.ring.resize(at + n);
    uint32_t* r = w.ring.data() + at;
    if (!chained_fan(w.corners.data(), n, r)) {
      w.used.resize(n);
      if (!walk_fan(w.corners.data(), n, r, w.used.data())) return false;
    }
    for (uint32_t i = 0; i < n; ++i) __builtin_prefetch(&src[r[i]]);
    w.end.push_back(uint32_t(at + n));
    w.child.push_back(uint32_t(v));
    if (w.child.size() == kBatch) flush(w);
    return true;
  };
  // Loop splits a triangle (a, b, c) with edges ab, bc, ca (face-edge i runs from face-vertex
  // i to i + 1) into (a', ab', ca'), (ab', b', bc'), (ca', bc', c') and (ab', bc', ca'), in
  // its winding, where x' is the child of x: so a refined vertex's corners are read from the
  // parent's faces around its parent vertex or edge, without the refined triangles. (Every
  // refined vertex is the child of one parent vertex or edge: Loop has no face children.)
  auto edge_child = [&](Index e) { return uint32_t(parent.GetEdgeChildVertex(e)); };
  auto vertex_child = [&](Index v) { return uint32_t(parent.GetVertexChildVertex(v)); };
  parallel_blocks(size_t(parent.GetNumVertices()), 2048, [&](size_t b, size_t e) {
    Scratch w;
    for (size_t v = b; v < e && ok.load(std::memory_order_relaxed); ++v) {
      // a' in (a', ab', ca'): next ab', previous ca'.
      const ConstIndexArray faces = parent.GetVertexFaces(Index(v));
      const auto at = parent.GetVertexFaceLocalIndices(Index(v));
      w.corners.clear();
      for (int i = 0; i < faces.size(); ++i) {
        const ConstIndexArray fe = parent.GetFaceEdges(faces[i]);
        if (fe.size() != 3) {
          ok = false;
          break;
        }
        const int j = at[i];
        w.corners.push_back(Corner{edge_child(fe[j]), edge_child(fe[(j + 2) % 3])});
      }
      if (!ok.load(std::memory_order_relaxed) || !finish(parent.GetVertexChildVertex(Index(v)), w)) ok = false;
    }
    flush(w);
  });
  parallel_blocks(size_t(parent.GetNumEdges()), 4096, [&](size_t b, size_t e) {
    Scratch w;
    for (size_t i = b; i < e && ok.load(std::memory_order_relaxed); ++i) {
      // ab' in (a', ab', ca'): next ca', previous a'; in (ab', b', bc'): b', bc'; in
      // (ab', bc', ca'): bc', ca'.
      const ConstIndexArray faces = parent.GetEdgeFaces(Index(i));
      const auto at = parent.GetEdgeFaceLocalIndices(Index(i));
      w.corners.clear();
      for (int q = 0; q < faces.size(); ++q) {
        const ConstIndexArray fv = parent.GetFaceVertices(faces[q]), fe = parent.GetFaceEdges(faces[q]);
        if (fe.size() != 3) {
          ok = false;
          break;
        }
        const int j = at[q];
        const uint32_t ca = edge_child(fe[(j + 2) % 3]), bc = edge_child(fe[(j + 1) % 3]);
        w.corners.push_back(Corner{ca, vertex_child(fv[j])});
        w.corners.push_back(Corner{vertex_child(fv[(j + 1) % 3]), bc});
        w.corners.push_back(Corner{bc, ca});
      }
      // Two faces A and B (B runs the edge the other way): in walking order A's first corner,
      // B's second, third and first, A's second and third.
      if (w.corners.size() == 6) {
        const Corner c[6] = {w.corners[0], w.corners[4], w.corners[5], w.corners[3], w.corners[1], w.corners[2]};
        std::copy(c, c + 6, w.corners.begin());
      }
      if (!ok.load(std::memory_order_relaxed) || !finish(parent.GetEdgeChildVertex(Index(i)), w)) ok = false;
    }
    flush(w);
  });
  return ok.load() && size_t(parent.GetNumVertices()) + size_t(parent.GetNumEdges()) == V;
}

}  // namespace particlemesh::detail
