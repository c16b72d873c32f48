// The camera's primary rays traced in tiles of kTile x kTile pixels (beam tracing's idea:
// rays that share an origin and nearly a direction meet nearly the same particles). A tile
// walks the caster's hierarchy once for all its rays, front to back over the pyramid through
// the eye that holds them, and keeps the particles found in the order of a lower bound of
// where any of its rays can enter their supports; each ray then takes that list in order
// instead of walking the hierarchy itself, and the list is only walked as deep as the tile's
// rays need (a first hit stops a ray). The per-ray sweep (raycast_impl.h) is the same, and
// every particle a ray meets is in its tile's list before the ray's horizon passes it, so the
// hits are those of RayCaster::first_hit, bit for bit.
#include <algorithm>
#include <bit>
#include <cmath>

#include "core/parallel.h"
#include "particlemesh/core/error.h"
#include "volume/camera_rays.h"
#include "volume/raycast_impl.h"

namespace PM_NAMESPACE::detail {

namespace {

constexpr int kTile = 12;  // measured: 12 beside 8 and 16 (bench/RESULTS.md)
constexpr double kInf = std::numeric_limits<double>::infinity();
// Relative margin of the tile's tests and bounds: far above the rounding of a ray's own
// entry and direction (~1e-15), far below anything that costs work.
constexpr double kSlack = 1e-9;

// 16 bytes: a tile whose rays go through every particle (a huge radius) holds them all.
struct Candidate {
  double key;  // lower bound of the entry t of every ray of the tile (unit directions)
  uint32_t k;
};

// A candidate as the tile's rays take it: with its sphere, which each of up to kTile^2 rays
// reads, copied once into the list they walk in order (rather than read from four arrays at
// a particle index each time).
struct Listed {
  double key;
  uint32_t k;
  Vec3 centre;
  double r2, inv_r2, w;
};

class TileCandidates {
 public:
  explicit TileCandidates(const RayCaster::Impl& im) : im_(im) {}

  // The tile whose corner pixels' rays are d[0..3], in order around it.
  void start(const Vec3& eye, const Vec3 d[4]) {
    o_ = eye;
    const Vec3 centre = d[0] + d[1] + d[2] + d[3];
    for (int i = 0; i < 4; ++i) {
      Vec3 n = cross(d[i], d[(i + 1) % 4]);
      const double l = norm(n);
      n = l > 0 ? n / l : Vec3{};  // a tile one pixel wide: no constraint that way
      planes_[i] = dot(n, centre) < 0 ? -n : n;
    }
    heap_.clear();
    pending_.clear();
    list.clear();
    if (!im_.nodes.empty() && box_in(im_.nodes[0])) push_node(box_key(im_.nodes[0]), 0);
  }

  // Opens the nearest node not yet opened; false when every one is.
  bool expand() {
    if (heap_.empty()) return false;
    const NodeEntry ne = heap_.front();
    std::pop_heap(heap_.begin(), heap_.end(), node_cmp);
    heap_.pop_back();
    const Node& nd = im_.nodes[ne.node];
    if (nd.count == 0) {
      for (uint32_t c = nd.first; c < nd.first + 2; ++c)
        if (box_in(im_.nodes[c])) push_node(std::max(box_key(im_.nodes[c]), ne.t), c);
    } else {
      for (uint32_t k = nd.first; k < nd.first + nd.count; ++k) {
        const Vec3 q = im_.pos[k] - o_;
        const double r = im_.bound_r[k];
        const double d = norm(q);
        if (!ball_in(q, r, d)) continue;
        // On a unit ray from the eye, t >= 0 at a point of the ball: t >= |q| - r.
        pending_.push_back({std::max(d - r - kSlack * (d + r), ne.t), k});
        std::push_heap(pending_.begin(), pending_.end(), cand_cmp);
      }
    }
    // Nodes not opened begin no nearer than the nearest of them (keys grow down the tree).
    const double h = heap_.empty() ? kInf : heap_.front().t;
    while (!pending_.empty() && pending_.front().key <= h) {
      const Candidate& c = pending_.front();
      list.push_back({c.key, c.k, im_.pos[c.k], im_.r2[c.k], im_.inv_r2[c.k], im_.w[c.k]});
      std::pop_heap(pending_.begin(), pending_.end(), cand_cmp);
      pending_.pop_back();
    }
    return true;
  }

  // Final: keys in increasing order, and every particle not in it has a key >= the last.
  std::vector<Listed> list;

 private:
  using Node = detail::Node;
  static bool node_cmp(const NodeEntry& a, const NodeEntry& b) { return a.t > b.t; }
  static bool cand_cmp(const Candidate& a, const Candidate& b) { return a.key > b.key; }

  void push_node(double key, uint32_t node) {
    heap_.push_back({key, node});
    std::push_heap(heap_.begin(), heap_.end(), node_cmp);
  }

  // Distance from the eye to the box, less the margin: no support inside is entered sooner.
  double box_key(const Node& nd) const {
    double d2 = 0, diag2 = 0;
    for (int a = 0; a < 3; ++a) {
      const double lo = nd.lo[a] - o_[a], hi = nd.hi[a] - o_[a];
      const double da = lo > 0 ? lo : (hi < 0 ? -hi : 0.0);
      d2 += da * da;
      diag2 += (hi - lo) * (hi - lo);
    }
    const double d = std::sqrt(d2);
    return d - kSlack * (d + std::sqrt(diag2));
  }

