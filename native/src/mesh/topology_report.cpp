#include "particlemesh/mesh/topology_report.h"

#include <algorithm>
#include <array>
#include <atomic>
#include <memory>
#include <numeric>

#include <tbb/combinable.h>

#include "core/disjoint_sets.h"
#include "core/huge_pages.h"
#include "core/parallel.h"
#include "mesh/corner_buckets.h"
#include "mesh/nesting.h"
#include "mesh/orientation.h"

// The report is built vertex by vertex, in parallel. The triangles' corners are bucketed by
// vertex (a stable counting sort over chunks of triangles, so each vertex's corners come out
// in increasing order whatever the thread count); each vertex's corners then give its fan and
// the edges whose lower endpoint it is: paired along the fan where it is a closed, consistently
// oriented disk (the common case), else grouped by a local sort; together, in vertex order,
// exactly the edges a global sort of all half-edges would give, without that sort. Each edge
// is recorded at a corner of its lower endpoint, and the per-component counts are summed from
// those records in triangle order. Every count is a sum of integers. Triangles are joined into components by a concurrent union-find that
// always links the larger root under the smaller, so each component's root is its lowest
// triangle whatever the order of the unions. Signed volumes are summed in triangle order, as
// a serial pass would, so the report is the same for any thread count. Boundary loops (and
// their sizes) are walked serially, in edge order: a boundary is small beside the triangles.

namespace PM_NAMESPACE {

namespace {

constexpr std::memory_order kRelaxed = std::memory_order_relaxed;

/// Adds to per-component counters, one atomic add per run of the same component (a
/// component's triangles, edges and vertices mostly come in long runs).
class RunAdder {
 public:
  explicit RunAdder(std::vector<std::atomic<uint64_t>>& counters) : c_(counters) {}
  ~RunAdder() { flush(); }
  void add(uint32_t comp, uint32_t n = 1) {
    if (comp != comp_) {
      flush();
      comp_ = comp;
    }
    n_ += n;
  }

 private:
  void flush() {
    if (n_ != 0) c_[comp_].fetch_add(n_, kRelaxed);
    n_ = 0;
  }
  std::vector<std::atomic<uint64_t>>& c_;
  uint32_t comp_ = UINT32_MAX;
  uint64_t n_ = 0;
};

/// A small array on the stack that moves to the heap when it outgrows it (a vertex's
/// corners: about six on a surface, any number on a soup).
template <class T, size_t N>
class SmallVector {
 public:
  void clear() { size_ = 0; }
  size_t size() const { return size_; }
  T* data() { return heap_.empty() ? local_ : heap_.data(); }
  T& operator[](size_t i) { return data()[i]; }
  void push_back(const T& v) {
    if (size_ == N && heap_.empty()) heap_.assign(local_, local_ + N);
    if (!heap_.empty()) {
      if (heap_.size() <= size_) heap_.resize(2 * size_);
      heap_[size_++] = v;
    } else {
      local_[size_++] = v;
    }
  }
  /// Sorted in place (insertion sort while small).
  template <class Less = std::less<T>>
  void sort(Less less = Less()) {
    T* d = data();
    if (size_ > 24) {
      std::sort(d, d + size_, less);
      return;
    }
    for (size_t i = 1; i < size_; ++i) {
      const T v = d[i];
      size_t j = i;
      for (; j > 0 && less(v, d[j - 1]); --j) d[j] = d[j - 1];
      d[j] = v;
    }
  }
  void reset() {  // back to the stack buffer
    size_ = 0;
    heap_.clear();
  }

