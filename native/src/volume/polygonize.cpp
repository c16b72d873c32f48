#include "particlemesh/volume/polygonize.h"

#include <algorithm>
#include <array>
#include <atomic>
#include <bit>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <memory>
#include <numbers>
#include <optional>
#include <string>

#include <tbb/parallel_sort.h>

#include "core/first_touch.h"
#include "core/hashing.h"
#include "core/huge_pages.h"
#include "core/parallel.h"
#include "core/progress_tracker.h"
#include "particlemesh/core/error.h"
#include "volume/anisotropic_sampling.h"
#include "volume/block_proofs.h"
#include "volume/cell_bits.h"
#include "volume/field_impl.h"
#include "volume/mc_table.h"
#include "volume/polygonize_finish.h"
#include "volume/sphere_sampling.h"
#include "volume/surface_vertices.h"

namespace PM_NAMESPACE {

namespace {

using Clock = std::chrono::steady_clock;
double seconds_since(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }

std::string num(double v) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.6g", v);
  return buf;
}

std::string bytes_text(double b) {
  char buf[64];
  if (b >= double(1ull << 30)) std::snprintf(buf, sizeof buf, "%.3g GiB", b / double(1ull << 30));  // %g: 1e300 bytes is not 300 digits
  else if (b >= double(1ull << 20)) std::snprintf(buf, sizeof buf, "%.1f MiB", b / double(1ull << 20));
  else std::snprintf(buf, sizeof buf, "%.0f bytes", b);
  return buf;
}

// ---- the sparse block grid -----------------------------------------------------------------
//
// Nodes sit at origin + h (i, j, k). A block holds the 8 x 8 x 8 nodes [8b, 8b + 8) on each
// axis; block coordinates are packed 21 bits per axis (z highest), so key order is z, y, x.
constexpr int kB = detail::kSampleBlock;
constexpr int kBN = kB * kB * kB;        // nodes per block
using detail::kL;                        // the local gather spans one more node per axis
constexpr int kLN = kL * kL * kL;
using detail::kMaskWords;                // one bit per (node, axis) edge owned by a block
using detail::BlockRange;
using detail::bit_count;
constexpr int64_t kMaxBlocksPerAxis = (int64_t(1) << 21) - 2;
constexpr uint32_t kNone = 0xffffffffu;

uint64_t pack(int64_t bx, int64_t by, int64_t bz) {
  return (uint64_t(bz) << 42) | (uint64_t(by) << 21) | uint64_t(bx);
}
void unpack(uint64_t k, int64_t* b) {
  b[0] = int64_t(k & 0x1fffff);
  b[1] = int64_t((k >> 21) & 0x1fffff);
  b[2] = int64_t(k >> 42);
}

// Sorted keys -> index (core/hashing.h's open-addressing table).
class BlockMap {
 public:
  explicit BlockMap(const std::vector<uint64_t>& sorted_keys)
      : keys_(sorted_keys), mask_(detail::build_key_table(keys_, table_)) {}
  uint32_t find(uint64_t key) const { return detail::find_key(table_, mask_, keys_, key); }
  size_t bytes() const { return table_.size() * sizeof(uint32_t); }