  // Whether the box reaches into the pyramid (each face's inner side), with the margin.
  bool box_in(const Node& nd) const {
    for (const Vec3& n : planes_) {
      double m = 0, mag = 0;
      for (int a = 0; a < 3; ++a) {
        const double lo = nd.lo[a] - o_[a], hi = nd.hi[a] - o_[a];
        m += n[a] * (n[a] > 0 ? hi : lo);
        mag += std::abs(lo) + std::abs(hi);
      }
      if (m < -kSlack * mag) return false;
    }
    return true;
  }

  bool ball_in(const Vec3& q, double r, double d) const {
    const double margin = r + kSlack * (d + r);
    for (const Vec3& n : planes_)
      if (dot(n, q) < -margin) return false;
    return true;
  }

  const RayCaster::Impl& im_;
  Vec3 o_;
  Vec3 planes_[4];                 // inward normals of the pyramid's faces (through the eye)
  std::vector<NodeEntry> heap_;    // nodes to open, by key
  std::vector<Candidate> pending_; // found, not yet final: a min-heap by key
};

// One ray of a tile: the tile's particles in their order (raycast_impl.h's Source). Spheres
// are tested against the ray a batch of kBatch candidates ahead, without a branch each (about
// a third of a tile's candidates miss a given ray, an unpredictable branch when each was
// tested as it was offered), and those the ray misses are passed over: they would add no
// event, so the horizon is the next sphere the ray meets. Each test is offer_sphere()'s own
// (Query::chord), so the same entries, exits and hits.
struct TileSource {
  static constexpr size_t kBatch = 8;
  TileSource(TileCandidates& t, const RayCaster::Impl::Query& q) : tile(t), query(q) {}
  TileCandidates& tile;
  const RayCaster::Impl::Query& query;
  size_t next = 0;
  size_t batch_begin = 0, batch_end = 0;  // the candidates tested: [batch_begin, batch_end)
  unsigned met = 0;                       // bit i: the ray meets candidate batch_begin + i
  RayCaster::Impl::Query::Chord chords[kBatch] = {};

  void test_batch() {
    batch_begin = next;
    batch_end = std::min(next + kBatch, tile.list.size());
    met = 0;
    for (size_t i = batch_begin; i < batch_end; ++i) {
      chords[i - batch_begin] = query.chord(tile.list[i].centre, tile.list[i].r2);
      met |= unsigned(chords[i - batch_begin].h2 > 0) << (i - batch_begin);
    }
  }

  double horizon() {
    while (true) {
      while (next == tile.list.size() && tile.expand()) {
      }
      if (next == tile.list.size()) return kInf;
      if (query.im.aniso) return tile.list[next].key;
      if (next >= batch_end) test_batch();
      // The next candidate of the batch the ray meets, found from the bits (a branch per
      // candidate, taken for a third of them at random, cost more than the test).
      const unsigned ahead = met >> (next - batch_begin);
      if (ahead != 0) {
        next += size_t(std::countr_zero(ahead));
        return tile.list[next].key;
      }
      next = batch_end;  // the rest of the batch missed: no event
    }
  }
  void advance(RayCaster::Impl::Query& q, Scratch& sc) {
    const size_t i = next++;
    const Listed& c = tile.list[i];
    if (q.im.aniso) {
      q.offer(c.k, sc);
      return;
    }
    const RayCaster::Impl::Query::Chord& ch = chords[i - batch_begin];  // met by the ray (horizon())
    q.enter(c.k, ch.tstar, ch.e2, c.inv_r2, c.w, ch.h2, sc);
  }
};

}  // namespace

void trace_camera(const RayCaster& caster, const CameraRays& rays, int threads, ProgressTracker& tracker,
                  const std::function<void(int x, int y, const RayHit* hit)>& pixel) {
  const RayCaster::Impl* im = RayCasterAccess::of(caster);
  const int W = rays.width, H = rays.height;
  if (im == nullptr || im->nodes.empty()) {  // a moved-from caster, or no particle of any strength
    for (int y = 0; y < H; ++y)
      for (int x = 0; x < W; ++x) pixel(x, y, nullptr);
    tracker.tick(uint64_t(H));
    return;
  }
  const size_t tile_rows = size_t((H + kTile - 1) / kTile);
  with_threads(threads, [&] {
    parallel_blocks(tile_rows, 1, [&](size_t r0, size_t r1) {
      const RayCancelScope scope(&tracker);  // a long ray checks it too
      Scratch& sc = ray_scratch();
      TileCandidates tile(*im);
      for (size_t tr = r0; tr < r1; ++tr) {
        const int y0 = int(tr) * kTile, y1 = std::min(H, y0 + kTile);
        for (int x0 = 0; x0 < W; x0 += kTile) {
          if (tracker.cancelled()) return;
          tracker.tick(0);
          const int x1 = std::min(W, x0 + kTile);
          const Vec3 corners[4] = {rays.direction(x0, y0), rays.direction(x1 - 1, y0),
                                   rays.direction(x1 - 1, y1 - 1), rays.direction(x0, y1 - 1)};
          tile.start(rays.eye, corners);
          for (int y = y0; y < y1; ++y)
            for (int x = x0; x < x1; ++x) {
              const Vec3 dir = rays.direction(x, y);
              sc.hits.clear();
              auto q = make_query(*im, rays.eye, dir, 0.0, kInf, true, &sc.hits);
              TileSource source(tile, q);
              q.sweep(sc, source);
              pixel(x, y, sc.hits.empty() ? nullptr : &sc.hits.front());
            }
        }
        tracker.tick(uint64_t(y1 - y0));
      }
    });
  });
}

}  // namespace particlemesh::detail