 private:
  T local_[N];
  std::vector<T> heap_;
  size_t size_ = 0;
};

/// Is the link of a vertex (the opposite edges of its triangles, as vertex pairs) a single
/// path or a single cycle? Every link vertex in at most two link edges, and all connected
/// (the edges' components are the vertices' components: every link vertex is on an edge).
/// A closed, consistently oriented fan of up to 32 corners is taken before (closed_fan_cycle).
bool link_is_one_fan(std::pair<uint32_t, uint32_t>* link, size_t n) {
  uint32_t label[64];
  if (n > 64) {
    std::vector<uint32_t> ids;
    for (size_t i = 0; i < n; ++i) {
      ids.push_back(link[i].first);
      ids.push_back(link[i].second);
    }
    std::sort(ids.begin(), ids.end());
    for (size_t i = 0; i + 2 < ids.size(); ++i)
      if (ids[i] == ids[i + 2]) return false;
    std::vector<uint32_t> parent(n);
    std::iota(parent.begin(), parent.end(), 0u);
    auto find = [&](uint32_t x) {
      while (parent[x] != x) x = parent[x] = parent[parent[x]];
      return x;
    };
    // Edges sharing a vertex, through the sorted ids: each id's edges.
    std::vector<std::pair<uint32_t, uint32_t>> at;  // (id, edge)
    for (size_t i = 0; i < n; ++i) {
      at.push_back({link[i].first, uint32_t(i)});
      at.push_back({link[i].second, uint32_t(i)});
    }
    std::sort(at.begin(), at.end());
    size_t parts = n;
    for (size_t i = 1; i < at.size(); ++i)
      if (at[i].first == at[i - 1].first) {
        const uint32_t a = find(at[i].second), b = find(at[i - 1].second);
        if (a != b) {
          parent[a] = b;
          --parts;
        }
      }
    return parts == 1;
  }
  // Degrees: no id more than twice among the 2n endpoints.
  for (size_t i = 0; i < n; ++i)
    for (const uint32_t id : {link[i].first, link[i].second}) {
      int count = 0;
      for (size_t j = 0; j < n; ++j) count += (link[j].first == id) + (link[j].second == id);
      if (count > 2) return false;
    }
  for (size_t i = 0; i < n; ++i) label[i] = uint32_t(i);
  auto find = [&](uint32_t x) {
    while (label[x] != x) x = label[x];
    return x;
  };
  size_t parts = n;
  for (size_t i = 0; i < n; ++i)
    for (size_t j = i + 1; j < n; ++j) {
      const auto a = link[i], b = link[j];
      if (a.first == b.first || a.first == b.second || a.second == b.first || a.second == b.second) {
        const uint32_t ri = find(uint32_t(i)), rj = find(uint32_t(j));
        if (ri != rj) {
          label[std::max(ri, rj)] = std::min(ri, rj);
          --parts;
        }
      }
    }
  return parts == 1;
}

/// A half-edge seen from its lower endpoint: the higher endpoint, the triangle and the
/// corner it leaves from, and whether it runs from the lower endpoint to the higher.
struct LoHalfEdge {
  uint32_t hi, face;
  uint8_t corner;
  bool forward;
  bool operator<(const LoHalfEdge& o) const {
    return hi != o.hi ? hi < o.hi : (face != o.face ? face < o.face : corner < o.corner);
  }
};

/// A corner at a vertex: its index 3 f + c, and its triangle's next and previous vertex.
struct Corner {
  uint32_t k, to, from;
};

/// Do the n corners at v form a closed, consistently oriented fan: no corner with v twice
/// or its other two vertices equal, every corner's next vertex distinct, and following each
/// corner to the one whose next vertex is its previous vertex a single cycle through all n?
/// If so, cycle[0..n) lists the corners in that order. Fans of more than 32 corners take
/// the general test.
bool closed_fan_cycle(const Corner* c, size_t n, uint32_t v, uint8_t* cycle) {
  if (n < 3 || n > 32) return false;
  for (size_t i = 0; i < n; ++i) {
    if (c[i].to == v || c[i].from == v || c[i].to == c[i].from) return false;
    for (size_t j = i + 1; j < n; ++j)
      if (c[i].to == c[j].to) return false;
  }
  size_t at = 0;
  for (size_t step = 0; step < n; ++step) {
    cycle[step] = uint8_t(at);
    const uint32_t want = c[at].from;
    size_t next = n;
    for (size_t j = 0; j < n; ++j)
      if (c[j].to == want) {
        next = j;
        break;
      }
    if (next == n || (next == 0) != (step + 1 == n)) return false;
    at = next;
  }
  return true;
}

/// Per-thread scratch of the per-vertex passes.
struct Scratch {
  uint8_t cycle[32];
  SmallVector<std::pair<uint32_t, uint32_t>, 32> link;
  SmallVector<uint32_t, 64> others;
  SmallVector<uint64_t, 32> pairs;
  SmallVector<LoHalfEdge, 64> half;
  SmallVector<uint32_t, 32> comps;
};

// Per corner, at the corner's vertex v, a record of the edges whose lower endpoint is v and
// whose first triangle (the lowest) this corner's is: the edge out of v (to the corner's next
// vertex) in the low three bits, the edge into v (from the previous vertex) in the next three,
// each its kind and whether it has an orientation conflict; and whether this is the first
// corner of a vertex whose triangles are all one component (it counts that vertex). Each
// corner's record is written by its own vertex's pass only.
constexpr uint8_t kBoundary = 1, kManifold = 2, kNonManifold = 3, kConflict = 4;
constexpr int kInEdgeShift = 3;
constexpr uint8_t kCountsVertex = 0x40;

/// A triangle's term of its closed component's signed volume, about the first vertex of the
/// component's lowest triangle (for accuracy); both reports sum these in triangle order.
inline double volume_term(const TriMesh& mesh, uint32_t origin, const Triangle& t) {
  return detail::signed_volume6(mesh.positions[origin], mesh.positions[t[0]], mesh.positions[t[1]],
                                mesh.positions[t[2]]) /
         6.0;
}

/// A degenerate triangle: a repeated vertex index or zero area.
inline bool degenerate(const TriMesh& mesh, const Triangle& t) {
  if (t[0] == t[1] || t[1] == t[2] || t[0] == t[2]) return true;
  const Vec3 c = cross(mesh.positions[t[1]] - mesh.positions[t[0]], mesh.positions[t[2]] - mesh.positions[t[0]]);
  return squared_norm(c) == 0;
}

}  // namespace

TopologyReport topology_report(const TriMesh& mesh) {
  TopologyReport r;
  const auto& T = mesh.triangles;
  const size_t F = T.size();
  const size_t V = mesh.positions.size();
  r.vertices = V;
  r.triangles = F;
  {
    std::atomic<bool> out_of_range{false};
    detail::parallel_blocks(F, 65536, [&](size_t b, size_t e) {
      for (size_t f = b; f < e; ++f)
        if (T[f][0] >= V || T[f][1] >= V || T[f][2] >= V) out_of_range.store(true, kRelaxed);
    });
    if (out_of_range) {
      // A report must not read out of bounds; treat the mesh as unusable.
      r.degenerate_triangles = F;
      return r;
    }
  }

  // Corners by vertex (corner 3 f + c, with the corner's next and previous vertex, so that
  // the per-vertex passes read no triangle), each vertex's in increasing order: counted and
  // placed per fixed chunk of triangles.
  std::vector<uint32_t> vf_off;
  detail::FreshArray<Corner> vf;
  detail::bucket_corners_by_vertex(T, V, vf_off, vf, [&](size_t f, uint32_t c) {
    return Corner{uint32_t(3 * f + c), T[f][(c + 1) % 3], T[f][(c + 2) % 3]};
  });

  // One pass over the vertices: is each used, is its fan one disk or one fan; the edges whose
  // lower endpoint it is (its half-edges to higher vertices, grouped by a local sort: in
  // vertex order, the order of a global sort of all edges), each recorded at its first
  // half-edge's corner (one writer per corner) and joining its triangles; and the triangles
  // whose lowest vertex it is that repeat an earlier one (duplicates).
  std::vector<uint8_t> vertex_bad(V, 0);
  std::vector<uint8_t> corner_edge(3 * F, 0);  // see kInEdgeShift
  detail::ConcurrentDisjointSets faces(F);
  struct BoundaryHalf {
    uint32_t lo, hi, face;
    uint8_t corner;
    bool operator<(const BoundaryHalf& o) const { return lo != o.lo ? lo < o.lo : hi < o.hi; }
  };
  struct Counts {
    size_t duplicates = 0, used = 0, edges = 0, boundary = 0, manifold = 0, nonmanifold = 0, conflicts = 0;
    std::vector<BoundaryHalf> boundary_halves;
  };
  tbb::combinable<Scratch> scratch;
  tbb::combinable<Counts> counts;
  detail::parallel_blocks(V, 2048, [&](size_t vb, size_t ve) {
    Scratch& s = scratch.local();
    Counts& n = counts.local();
    for (size_t vi = vb; vi < ve; ++vi) {
      const uint32_t v = uint32_t(vi);
      const uint32_t begin = vf_off[v], end = vf_off[v + 1];
      if (begin == end) continue;
      ++n.used;
      // The common case: a closed, consistently oriented fan. Each neighbour w is the next
      // vertex of exactly one corner and the previous vertex of exactly one, and the corners
      // chain (a corner's previous vertex is the next one's next vertex) into one cycle through
      // all of them: each edge {v, w} is then manifold, without conflict, its two half-edges
      // those of two consecutive corners, and no triangle at v repeats another. Anything else
      // (a boundary, a flip, a pinch, a repeated corner or triangle) takes the general pass.
      if (closed_fan_cycle(&vf[begin], end - begin, v, s.cycle)) {
        const size_t deg = end - begin;
        for (size_t q = 0; q < deg; ++q) {
          const Corner& in = vf[begin + s.cycle[q]];                       // the half-edge into v from w
          const Corner& out = vf[begin + s.cycle[q + 1 == deg ? 0 : q + 1]];  // out of v to w
          const uint32_t w = out.to;
          if (w < v) continue;
          const uint32_t fi = in.k / 3, fo = out.k / 3;
          // Recorded at v's corner of the edge's lower triangle.
          if (fi < fo) corner_edge[in.k] |= kManifold << kInEdgeShift;
          else corner_edge[out.k] |= kManifold;
          faces.unite(fi, fo);
          ++n.manifold;
          ++n.edges;
        }
        vertex_bad[v] = 0;
        corner_edge[vf[begin].k] |= kCountsVertex;
        continue;
      }
      s.link.clear();
      s.pairs.clear();
      s.half.clear();
      bool bad = false;
      for (uint32_t i = begin; i < end; ++i) {
        const uint32_t to = vf[i].to, from = vf[i].from, k = vf[i].k;
        // The fan: the opposite edge of every triangle at v (a triangle with v twice, or
        // with its other two corners equal, makes v non-manifold).
        if (to == v || from == v || to == from) bad = true;
        else s.link.push_back({to, from});
        // Half-edges at this corner whose lower endpoint is v: out of v and into v.
        if (to != v && to > v) s.half.push_back({to, k / 3, uint8_t(k % 3), true});
        if (from != v && from > v) s.half.push_back({from, k / 3, uint8_t((k % 3 + 2) % 3), false});
        // Duplicates: each triangle once, at its lowest vertex (a triangle with v twice is
        // counted at the corner followed by v; one with v three times at its first corner).
        if (to >= v && from >= v) {
          const bool first = (to != v && from != v) || (to == v && from != v) || (to == v && from == v && k % 3 == 0);
          if (first) s.pairs.push_back((uint64_t(std::min(to, from)) << 32) | std::max(to, from));
        }
      }
      if (!bad) bad = !link_is_one_fan(s.link.data(), s.link.size());
      vertex_bad[v] = bad;
      if (!bad) corner_edge[vf[begin].k] |= kCountsVertex;
      if (s.pairs.size() > 1) {
        s.pairs.sort();
        for (size_t i = 1; i < s.pairs.size(); ++i) n.duplicates += s.pairs[i] == s.pairs[i - 1];
      }
      s.half.sort();
      for (size_t i = 0; i < s.half.size();) {
        size_t j = i + 1;
        while (j < s.half.size() && s.half[j].hi == s.half[i].hi) ++j;
        const LoHalfEdge& first = s.half[i];
        for (size_t q = i + 1; q < j; ++q) faces.unite(first.face, s.half[q].face);
        uint8_t kind;
        if (j - i == 1) {
          kind = kBoundary;
          ++n.boundary;
          n.boundary_halves.push_back({v, first.hi, first.face, first.corner});
        } else if (j - i == 2) {
          const bool conflict = first.forward == s.half[i + 1].forward;
          kind = kManifold | (conflict ? kConflict : 0);
          ++n.manifold;
          n.conflicts += conflict;
        } else {
          kind = kNonManifold;
          ++n.nonmanifold;
        }
        // At v's corner of the first triangle: the half-edge's own corner if it leaves v, the
        // next one if it enters v.
        if (first.forward) corner_edge[3 * size_t(first.face) + first.corner] |= kind;
        else corner_edge[3 * size_t(first.face) + (first.corner + 1) % 3] |= uint8_t(kind << kInEdgeShift);
        ++n.edges;
        i = j;
      }
    }
  });
  std::vector<BoundaryHalf> boundary;
  counts.combine_each([&](const Counts& n) {
    r.duplicate_triangles += n.duplicates;
    r.vertices_used += n.used;
    r.edges += n.edges;
    r.boundary_edges += n.boundary;
    r.manifold_edges += n.manifold;
    r.nonmanifold_edges += n.nonmanifold;
    r.orientation_conflicts += n.conflicts;
    boundary.insert(boundary.end(), n.boundary_halves.begin(), n.boundary_halves.end());
  });
  std::sort(boundary.begin(), boundary.end());  // edge order: (lower, higher endpoint)
  std::vector<uint32_t> boundary_off;           // per vertex: its boundary edges (as lower endpoint)
  if (!boundary.empty()) {
    boundary_off.assign(V + 1, 0);
    for (const BoundaryHalf& h : boundary) ++boundary_off[h.lo + 1];
    for (size_t v = 0; v < V; ++v) boundary_off[v + 1] += boundary_off[v];
  }

  // Components, numbered by their lowest triangle (each set's root) in triangle order.
  detail::FreshArray<uint32_t> comp(F);  // every entry written by the first pass below
  std::vector<uint32_t> root_face;  // per component: its lowest triangle
  size_t ncomp = 0;
  {
    constexpr size_t kChunk = 65536;
    const size_t chunks = (F + kChunk - 1) / kChunk;
    std::vector<uint32_t> roots_before(chunks + 1, 0);
    detail::parallel_blocks(chunks, 1, [&](size_t cb, size_t ce) {
      for (size_t h = cb; h < ce; ++h) {
        uint32_t n = 0;
        for (size_t f = h * kChunk; f < std::min(F, (h + 1) * kChunk); ++f) {
          const uint32_t root = faces.find(uint32_t(f));
          comp[f] = root;  // the root for now
          n += root == f;
        }
        roots_before[h + 1] = n;
      }
    });
    for (size_t h = 0; h < chunks; ++h) roots_before[h + 1] += roots_before[h];
    ncomp = roots_before[chunks];
    root_face.resize(ncomp);
    detail::parallel_blocks(chunks, 1, [&](size_t cb, size_t ce) {
      for (size_t h = cb; h < ce; ++h) {
        uint32_t id = roots_before[h];
        for (size_t f = h * kChunk; f < std::min(F, (h + 1) * kChunk); ++f)
          if (comp[f] == f) root_face[id++] = uint32_t(f);
      }
    });
    // Each triangle's root is a lower triangle: its component is the root's rank among the
    // roots, found by binary search (components are few) or, when many, through a table.
    if (ncomp < 64) {
      detail::parallel_blocks(F, 65536, [&](size_t b, size_t e) {
        for (size_t f = b; f < e; ++f)
          comp[f] = uint32_t(std::lower_bound(root_face.begin(), root_face.end(), comp[f]) - root_face.begin());
      });
    } else {
      std::vector<uint32_t> id_of_root(F);
      detail::parallel_blocks(ncomp, 65536, [&](size_t b, size_t e) {
        for (size_t c = b; c < e; ++c) id_of_root[root_face[c]] = uint32_t(c);
      });
      detail::parallel_blocks(F, 65536, [&](size_t b, size_t e) {
        for (size_t f = b; f < e; ++f) comp[f] = id_of_root[comp[f]];
      });
    }
  }

  // Per component: triangles, edges by kind, orientation conflicts, vertices, bad vertices.
  std::vector<std::atomic<uint64_t>> c_tris(ncomp), c_edges(ncomp), c_boundary(ncomp), c_nonmanifold(ncomp),
      c_conflict(ncomp), c_vertices(ncomp), c_bad_vertex(ncomp);  // value-initialised: 0
  r.nonmanifold_vertices = size_t(std::count(vertex_bad.begin(), vertex_bad.end(), uint8_t(1)));
  // Triangles, edges and the vertices whose triangles are one component, from the corners'
  // records in triangle order.
  // What a corner's record counts, by record: edges, boundary, non-manifold, conflicts,
  // vertices (a byte each).
  std::array<uint64_t, 128> counts_of{};
  for (uint32_t info = 0; info < 128; ++info) {
    uint64_t n = (info & kCountsVertex) ? uint64_t(1) << 32 : 0;
    for (const uint32_t edge : {info & 7, (info >> kInEdgeShift) & 7}) {
      if (edge == 0) continue;
      n += 1;
      if ((edge & 3) == kBoundary) n += uint64_t(1) << 8;
      if ((edge & 3) == kNonManifold) n += uint64_t(1) << 16;
      if (edge & kConflict) n += uint64_t(1) << 24;
    }
    counts_of[info] = n;
  }
  detail::parallel_blocks(F, 16384, [&](size_t b, size_t e) {
    RunAdder tris(c_tris), edges(c_edges), bnd(c_boundary), nonmanifold(c_nonmanifold), conflict(c_conflict),
        verts(c_vertices);
    for (size_t f = b; f < e; ++f) {
      const uint32_t cf = comp[f];
      tris.add(cf);
      const uint64_t n = counts_of[corner_edge[3 * f] & 127] + counts_of[corner_edge[3 * f + 1] & 127] +
                         counts_of[corner_edge[3 * f + 2] & 127];  // each byte at most 6: no carries
      if (n == 0) continue;
      edges.add(cf, uint32_t(n & 255));
      if (n & 0xffffff00) {
        bnd.add(cf, uint32_t((n >> 8) & 255));
        nonmanifold.add(cf, uint32_t((n >> 16) & 255));
        conflict.add(cf, uint32_t((n >> 24) & 255));
      }
      verts.add(cf, uint32_t(n >> 32));
    }
  });
  // The non-manifold vertices: in each of their triangles' components, a vertex and a bad one.
  if (r.nonmanifold_vertices > 0) {
    detail::parallel_blocks(V, 4096, [&](size_t vb, size_t ve) {
      Scratch& s = scratch.local();
      RunAdder verts(c_vertices), bad(c_bad_vertex);
      for (size_t v = vb; v < ve; ++v) {
        if (!vertex_bad[v]) continue;
        s.comps.clear();
        for (uint32_t i = vf_off[v]; i < vf_off[v + 1]; ++i) s.comps.push_back(comp[vf[i].k / 3]);
        s.comps.sort();
        for (size_t i = 0; i < s.comps.size(); ++i) {
          if (i > 0 && s.comps[i] == s.comps[i - 1]) continue;
          verts.add(s.comps[i]);
          bad.add(s.comps[i]);
        }
      }
    });
  }
  std::vector<ComponentReport> C(ncomp);
  for (size_t c = 0; c < ncomp; ++c) {
    C[c].triangles = c_tris[c].load(kRelaxed);
    C[c].edges = c_edges[c].load(kRelaxed);
    C[c].boundary_edges = c_boundary[c].load(kRelaxed);
    C[c].nonmanifold_edges = c_nonmanifold[c].load(kRelaxed);
    C[c].vertices = c_vertices[c].load(kRelaxed);
  }

  // Boundary loops.
  std::vector<uint32_t> loops_per_comp(ncomp, 0);
  const bool traceable = r.nonmanifold_edges == 0 && r.orientation_conflicts == 0;
  if (traceable && r.boundary_edges > 0) {
    // The triangle holding the directed half-edge (from, to), the first in (triangle,
    // corner) order; -1 if none.
    auto find_half = [&](uint32_t from, uint32_t to) -> int64_t {
      if (from == to) return -1;
      for (uint32_t i = vf_off[from]; i < vf_off[from + 1]; ++i)
        if (vf[i].to == to) return vf[i].k / 3;
      return -1;
    };
    // The slot of boundary edge {from, to} among the boundary edges (in edge order) if it
    // runs from `from` to `to`; else -1.
    auto boundary_slot = [&](uint32_t from, uint32_t to) -> int64_t {
      if (from == to) return -1;
      const uint32_t lo = std::min(from, to), hi = std::max(from, to);
      for (uint32_t i = boundary_off[lo]; i < boundary_off[lo + 1]; ++i)
        if (boundary[i].hi == hi) return T[boundary[i].face][boundary[i].corner] == from ? int64_t(i) : -1;
      return -1;
    };
    std::vector<uint8_t> visited(boundary.size(), 0);
    for (size_t start = 0; start < boundary.size(); ++start) {
      if (visited[start]) continue;
      size_t cur = start;
      size_t guard = 0, edges = 0;
      while (!visited[cur] && guard++ <= boundary.size()) {
        visited[cur] = 1;
        ++edges;
        const BoundaryHalf& h = boundary[cur];
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
          if (slot >= 0) {
            next = slot;
            break;
          }
          const int64_t g = find_half(c, b);
          if (g < 0) break;
          f = uint32_t(g);
        }
        if (next < 0) break;
        cur = size_t(next);
      }
      ++r.boundary_loops;
      ++loops_per_comp[comp[boundary[start].face]];
      r.boundary_loop_edges.push_back(edges);
    }
  } else if (r.boundary_edges > 0) {
    // Not traceable: the connected components of the boundary-edge graph.
    std::vector<uint32_t> parent(V);
    std::iota(parent.begin(), parent.end(), 0u);
    auto find = [&](uint32_t x) {
      while (parent[x] != x) x = parent[x] = parent[parent[x]];
      return x;
    };
    for (size_t v = 0; v < V; ++v)
      for (uint32_t i = boundary_off[v]; i < boundary_off[v + 1]; ++i) {
        const uint32_t a = find(uint32_t(v)), b = find(boundary[i].hi);
        if (a != b) parent[std::max(a, b)] = std::min(a, b);
      }
    std::vector<uint8_t> counted(V, 0);
    std::vector<size_t> edges_at(V, 0);
    for (size_t v = 0; v < V; ++v)
      for (uint32_t i = boundary_off[v]; i < boundary_off[v + 1]; ++i) {
        const uint32_t root = find(uint32_t(v));
        ++edges_at[root];
        if (!counted[root]) {
          counted[root] = 1;
          ++r.boundary_loops;
          ++loops_per_comp[comp[boundary[i].face]];
        }
      }
    for (size_t v = 0; v < V; ++v)
      if (counted[v]) r.boundary_loop_edges.push_back(edges_at[v]);
  }
  std::sort(r.boundary_loop_edges.begin(), r.boundary_loop_edges.end());