 private:
  const std::vector<uint64_t>& keys_;
  std::vector<uint32_t> table_;
  uint64_t mask_ = 0;
};

// What the mesher keeps per block of the marching set.
struct MeshBlock {
  uint32_t sampled = kNone;   // index of the block's samples, kNone = all zero
  uint32_t up[7];             // marching-set index of block b + d, d = 1..7 (bit 0 x, 1 y, 2 z)
  uint32_t vertex_offset = 0; // first vertex of the block: its edge crossings, then its
  uint32_t edge_vertices = 0; // cells' inside vertices (see McTable::center_count)
  uint32_t center_vertices = 0;
  uint64_t triangle_offset = 0;  // first triangle of the block's cells
  uint32_t triangle_count = 0;
  bool mixed = false;         // some inside and some outside node among its 9^3
  uint64_t mask[kMaskWords];  // edges with a crossing: bit 3 * (x + 8 (y + 8 z)) + axis
  uint16_t prefix[kMaskWords];// crossings before each mask word
};

struct Grid {
  Vec3 origin;
  double h = 0;
  std::vector<uint64_t> sampled_keys;  // blocks some support reaches, sorted
  // Per block of sampled_keys: what block_proofs.h proved (None, Inside, Outside), and its
  // samples (kBN floats, node x + 8 (y + 8 z)) or nullptr for a proven block left unsampled.
  std::vector<detail::BlockProof> proof;
  std::vector<const float*> samples;
  // sampled_keys' indices in the order of the particles in memory (by x, then y, then z, as
  // the field's grid keeps them): proving and sampling in it read the particles near each
  // other one block after the next.
  std::vector<uint32_t> memory_order;
  // The samples' storage: uninitialised, each block's kBN floats written by its sampling
  // (which starts from zero itself), so its pages are first touched on all cores.
  detail::FreshArray<float> values, more_values;
  std::vector<uint64_t> mesh_keys;     // sampled blocks and their lower neighbours, sorted
  std::vector<MeshBlock> mesh;
};

// The 9^3 samples of block b's nodes [8b, 8b + 8] from the up to 8 blocks holding them.
void gather(const Grid& g, const MeshBlock& mb, float* local) {
  for (int d = 0; d < 8; ++d) {
    const uint32_t mi = d == 0 ? kNone : mb.up[d - 1];
    const uint32_t si = d == 0 ? mb.sampled : (mi == kNone ? kNone : g.mesh[mi].sampled);
    const int dx = d & 1, dy = (d >> 1) & 1, dz = (d >> 2) & 1;
    const int x0 = dx ? kB : 0, x1 = dx ? kB + 1 : kB;
    const int y0 = dy ? kB : 0, y1 = dy ? kB + 1 : kB;
    const int z0 = dz ? kB : 0, z1 = dz ? kB + 1 : kB;
    const float* src = si == kNone ? nullptr : g.samples[si];
    // Unsampled: no support reaches it (F = 0), or proven outside (any value below T does)
    // or inside (any value at or above T): such nodes are in no crossing cell.
    const float fill = si != kNone && g.proof[si] == detail::BlockProof::Inside
                           ? std::numeric_limits<float>::infinity() : 0.0f;
    // A row of x at a time, copied or filled (the test of src per node, inside the loop,
    // kept the compiler from copying rows whole): a whole row of kB nodes, or the one node
    // at x = kB from the block beyond.
    const int width = x1 - x0;
    for (int z = z0; z < z1; ++z)
      for (int y = y0; y < y1; ++y) {
        float* to = local + x0 + kL * (y + kL * z);
        if (src == nullptr) {
          std::fill_n(to, width, fill);
          continue;
        }
        const float* from = src + kB * ((y - y0) + kB * (z - z0));
        if (width == kB)
          std::memcpy(to, from, kB * sizeof(float));  // (a fixed size: two moves, no library call)
        else
          to[0] = from[0];
      }
  }
}

// The position of block `key`'s first node.
Vec3 block_first_node(const Grid& g, uint64_t key) {
  int64_t b[3];
  unpack(key, b);
  return {g.origin.x + double(b[0] * kB) * g.h, g.origin.y + double(b[1] * kB) * g.h,
          g.origin.z + double(b[2] * kB) * g.h};
}

// Block indices ordered by x, then y, then z (keys are by z, then y, then x).
std::vector<uint32_t> particle_memory_order(const std::vector<uint64_t>& keys) {
  std::vector<std::pair<uint64_t, uint32_t>> swapped(keys.size());
  for (size_t i = 0; i < keys.size(); ++i) {
    int64_t b[3];
    unpack(keys[i], b);
    swapped[i] = {pack(b[2], b[1], b[0]), uint32_t(i)};
  }
  tbb::parallel_sort(swapped.begin(), swapped.end());
  std::vector<uint32_t> order(keys.size());
  for (size_t i = 0; i < keys.size(); ++i) order[i] = swapped[i].second;
  return order;
}

// Sample the blocks `todo` (indices into sampled_keys) into `storage`, on all cores.
void sample_blocks(const ParticleField& field, Grid& g, const std::vector<uint32_t>& todo,
                   detail::FreshArray<float>& storage, detail::ProgressTracker& tracker) {
  storage = detail::FreshArray<float>(todo.size() * kBN);
  detail::parallel_blocks(todo.size(), 4, [&](size_t bb, size_t be) {
    if (tracker.cancelled()) return;
    for (size_t k = bb; k < be; ++k) {
      const uint32_t i = todo[k];
      float* out = storage.data() + k * kBN;
      const Vec3 first = block_first_node(g, g.sampled_keys[i]);
      if (field.anisotropic()) detail::sample_block_anisotropic(field, first, g.h, out);
      else detail::sample_block_spherical(field, first, g.h, out);
      g.samples[i] = out;
    }
    tracker.tick(be - bb);
  });
}

// Does a node of proven block i share a cell with a node of the other state? Those are the
// nodes of its 26 neighbours next to it: a neighbour one block up along an axis contributes
// its first layer there, one block down its last, one level with it all eight. Unreached
// neighbours are 0 (outside); proven ones have their state; sampled ones are looked at.
bool touches_other_state(const Grid& g, const BlockMap& map, size_t i, double T) {
  const bool inside = g.proof[i] == detail::BlockProof::Inside;
  int64_t b[3];
  unpack(g.sampled_keys[i], b);
  for (int dz = -1; dz <= 1; ++dz)
    for (int dy = -1; dy <= 1; ++dy)
      for (int dx = -1; dx <= 1; ++dx) {
        if (dx == 0 && dy == 0 && dz == 0) continue;
        const uint32_t j = map.find(pack(b[0] + dx, b[1] + dy, b[2] + dz));
        if (j == kNone) {
          if (inside) return true;
          continue;
        }
        const float* v = g.samples[j];
        if (v == nullptr) {
          if ((g.proof[j] == detail::BlockProof::Inside) != inside) return true;
          continue;
        }
        const int x0 = dx > 0 ? 0 : (dx < 0 ? kB - 1 : 0), x1 = dx > 0 ? 0 : kB - 1;
        const int y0 = dy > 0 ? 0 : (dy < 0 ? kB - 1 : 0), y1 = dy > 0 ? 0 : kB - 1;
        const int z0 = dz > 0 ? 0 : (dz < 0 ? kB - 1 : 0), z1 = dz > 0 ? 0 : kB - 1;
        for (int z = z0; z <= z1; ++z)
          for (int y = y0; y <= y1; ++y)
            for (int x = x0; x <= x1; ++x)
              if ((double(v[x + kB * (y + kB * z)]) >= T) != inside) return true;
      }
  return false;
}

// Whether the eight blocks mesh block mb reads (itself and its upper neighbours) are all
// unsampled and of one state: then it has no crossing and needs no gathering.
bool uniform_unsampled(const Grid& g, const MeshBlock& mb) {
  int state = -1;
  for (int d = 0; d < 8; ++d) {
    const uint32_t mi = d == 0 ? kNone : mb.up[d - 1];
    const uint32_t si = d == 0 ? mb.sampled : (mi == kNone ? kNone : g.mesh[mi].sampled);
    int s = 0;
    if (si != kNone) {
      if (g.samples[si] != nullptr) return false;
      s = g.proof[si] == detail::BlockProof::Inside ? 1 : 0;
    }
    if (state >= 0 && s != state) return false;
    state = s;
  }
  return true;
}

inline uint32_t rank_of(const MeshBlock& mb, int bit) {
  const int w = bit >> 6, b = bit & 63;
  return mb.prefix[w] + bit_count(mb.mask[w] & ((uint64_t(1) << b) - 1));
}

// Does some particle's support reach a node of block `key`? (A cheap superset test: the
// support's bounding box against the block's node box.)
bool block_reached(const ParticleField& field, const Grid& g, uint64_t key) {
  int64_t b[3];
  unpack(key, b);
  const double h = g.h;
  const NeighborGrid& grid = field.grid();
  const auto& P = grid.sorted_points();
  const auto& inv_r2s = field.sorted_inverse_squared_radii();
  const bool uniform = field.uniform_radius();
  const double r_common = field.params().radius;
  const double rmax = field.cell_reach();
  double lo[3], hi[3];
  const double o[3] = {g.origin.x, g.origin.y, g.origin.z};
  for (int a = 0; a < 3; ++a) {
    lo[a] = o[a] + double(b[a] * kB) * h;
    hi[a] = lo[a] + double(kB - 1) * h;
  }
  if (field.anisotropic())
    return detail::anisotropic_support_meets_box(field, {lo[0], lo[1], lo[2]}, {hi[0], hi[1], hi[2]});
  const NeighborGrid::CellCoord clo = grid.coord_of({lo[0] - rmax, lo[1] - rmax, lo[2] - rmax});
  const NeighborGrid::CellCoord chi = grid.coord_of({hi[0] + rmax, hi[1] + rmax, hi[2] + rmax});
  bool reached = false;
  auto test = [&](uint32_t s) {
    const double r = uniform ? r_common : 1.0 / std::sqrt(inv_r2s[s]);
    double d2 = 0;
    const double p[3] = {P[s].x, P[s].y, P[s].z};
    for (int a = 0; a < 3; ++a) {
      const double d = p[a] < lo[a] ? lo[a] - p[a] : (p[a] > hi[a] ? p[a] - hi[a] : 0.0);
      d2 += d * d;
    }
    reached = d2 < r * r;
  };
  field.for_each_cell_in(clo, chi, [&](uint32_t c) {
    for (uint32_t s = grid.cell_begin(c); s < grid.cell_end(c) && !reached; ++s) test(s);
  });
  for (uint32_t s = grid.apart_begin(); s < grid.point_count() && !reached; ++s) test(s);
  return reached;
}

// The decision bits of the cell with case cs (both states) whose lower corner is local node
// (x, y, z); its eight samples go to cv.
inline unsigned cell_decisions(const float* local, int x, int y, int z, int cs, double T,
                               const detail::McTable& table, float cv[8]) {
  for (int c = 0; c < 8; ++c)
    cv[c] = local[(x + (c & 1)) + kL * ((y + ((c >> 1) & 1)) + kL * (z + ((c >> 2) & 1)))];
  unsigned decisions = 0;
  const uint8_t amb = table.ambiguous_faces(cs);
  int j = 0;
  for (int f = 0; amb && f < 6; ++f) {
    if (!((amb >> f) & 1)) continue;
    const auto& q = detail::mc_face_corners(f);
    const bool first_in = (cs >> q[0]) & 1;
    const double va = cv[first_in ? q[0] : q[1]], vc = cv[first_in ? q[2] : q[3]];
    const double vb = cv[first_in ? q[1] : q[0]], vd = cv[first_in ? q[3] : q[2]];
    // Asymptotic decider: the bilinear interpolant's saddle value
    // (va vc - vb vd) / ((va + vc) - (vb + vd)) >= T joins the inside corners. Products of
    // floats are exact in double and the sums commute, so both cells sharing this face
    // compute the same bit.
    if (va * vc - vb * vd >= T * ((va + vc) - (vb + vd))) decisions |= 1u << j;
    ++j;
  }
  return decisions;
}

// The distinct blocks of every cell's range (cell_block_range), sorted: marked in a bitmap of
// the ranges' box when that box is small against the ranges' total (dense particles), else
// listed (`counts`: each cell's first slot) and sorted.
template <class Range>
std::vector<uint64_t> candidate_list(size_t ncells, uint64_t total, const std::vector<uint64_t>& counts,
                                     const Range& cell_block_range, detail::ProgressTracker& tracker) {
  int64_t lo[3] = {INT64_MAX, INT64_MAX, INT64_MAX}, hi[3] = {INT64_MIN, INT64_MIN, INT64_MIN};
  for (size_t c = 0; c < ncells; ++c) {
    int64_t blo[3], bhi[3];
    cell_block_range(uint32_t(c), blo, bhi);
    for (int a = 0; a < 3; ++a) {
      lo[a] = std::min(lo[a], blo[a]);
      hi[a] = std::max(hi[a], bhi[a]);
    }
  }
  std::vector<uint64_t> cand;
  const double box = ncells == 0 ? 0.0 : double(hi[0] - lo[0] + 1) * double(hi[1] - lo[1] + 1) * double(hi[2] - lo[2] + 1);
  if (ncells > 0 && box <= 64.0 * double(total) && box < double(uint64_t(1) << 31)) {
    const uint64_t nx = uint64_t(hi[0] - lo[0] + 1), ny = uint64_t(hi[1] - lo[1] + 1);
    std::vector<std::atomic<uint64_t>> bits((uint64_t(box) + 63) / 64);
    detail::parallel_blocks(ncells, 256, [&](size_t cb, size_t ce) {
      for (size_t c = cb; c < ce; ++c) {
        int64_t blo[3], bhi[3];
        cell_block_range(uint32_t(c), blo, bhi);
        for (int64_t z = blo[2]; z <= bhi[2]; ++z)
          for (int64_t y = blo[1]; y <= bhi[1]; ++y)
            for (int64_t x = blo[0]; x <= bhi[0]; ++x) {
              const uint64_t i = (uint64_t(z - lo[2]) * ny + uint64_t(y - lo[1])) * nx + uint64_t(x - lo[0]);
              bits[i >> 6].fetch_or(uint64_t(1) << (i & 63), std::memory_order_relaxed);
            }
      }
      tracker.tick(ce - cb);
    });
    tracker.check();
    // Key order is z, then y, then x: the bitmap's order.
    for (uint64_t w = 0; w < bits.size(); ++w)
      for (uint64_t word = bits[w].load(std::memory_order_relaxed); word != 0; word &= word - 1) {
        const uint64_t i = 64 * w + uint64_t(std::countr_zero(word));
        cand.push_back(pack(lo[0] + int64_t(i % nx), lo[1] + int64_t((i / nx) % ny), lo[2] + int64_t(i / (nx * ny))));
      }
    return cand;
  }
  cand.resize(total);
  detail::parallel_blocks(ncells, 256, [&](size_t cb, size_t ce) {
    for (size_t c = cb; c < ce; ++c) {
      int64_t blo[3], bhi[3];
      cell_block_range(uint32_t(c), blo, bhi);
      uint64_t k = counts[c];
      for (int64_t z = blo[2]; z <= bhi[2]; ++z)
        for (int64_t y = blo[1]; y <= bhi[1]; ++y)
          for (int64_t x = blo[0]; x <= bhi[0]; ++x) cand[k++] = pack(x, y, z);
    }
    tracker.tick(ce - cb);
  });
  tracker.check();
  tbb::parallel_sort(cand.begin(), cand.end());
  cand.erase(std::unique(cand.begin(), cand.end()), cand.end());
  return cand;
}

PolygonizeResult polygonize_field(const ParticleField& field, const PolygonizeOptions& options,
                                  detail::ProgressTracker& tracker, double begin, PolygonizeStats st,
                                  Clock::time_point t_start, const std::vector<VertexAttribute>* attributes) {
  const double T = field.threshold();
  const double R = field.params().radius;
  const double rmax = field.max_radius();
  st.particles = field.size();
  st.kernel = field.kernel();
  st.radius = R;
  st.max_radius = rmax;
  st.threshold = T;
  st.spacing = field.spacing();
  st.radius_defaulted = field.radius_defaulted();
  st.threshold_defaulted = field.threshold_defaulted();
  st.anisotropic = field.anisotropic();
  st.anisotropic_particles = field.anisotropic_count();
  st.calibration_ratio = field.calibration_ratio();
  const FieldAtParticles at = field_at_particles(field);
  st.enclosed_fraction = at.enclosed_fraction;
  st.density_radius = at.density_radius;
  if (!(options.cell_size >= 0) || !std::isfinite(options.cell_size))
    throw Error(Status::InvalidArgument,
                "cell_size is " + num(options.cell_size) + " (must be a finite length > 0, or 0 for the default)");
  const double h = options.cell_size > 0 ? options.cell_size : kDefaultCellFraction * R;
  st.cell_size = h;
  st.cell_size_defaulted = options.cell_size == 0;
  const uint64_t budget = options.max_grid_bytes;

  // A lower bound before anything else: one particle's support alone.
  {
    const double per_particle = 4.0 / 3.0 * std::numbers::pi * std::pow(rmax / h, 3.0) * sizeof(float);
    if (budget != 0 && per_particle > double(budget))
      throw Error(Status::LimitExceeded,
                  "cell size " + num(h) + " is too small for radius " + num(rmax) + ": one particle's support alone spans " +
                      num(per_particle / sizeof(float)) + " grid nodes (" + bytes_text(per_particle) +
                      "), more than the grid memory budget of " + bytes_text(double(budget)) +
                      " (max_grid_bytes; use a larger cell size or raise the budget)");
  }
  Grid g;
  g.h = h;
  // One block plus one cell of margin below the supports, so that every block that can hold
  // a crossing, and its lower neighbours, have non-negative coordinates. Anchored to the lower
  // corner (the whole cloud's for a tile) and the largest radius, not to these particles'
  // supports, so that the tiles of a cloud share its lattice (polygonize.h, "The lattice").
  // Anisotropic kernels are not cut into tiles (each ellipsoid depends on its neighbours):
  // their lattice hangs below their ellipsoids' box.
  g.origin = field.anisotropic() ? field.support_min() - Vec3{1, 1, 1} * (double(kB + 1) * h)
                                 : (field.lower_corner() - Vec3{rmax, rmax, rmax}) - Vec3{1, 1, 1} * (double(kB + 1) * h);
  if (options.lattice_anchor == LatticeAnchor::Space) g.origin = space_anchored_origin(g.origin, h);
  st.origin = g.origin;
  {
    double box_nodes = 1;
    for (int a = 0; a < 3; ++a) {
      const double extent = (field.support_max()[a] - field.support_min()[a]) / h;
      if (!(extent < double(kMaxBlocksPerAxis - 4) * kB))
        throw Error(Status::LimitExceeded,
                    "the particles' supports span " + num(extent) + " cells of size " + num(h) + " along " +
                        std::string(1, "xyz"[a]) + " (at most " + std::to_string((kMaxBlocksPerAxis - 4) * kB) +
                        "): use a larger cell size or remove far outliers");
      box_nodes *= std::floor(extent) + 1;
      // A tile far above its domain's corner: its blocks' coordinates must still fit a key.
      const double top = (field.support_max()[a] - g.origin[a]) / h;
      if (!(top < double(kMaxBlocksPerAxis - 4) * kB))
        throw Error(Status::LimitExceeded,
                    "the particles lie " + num(top) + " cells of size " + num(h) + " above the lattice's origin along " +
                        std::string(1, "xyz"[a]) + " (at most " + std::to_string((kMaxBlocksPerAxis - 4) * kB) +
                        "): use a larger cell size or a domain_min closer to the particles");
    }
    st.bounding_box_nodes = box_nodes < 1.8e19 ? uint64_t(box_nodes) : std::numeric_limits<uint64_t>::max();
    // The lattice's nodes are origin + i h in doubles: where the coordinates are as large as
    // 2^52 cells, neighbouring nodes round to one position and every triangle is a point.
    // Keep 12 bits below a cell for the crossings between nodes.
    constexpr double kMaxCellsFromZero = 1099511627776.0;  // 2^40
    for (int a = 0; a < 3; ++a) {
      const double far = std::max({std::fabs(g.origin[a]), std::fabs(field.support_min()[a]),
                                   std::fabs(field.support_max()[a])});
      if (!(far / h < kMaxCellsFromZero))
        throw Error(Status::LimitExceeded,
                    "cell size " + num(h) + " is too small for coordinates as large as " + num(far) + " along " +
                        std::string(1, "xyz"[a]) + ": the grid's nodes there would not be distinct in double precision "
                        "(at most 2^40 cells from the origin; move the particles nearer the origin or use a larger cell size)");
    }
  }

  // A tile (options.cells): only its cells are meshed, with the nodes and edges they use.
  const bool ranged = options.cells.has_value();
  int64_t cmin[3] = {0, 0, 0}, cmax[3] = {0, 0, 0};
  if (ranged) {
    // Clamped far outside any lattice (block keys have 21 bits per axis): no overflow below.
    constexpr int64_t kFar = int64_t(1) << 40;
    for (int a = 0; a < 3; ++a) {
      if (!(options.cells->min[a] < options.cells->max[a]))
        throw Error(Status::InvalidArgument, std::string("cell range is empty along ") + "xyz"[a] + " (cell_min " +
                                                 std::to_string(options.cells->min[a]) + " >= cell_max " +
                                                 std::to_string(options.cells->max[a]) + ")");
      cmin[a] = std::clamp(options.cells->min[a], -kFar, kFar);
      cmax[a] = std::clamp(options.cells->max[a], -kFar, kFar);
    }
  }
  // Does block `key` hold a node of the range's cells (nodes cmin..cmax)?
  auto block_in_range = [&](uint64_t key) {
    int64_t b[3];
    unpack(key, b);
    for (int a = 0; a < 3; ++a)
      if (b[a] * kB > cmax[a] || b[a] * kB + (kB - 1) < cmin[a]) return false;
    return true;
  };
  // The cells and nodes of block b in the range (all of them without one).
  auto block_range = [&](const int64_t* b) { return ranged ? detail::block_range(b, cmin, cmax) : BlockRange{}; };

  const NeighborGrid& pgrid = field.grid();
  const auto& P = pgrid.sorted_points();
  // The particle grid's cells, then each particle kept apart from them as a unit of its own.
  const size_t ncells = pgrid.cell_count() + (pgrid.point_count() - pgrid.apart_begin());

  // ---- 1. candidate blocks: the blocks each particle-grid cell's supports reach ------------
  tracker.stage("finding blocks", begin, begin + 0.05 * (1 - begin), ncells);
  auto cell_block_range = [&](uint32_t c, int64_t* blo, int64_t* bhi) {
    // Infinite sentinels: a finite one (1e300) stayed the minimum for particles near DBL_MAX,
    // below the grid origin, and the block index overflowed int64 (found by fuzzing).
    constexpr double kInf = std::numeric_limits<double>::infinity();
    double lo[3] = {kInf, kInf, kInf}, hi[3] = {-kInf, -kInf, -kInf};
    const bool apart = c >= pgrid.cell_count();
    const uint32_t first = apart ? pgrid.apart_begin() + (c - uint32_t(pgrid.cell_count())) : pgrid.cell_begin(c);
    const uint32_t last = apart ? first + 1 : pgrid.cell_end(c);
    for (uint32_t s = first; s < last; ++s) {
      const double r = field.uniform_radius() ? R : 1.0 / std::sqrt(field.sorted_inverse_squared_radii()[s]);
      for (int a = 0; a < 3; ++a) {
        // The support's half extent: the radius, or the ellipsoid's along this axis.
        const double e = field.anisotropic() ? double(field.sorted_half_extents()[3 * size_t(s) + size_t(a)]) : r;
        lo[a] = std::min(lo[a], P[s][a] - e);
        hi[a] = std::max(hi[a], P[s][a] + e);
      }
    }
    for (int a = 0; a < 3; ++a) {
      const double o = g.origin[a];
      blo[a] = int64_t(std::floor((lo[a] - o) / h)) / kB;
      bhi[a] = int64_t(std::floor((hi[a] - o) / h)) / kB;
    }
  };
  std::vector<uint64_t> counts(ncells + 1, 0);
  detail::parallel_blocks(ncells, 256, [&](size_t cb, size_t ce) {
    for (size_t c = cb; c < ce; ++c) {
      int64_t blo[3], bhi[3];
      cell_block_range(uint32_t(c), blo, bhi);
      counts[c + 1] = uint64_t(bhi[0] - blo[0] + 1) * uint64_t(bhi[1] - blo[1] + 1) * uint64_t(bhi[2] - blo[2] + 1);
    }
  });
  for (size_t c = 0; c < ncells; ++c) counts[c + 1] += counts[c];
  const uint64_t candidate_keys = counts[ncells];
  if (budget != 0 && double(candidate_keys) * sizeof(uint64_t) > double(budget))
    throw Error(Status::LimitExceeded,
                "the block search alone would need " + bytes_text(double(candidate_keys) * sizeof(uint64_t)) +
                    ", more than the grid memory budget of " + bytes_text(double(budget)) +
                    " (max_grid_bytes; use a larger cell size or raise the budget)");
  std::vector<uint64_t> cand = candidate_list(ncells, candidate_keys, counts, cell_block_range, tracker);
  if (ranged) cand.erase(std::remove_if(cand.begin(), cand.end(), [&](uint64_t k) { return !block_in_range(k); }), cand.end());
  st.candidate_blocks = cand.size();

  // ---- 2. the blocks some support really reaches ----------------------------------------------
  tracker.stage("finding blocks", begin + 0.05 * (1 - begin), begin + 0.1 * (1 - begin), cand.size());
  {
    std::vector<uint8_t> reached(cand.size(), 0);
    detail::parallel_blocks(cand.size(), 64, [&](size_t cb, size_t ce) {
      if (tracker.cancelled()) return;
      for (size_t i = cb; i < ce; ++i) reached[i] = block_reached(field, g, cand[i]);
      tracker.tick(ce - cb);
    });
    tracker.check();
    for (size_t i = 0; i < cand.size(); ++i)
      if (reached[i]) g.sampled_keys.push_back(cand[i]);
  }
  std::vector<uint64_t>().swap(cand);
  {
    std::vector<uint64_t> keys;
    keys.reserve(g.sampled_keys.size() * 8);
    for (uint64_t k : g.sampled_keys) {
      int64_t b[3];
      unpack(k, b);
      for (int d = 0; d < 8; ++d) keys.push_back(pack(b[0] - (d & 1), b[1] - ((d >> 1) & 1), b[2] - ((d >> 2) & 1)));
    }
    tbb::parallel_sort(keys.begin(), keys.end());
    keys.erase(std::unique(keys.begin(), keys.end()), keys.end());
    if (ranged) keys.erase(std::remove_if(keys.begin(), keys.end(), [&](uint64_t k) { return !block_in_range(k); }), keys.end());
    g.mesh_keys = std::move(keys);
  }
  st.reached_blocks = g.sampled_keys.size();
  // The grid's memory: its bookkeeping, then the samples of the blocks sampled. Checked
  // against the budget before each allocation, the bookkeeping first (the samples only add).
  const double bookkeeping =
      double(g.sampled_keys.size()) * (sizeof(uint64_t) + sizeof(float*) + sizeof(detail::BlockProof)) +
      double(g.mesh_keys.size()) * (sizeof(MeshBlock) + sizeof(uint64_t) + 2 * sizeof(uint32_t));
  auto check_budget = [&](size_t sampled) {
    const double bytes = bookkeeping + double(sampled) * (kBN * sizeof(float));
    if (budget != 0 && bytes > double(budget))
      throw Error(Status::LimitExceeded,
                  "the sampled grid would need " + bytes_text(bytes) + " (" + std::to_string(sampled) + " of " +
                      std::to_string(st.reached_blocks) + " blocks of 8^3 nodes of size " + num(h) +
                      " sampled), more than the grid memory budget of " + bytes_text(double(budget)) +
                      " (max_grid_bytes; use a larger cell size or raise the budget)");
    return bytes;
  };
  check_budget(0);
  if (g.mesh_keys.size() >= kNone || st.reached_blocks >= kNone)
    throw Error(Status::LimitExceeded, "more than 4294967294 blocks");
  st.seconds_setup += seconds_since(t_start);

  // ---- 3. sampling, where the surface may be --------------------------------------------------
  auto t0 = Clock::now();
  const size_t ns = g.sampled_keys.size();
  g.proof.assign(ns, detail::BlockProof::None);
  g.samples.assign(ns, nullptr);
  g.memory_order = particle_memory_order(g.sampled_keys);
  if (detail::block_proofs_apply(field)) {
    tracker.stage("proving blocks", begin + 0.1 * (1 - begin), begin + 0.25 * (1 - begin), ns);
    // A block beside one that no support reaches (F = 0 at all of its nodes, one cell from
    // this block's) is as good as never wholly inside (F would have to rise from 0 to T
    // within a cell), so only the outside proof is tried there; a block not proven is just
    // sampled. Most blocks of a thin layer of particles (a sampled surface) are such blocks;
    // inside a fluid, all of a block's neighbours are reached.
    const BlockMap reached(g.sampled_keys);
    auto surrounded = [&](uint64_t key) {
      int64_t b[3];
      unpack(key, b);
      for (int a = 0; a < 3; ++a)
        for (const int64_t d : {int64_t(-1), int64_t(1)}) {
          int64_t n[3] = {b[0], b[1], b[2]};
          n[a] += d;
          if (n[a] < 0 || n[a] > kMaxBlocksPerAxis || reached.find(pack(n[0], n[1], n[2])) == kNone) return false;
        }
      return true;
    };
    detail::parallel_blocks(ns, 4, [&](size_t bb, size_t be) {
      if (tracker.cancelled()) return;
      for (size_t k = bb; k < be; ++k) {
        const uint32_t i = g.memory_order[k];
        const uint64_t key = g.sampled_keys[i];
        g.proof[i] = detail::prove_block(field, block_first_node(g, key), h, surrounded(key));
      }
      tracker.tick(be - bb);
    });
    tracker.check();
  }
  st.seconds_proofs = seconds_since(t0);
  t0 = Clock::now();
  tracker.stage("sampling the field", begin + 0.25 * (1 - begin), begin + 0.6 * (1 - begin), ns);
  std::vector<uint32_t> todo;
  for (const uint32_t i : g.memory_order)
    if (g.proof[i] == detail::BlockProof::None) todo.push_back(i);
  const size_t first_pass = todo.size();
  check_budget(first_pass);
  sample_blocks(field, g, todo, g.values, tracker);
  tracker.check();  // cancelled: stop before the second pass's search over every block
  // A proven block needs its samples after all where one of its nodes shares a cell with a
  // node of the other state: that cell holds a crossing, whose vertex and decider read them.
  {
    const BlockMap sampled_map(g.sampled_keys);
    std::vector<uint8_t> need(ns, 0);
    detail::parallel_blocks(ns, 64, [&](size_t bb, size_t be) {
      for (size_t i = bb; i < be; ++i) need[i] = g.proof[i] != detail::BlockProof::None && touches_other_state(g, sampled_map, i, T);
    });
    todo.clear();
    for (const uint32_t i : g.memory_order)
      if (need[i]) todo.push_back(i);
    st.grid_bytes = uint64_t(check_budget(first_pass + todo.size()));
    sample_blocks(field, g, todo, g.more_values, tracker);
  }
  const double grid_bytes = double(st.grid_bytes);
  tracker.check();
  for (size_t i = 0; i < ns; ++i) {
    if (g.samples[i] != nullptr) ++st.sampled_blocks;
    else if (g.proof[i] == detail::BlockProof::Inside) ++st.inside_blocks;
    else ++st.outside_blocks;
  }
  st.sampled_nodes = uint64_t(st.sampled_blocks) * kBN;
  st.seconds_sampling = seconds_since(t0);

  // ---- 4. classification: crossings per block -----------------------------------------------
  t0 = Clock::now();
  const size_t nm = g.mesh_keys.size();
  tracker.stage("classifying", begin + 0.6 * (1 - begin), begin + 0.7 * (1 - begin), nm);
  g.mesh.resize(nm);
  const detail::McTable& table = detail::McTable::get();
  const float Tf = detail::float_threshold(T);
  {
    const BlockMap mesh_map(g.mesh_keys);
    const BlockMap sampled_map(g.sampled_keys);
    detail::parallel_blocks(nm, 256, [&](size_t bb, size_t be) {
      for (size_t i = bb; i < be; ++i) {
        MeshBlock& mb = g.mesh[i];
        int64_t b[3];
        unpack(g.mesh_keys[i], b);
        mb.sampled = sampled_map.find(g.mesh_keys[i]);
        for (int d = 1; d < 8; ++d)
          mb.up[d - 1] = mesh_map.find(pack(b[0] + (d & 1), b[1] + ((d >> 1) & 1), b[2] + ((d >> 2) & 1)));
      }
    });
    detail::parallel_blocks(nm, 16, [&](size_t bb, size_t be) {
      if (tracker.cancelled()) return;
      std::unique_ptr<float[]> local(new float[kLN]);
      uint16_t rows[kL * kL];
      for (size_t i = bb; i < be; ++i) {
        MeshBlock& mb = g.mesh[i];
        int64_t b[3];
        unpack(g.mesh_keys[i], b);
        bool any_in = false, any_out = false;
        if (!uniform_unsampled(g, mb)) {
          gather(g, mb, local.get());
          detail::inside_rows(local.get(), Tf, rows);
          for (int r = 0; r < kL * kL; ++r) {
            any_in |= rows[r] != 0;
            any_out |= rows[r] != (1u << kL) - 1;
          }
        }
        mb.mixed = any_in && any_out;
        const BlockRange rg = block_range(b);
        if (mb.mixed) detail::crossing_mask(rows, rg, mb.mask);
        else std::memset(mb.mask, 0, sizeof mb.mask);
        uint32_t count = 0;
        for (int w = 0; w < kMaskWords; ++w) {
          mb.prefix[w] = uint16_t(count);
          count += bit_count(mb.mask[w]);
        }
        mb.edge_vertices = count;
        uint32_t centers = 0, triangles = 0;
        if (mb.mixed) {
          float cv[8];
          detail::for_each_mixed_cell(rows, rg, [&](int x, int y, int z, int cs) {
            const unsigned d = cell_decisions(local.get(), x, y, z, cs, T, table, cv);
            centers += uint32_t(table.center_count(cs, d));
            triangles += uint32_t(table.triangle_count(cs, d));
          });
        }
        mb.center_vertices = centers;
        mb.triangle_count = triangles;
      }
      tracker.tick(be - bb);
    });
    tracker.check();
  }
  uint64_t total_vertices = 0, total_triangles = 0;
  for (MeshBlock& mb : g.mesh) {
    mb.vertex_offset = uint32_t(total_vertices);
    mb.triangle_offset = total_triangles;
    total_vertices += uint64_t(mb.edge_vertices) + mb.center_vertices;
    total_triangles += mb.triangle_count;
    if (mb.mixed) ++st.surface_blocks;
    if (total_vertices >= uint64_t(kNone))
      throw Error(Status::LimitExceeded, "the mesh would have more than 4294967294 vertices (use a larger cell size)");
  }

  // ---- 5. vertices (refined on the true field) and triangles --------------------------------
  // The mesh is the other large allocation: counted now, before it is made, against the same
  // budget (tiny radii over many particles made a 1 GB mesh on top of a grid under the budget).
  {
    const double mesh_bytes = double(total_vertices) * 2 * sizeof(Vec3) + double(total_triangles) * sizeof(Triangle) +
                              double(nm) * sizeof(uint64_t);
    if (budget != 0 && grid_bytes + mesh_bytes > double(budget))
      throw Error(Status::LimitExceeded,
                  "the mesh would need " + bytes_text(mesh_bytes) + " (" + std::to_string(total_vertices) +
                      " vertices, " + std::to_string(total_triangles) + " triangles) on top of the sampled grid's " +
                      bytes_text(grid_bytes) + ", more than the grid memory budget of " + bytes_text(double(budget)) +
                      " (max_grid_bytes; use a larger cell size or raise the budget)");
    st.grid_bytes = uint64_t(grid_bytes + mesh_bytes);
  }
  tracker.stage("meshing", begin + 0.7 * (1 - begin), begin + 1.0 * (1 - begin), nm);
  PolygonizeResult result;
  TriMesh& mesh = result.mesh;
  // Every element is written by the parallel pass below; their pages are faulted in on all
  // cores first rather than while resize() zeroes them on this one (first_touch.h).
  detail::resize_touched(mesh.positions, total_vertices);
  detail::resize_touched(mesh.normals, total_vertices);
  detail::resize_touched(mesh.triangles, total_triangles);
  // The particles' attributes at the vertices (AttributeSums), each summed right after its
  // vertex is placed: a crossing's from the particles gathered for its edge.
  std::optional<detail::AttributeSums> attribute_shape;
  if (attributes && !attributes->empty()) attribute_shape.emplace(mesh.attributes, mesh.positions.size(), field, *attributes);
  const bool with_attributes = attribute_shape && attribute_shape->any();
  // Spherical kernels: a crossing's evaluations can go through the particles gathered for its
  // edge (the same values bit for bit, a third of the particles tested each time). Gathering
  // costs about one evaluation of the field, so it pays where a crossing takes two or more:
  // with attributes (one more query at the vertex), or where the field bends (a thin layer
  // of particles: ~2.3 evaluations a crossing), not in a dense block (~1.25). Each task
  // follows the evaluations per crossing it has seen so far; either way the mesh is the same.
  const bool can_gather = !field.anisotropic();
  std::vector<uint64_t> block_evals(nm, 0);
  std::atomic<bool> broken{false};
  detail::parallel_blocks(nm, 4, [&](size_t bb, size_t be) {
    if (tracker.cancelled()) return;
    std::unique_ptr<float[]> local(new float[kLN]);
    uint16_t rows[kL * kL];
    detail::EdgeNeighbours near;
    uint64_t seen_crossings = 0, seen_evals = 0;  // this task's, for choosing to gather
    std::optional<detail::AttributeSums> sums;
    if (with_attributes) sums.emplace(*attribute_shape);
    for (size_t i = bb; i < be; ++i) {
      const MeshBlock& mb = g.mesh[i];
      if (!mb.mixed) continue;
      int64_t b[3];
      unpack(g.mesh_keys[i], b);
      gather(g, mb, local.get());
      const double base[3] = {g.origin.x + double(b[0] * kB) * h, g.origin.y + double(b[1] * kB) * h,
                              g.origin.z + double(b[2] * kB) * h};
      // Vertices of the block's own crossing edges, in bit order.
      uint32_t v = mb.vertex_offset;
      uint64_t evals = 0;
      for (int w = 0; w < kMaskWords; ++w) {
        uint64_t bits = mb.mask[w];
        while (bits) {
          const int bit = 64 * w + std::countr_zero(bits);
          bits &= bits - 1;
          const int li = bit / 3, a = bit % 3;
          const int x = li % kB, y = (li / kB) % kB, z = li / (kB * kB);
          const int l = x + kL * (y + kL * z);
          const int step = a == 0 ? 1 : (a == 1 ? kL : kL * kL);
          const Vec3 pa{base[0] + x * h, base[1] + y * h, base[2] + z * h};
          detail::Crossing c;
          const bool gather_edges = can_gather && (with_attributes || 2 * seen_evals >= 3 * seen_crossings);
          if (gather_edges) {
            near.gather(field, pa, a, h);
            c = detail::refine_crossing(near, pa, a, h, local[l], local[l + step], T);
          } else {
            c = detail::refine_crossing(field, pa, a, h, local[l], local[l + step], T);
          }
          evals += uint64_t(c.evaluations);
          ++seen_crossings;
          seen_evals += uint64_t(c.evaluations);
          mesh.positions[v] = c.position;
          mesh.normals[v] = c.normal;
          if (sums) {
            if (gather_edges) sums->interpolate(v, near, c.position);
            else sums->interpolate(v, field, c.position);
          }
          ++v;
        }
      }
      // Triangles of the block's own cells (and the cells' inside vertices, in cell order).
      Triangle* tris = mesh.triangles.data() + mb.triangle_offset;
      Triangle* const tris_end = tris + mb.triangle_count;
      uint32_t next_center = mb.vertex_offset + mb.edge_vertices;
      detail::inside_rows(local.get(), Tf, rows);
      detail::for_each_mixed_cell(rows, block_range(b), [&](int x, int y, int z, int cs) {
        float cv[8];
        const unsigned decisions = cell_decisions(local.get(), x, y, z, cs, T, table, cv);
        uint32_t center_id[4] = {0, 0, 0, 0};
        const int nc = table.center_count(cs, decisions);
        if (nc > 0) {
          const uint8_t* cl = table.center_loops_begin(cs, decisions);
          const Vec3 cell_lo{base[0] + x * h, base[1] + y * h, base[2] + z * h};
          for (int k = 0; k < nc && k < 4; ++k) {
            const int len = *cl++;
            const detail::Crossing c = detail::center_vertex(field, cell_lo, h, cv, cl, len, T);
            cl += len;
            evals += uint64_t(c.evaluations);
            mesh.positions[next_center] = c.position;
            mesh.normals[next_center] = c.normal;
            if (sums) sums->interpolate(next_center, field, c.position);
            center_id[k] = next_center++;
          }
        }
        const uint8_t* e = table.triangles_begin(cs, decisions);
        const uint8_t* ee = table.triangles_end(cs, decisions);
        for (; e != ee; e += 3) {
          Triangle t;
          for (int k = 0; k < 3; ++k) {
            const int edge = e[k];
            if (edge >= detail::kCenterBase) {
              t[k] = center_id[(edge - detail::kCenterBase) & 3];
              continue;
            }
            const int lc = detail::mc_edge_lower_corner(edge);
            const int axis = detail::mc_edge_axis(edge);
            const int nx = x + (lc & 1), ny = y + ((lc >> 1) & 1), nz = z + ((lc >> 2) & 1);
            const int d = (nx >> 3) | ((ny >> 3) << 1) | ((nz >> 3) << 2);
            const uint32_t owner = d == 0 ? uint32_t(i) : mb.up[d - 1];
            if (owner == kNone) {
              broken = true;
              t[k] = 0;
              continue;
            }
            const MeshBlock& ob = g.mesh[owner];
            const int bit = 3 * ((nx & 7) + kB * ((ny & 7) + kB * (nz & 7))) + axis;
            if (!((ob.mask[bit >> 6] >> (bit & 63)) & 1)) broken = true;
            t[k] = ob.vertex_offset + rank_of(ob, bit);
          }
          if (tris == tris_end) {
            broken = true;  // cannot happen: both passes classify the cells alike
            continue;
          }
          *tris++ = t;
        }
      });
      block_evals[i] = evals;
      if (tris != tris_end) broken = true;
    }
    tracker.tick(be - bb);
  });
  tracker.check();
  if (broken)
    throw Error(Status::Internal, "polygonize: inconsistent cells (an edge without a crossing, or a changed triangle count)");

  for (size_t i = 0; i < nm; ++i) st.field_evaluations += block_evals[i];
  st.vertices = mesh.positions.size();
  st.triangles = mesh.triangles.size();
  st.seconds_meshing = seconds_since(t0);
  result.stats = st;
  return result;
}

}  // namespace