  // Finish the per-component records.
  for (size_t c = 0; c < ncomp; ++c) {
    auto& cr = C[c];
    const bool conflict = c_conflict[c].load(kRelaxed) != 0;
    cr.consistently_oriented = !conflict && cr.nonmanifold_edges == 0;
    cr.boundary_loops = loops_per_comp[c];
    cr.euler_characteristic = int64_t(cr.vertices) - int64_t(cr.edges) + int64_t(cr.triangles);
    cr.manifold = cr.nonmanifold_edges == 0 && c_bad_vertex[c].load(kRelaxed) == 0;
    cr.closed = cr.manifold && cr.boundary_edges == 0;
    if (cr.manifold) {
      const int64_t twice = 2 - cr.euler_characteristic - int64_t(cr.boundary_loops);
      cr.genus = twice >= 0 && twice % 2 == 0 ? int(twice / 2) : -1;
    }
  }
  // The one pass that reads the positions: degenerate triangles (a repeated vertex or zero
  // area), and the signed volumes of closed components, about the first vertex of each one's
  // lowest triangle for accuracy: the terms in parallel (each written before it is read),
  // summed in triangle order.
  const bool any_closed = std::any_of(C.begin(), C.end(), [](const ComponentReport& c) { return c.closed; });
  std::unique_ptr<double[]> term(any_closed ? new double[F] : nullptr);
  {
    tbb::combinable<size_t> count;
    detail::parallel_blocks(F, 16384, [&](size_t b, size_t e) {
      size_t n = 0;
      for (size_t f = b; f < e; ++f) {
        const Triangle& t = T[f];
        n += degenerate(mesh, t);
        if (any_closed && C[comp[f]].closed) term[f] = volume_term(mesh, T[root_face[comp[f]]][0], t);
      }
      count.local() += n;
    });
    r.degenerate_triangles = count.combine(std::plus<size_t>());
  }
  if (any_closed) {
    std::vector<double> vol(ncomp, 0.0);
    for (size_t f = 0; f < F; ++f)
      if (C[comp[f]].closed) vol[comp[f]] += term[f];
    for (size_t c = 0; c < ncomp; ++c) C[c].signed_volume = vol[c];
  }

  r.components = ncomp;
  r.euler_characteristic = int64_t(r.vertices_used) - int64_t(r.edges) + int64_t(r.triangles);
  r.manifold = r.nonmanifold_edges == 0 && r.nonmanifold_vertices == 0;
  r.closed = r.manifold && r.boundary_edges == 0 && F > 0;
  r.consistently_oriented = r.orientation_conflicts == 0 && r.nonmanifold_edges == 0;
  // A closed component inside another (a cavity's wall) faces into the cavity: outward is
  // away from the solid each bounds (mesh/nesting.h).
  std::vector<uint8_t> closed_flags(ncomp, 0);
  for (size_t c = 0; c < ncomp; ++c) closed_flags[c] = C[c].closed;
  const std::vector<uint32_t> depth = detail::nesting_depths(mesh.positions, T, comp.data(), ncomp, closed_flags);
  r.outward = true;
  for (size_t c = 0; c < ncomp; ++c) {
    C[c].nesting_depth = depth[c];
    if (C[c].closed) {
      ++r.closed_components;
      if (!detail::faces_away_from_its_solid(C[c].signed_volume, depth[c])) r.outward = false;
    }
  }
  if (r.closed_components == 0) r.outward = false;
  std::vector<size_t> order(ncomp);
  std::iota(order.begin(), order.end(), size_t(0));
  std::stable_sort(order.begin(), order.end(), [&](size_t a, size_t b) { return C[a].triangles > C[b].triangles; });
  r.per_component.reserve(ncomp);
  for (size_t i : order) r.per_component.push_back(C[i]);
  return r;
}