PolygonizeResult polygonize(const ParticleField& field, const PolygonizeOptions& options) {
  detail::ProgressTracker tracker(options.progress);
  const auto t0 = Clock::now();
  if (field.size() == 0) throw Error(Status::InvalidInput, "the field has no particles");
  detail::validate_finishing(options);
  PolygonizeResult r = detail::with_threads(options.threads, [&] {
    PolygonizeResult res = polygonize_field(field, options, tracker, 0.0, PolygonizeStats{}, t0, nullptr);
    detail::finish_polygonized(res, options, field, nullptr, 0, tracker);
    return res;
  });
  tracker.finish();
  return r;
}

PolygonizeResult polygonize(const PointCloud& cloud, const PolygonizeOptions& options) {
  detail::ProgressTracker tracker(options.progress);
  const auto t0 = Clock::now();
  detail::validate_finishing(options);
  PolygonizeResult r = detail::with_threads(options.threads, [&] {
    // The anisotropic kernels cost about as much as the sampling: give them their share.
    const double field_end = options.anisotropy.enabled ? 0.3 : 0.1;
    const ParticleField field = detail::polygonize_field_of(cloud, options, tracker, 0.0, field_end);
    // The attributes are interpolated while the vertices are placed (above).
    PolygonizeResult res =
        polygonize_field(field, options, tracker, field_end, PolygonizeStats{}, t0, &cloud.attributes);
    detail::finish_polygonized(res, options, field, cloud.positions.data(), cloud.positions.size(), tracker,
                               &cloud.attributes);
    return res;
  });
  tracker.finish();
  return r;
}

}  // namespace particlemesh