// The report of a subdivided mesh from its control mesh's. One round of 1-to-4 splits of a
// mesh M that is one closed, manifold (every vertex's link one cycle through distinct
// vertices), consistently oriented component without duplicate triangles (no two with the
// same three vertices) and without unused vertices gives a mesh M' that is all of that too:
//  - counts: every vertex stays and every edge gets one new vertex (V' = V + E); every edge
//    becomes two and every triangle gets three inner edges (E' = 2E + 3F); F' = 4F. So
//    V' - E' + F' = V - E + F (the Euler characteristic and, one closed component, the genus).
//  - each old vertex of valence n has the n new vertices of its edges as its link, in the
//    order of its old link: one cycle through distinct vertices. The new vertex e(ab) of
//    edge ab (triangles abx and aby, x != y since they are not duplicates) has the link
//    cycle a, e(ax), e(bx), b, e(by), e(ay): six distinct vertices. So every vertex is
//    manifold, every edge has two triangles (closed), and no triangle repeats a vertex.
//  - a corner triangle (v, e(va), e(vb)) repeats another's vertices only if both come from
//    triangles with the vertices v, a, b, a middle one (e(ab), e(bc), e(ca)) only if both
//    come from triangles with a, b, c: neither can happen without an earlier duplicate, and
//    corner and middle triangles never share their vertex sets (a corner has an old vertex).
//  - each child triangle is wound like its parent, so two children sharing an edge traverse
//    it in opposite directions (inside one parent by construction; across a parent edge
//    because the parents did), and children of edge-adjacent parents share an edge, so the
//    result is one consistently oriented component.
// By induction over the levels, the refined mesh's report is the one written below; only the
// degenerate triangles (zero area: the positions) and the signed volume are measured, with
// the same expressions as topology_report, the volume summed in triangle order from the
// first vertex of triangle 0 (the component's lowest), so every value is the same bits.
std::optional<TopologyReport> subdivided_topology_report(const TopologyReport& control, const TriMesh& refined,
                                                         int levels) {
  const TopologyReport& c = control;
  if (levels < 0 || levels > 16 || c.triangles == 0 || c.components != 1 || !c.closed || !c.manifold ||
      !c.consistently_oriented || c.nonmanifold_vertices != 0 || c.duplicate_triangles != 0 ||
      c.vertices_used != c.vertices || c.boundary_edges != 0)
    return std::nullopt;
  uint64_t V = c.vertices, E = c.edges, F = c.triangles;
  for (int l = 0; l < levels; ++l) {
    V += E;
    E = 2 * E + 3 * F;
    F = 4 * F;
  }
  const auto& T = refined.triangles;
  if (refined.positions.size() != V || T.size() != F || int64_t(V) - int64_t(E) + int64_t(F) != c.euler_characteristic)
    return std::nullopt;

  // The one pass over the positions, serial: the volume is summed in triangle order anyway.
  const size_t nv = refined.positions.size();
  size_t degenerate_triangles = 0;
  double volume = 0.0;
  const uint32_t origin = T[0][0];
  if (origin >= nv) return std::nullopt;
  for (size_t f = 0; f < T.size(); ++f) {
    const Triangle& t = T[f];
    if (t[0] >= nv || t[1] >= nv || t[2] >= nv) return std::nullopt;  // not a subdivision after all
    degenerate_triangles += degenerate(refined, t);
    volume += volume_term(refined, origin, t);
  }

  TopologyReport r;
  r.vertices = r.vertices_used = V;
  r.triangles = F;
  r.edges = r.manifold_edges = E;
  r.degenerate_triangles = degenerate_triangles;
  r.components = r.closed_components = 1;
  r.euler_characteristic = int64_t(V) - int64_t(E) + int64_t(F);
  r.manifold = r.closed = r.consistently_oriented = true;
  r.outward = detail::faces_outward(volume);
  ComponentReport cr;
  cr.triangles = F;
  cr.vertices = V;
  cr.edges = E;
  cr.euler_characteristic = r.euler_characteristic;
  cr.closed = cr.manifold = cr.consistently_oriented = true;
  const int64_t twice = 2 - cr.euler_characteristic;
  cr.genus = twice >= 0 && twice % 2 == 0 ? int(twice / 2) : -1;
  cr.signed_volume = volume;
  r.per_component.push_back(cr);
  return r;
}

}  // namespace particlemesh
