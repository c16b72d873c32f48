#include "surface/neighbor_lists.h"

#include <algorithm>
#include <cmath>
#include <optional>
#include <string>
#include <utility>

#include "core/parallel.h"
#include "core/select_within.h"
#include "spatial/neighbor_cell_walk.h"

namespace PM_NAMESPACE::detail {

namespace {

/// `point` (an input index) has `count` neighbours, over the limit; the most any point has is
/// `most`: the limit that would let the call through (the command-line tool reads it from
/// "the neighbour limit to at least N" for its --max-neighbors advice).
[[noreturn]] void too_many(size_t point, size_t count, size_t most, size_t max_neighbors, const std::string& within) {
  throw Error(Status::LimitExceeded,
              "point " + std::to_string(point) + " has " + std::to_string(count) + " neighbours within " + within +
                  ", more than the limit of " + std::to_string(max_neighbors) +
                  ": the points are packed far denser than the spacing (raise the neighbour limit to at least " +
                  std::to_string(most) + ", or give a smaller spacing / max edge factor)");
}

/// d[i] = squared_distance(q_i, p) for the m points q by coordinate, the same bits (a loop
/// the compiler vectorises).
void squared_distances(const double* x, const double* y, const double* z, size_t m, const Vec3& p,
                       double* __restrict d) {
  for (size_t i = 0; i < m; ++i) {
    const double dx = x[i] - p.x, dy = y[i] - p.y, dz = z[i] - p.z;
    d[i] = dx * dx + dy * dy + dz * dz;
  }
}

}  // namespace

NeighborLists build_neighbor_lists(const NeighborGrid& grid, const std::vector<uint32_t>& rep,
                                   double radius, size_t max_neighbors,
                                   ProgressTracker& tracker) {
  const size_t n = grid.point_count();
  const double r2 = radius * radius;
  // Chunks of cells; each fills its own buffer, and buffers are joined in chunk order (so
  // the lists do not depend on the chunking). At least ~16 chunks: a 7k-point preview has
  // ~2k cells, which one chunk of 2048 left to a single thread.
  const size_t cells = grid.cell_count();
  const size_t chunk_cells = std::clamp<size_t>(cells / 16, 64, 2048);
  const size_t chunks = (cells + chunk_cells - 1) / chunk_cells;
  std::vector<std::vector<uint32_t>> chunk_index(chunks);
  std::vector<uint32_t> count(n, 0);
  size_t cap_point = SIZE_MAX;  // lowest input index over the cap (written under no race:
  std::vector<uint32_t> chunk_over(chunks, UINT32_MAX);  // per chunk, joined below)

  // Without duplicates (most clouds) every point is its own representative: the loop then
  // skips the check per candidate.
  bool duplicates = false;
  for (size_t s = 0; s < n && !duplicates; ++s) duplicates = rep[s] != s;
  const auto fill = [&]<bool kDuplicates>(size_t kb, size_t ke) {
    for (size_t k = kb; k < ke; ++k) {
      if (tracker.cancelled()) return;
      auto& out = chunk_index[k];
      const size_t cb = k * chunk_cells, ce = std::min(cells, cb + chunk_cells);
      out.reserve((grid.cell_begin(uint32_t(std::min(ce, cells - 1))) - grid.cell_begin(uint32_t(cb)) + 1) * 16);
      uint32_t around[27];
      NeighborCellWalk walk(grid);
      // The 27 cells' points (representatives only) by coordinate, and one point's squared
      // distances to them: every point of the cell measures them all in a loop the compiler
      // turns into vector instructions, then keeps those within the radius, in order.
      std::vector<double> bx, by, bz, bd;
      std::vector<uint32_t> bt, kept_t;
      for (size_t c = cb; c < ce; ++c) {
        const int na = walk.around(uint32_t(c), around);
        // (Written by index into room for all: push_back's possible reallocation kept the
        // copy from running as a plain loop.)
        size_t m = 0;
        for (int a = 0; a < na; ++a) m += grid.cell_end(around[a]) - grid.cell_begin(around[a]);
        if (bt.size() < m)
          bx.resize(m), by.resize(m), bz.resize(m), bt.resize(m), bd.resize(m), kept_t.resize(m + 16);
        m = 0;
        for (int a = 0; a < na; ++a)
          for (uint32_t t = grid.cell_begin(around[a]); t < grid.cell_end(around[a]); ++t) {
            if (kDuplicates && rep[t] != t) continue;
            const Vec3& q = grid.sorted_point(t);
            bx[m] = q.x, by[m] = q.y, bz[m] = q.z, bt[m] = t;
            ++m;
          }
        for (uint32_t s = grid.cell_begin(uint32_t(c)); s < grid.cell_end(uint32_t(c)); ++s) {
          if (kDuplicates && rep[s] != s) continue;
          const Vec3 p = grid.sorted_point(s);
          squared_distances(bx.data(), by.data(), bz.data(), m, p, bd.data());
          const size_t kept = select_within(bd.data(), m, -INFINITY, r2, bt.data(), s, kept_t.data());
          out.insert(out.end(), kept_t.begin(), kept_t.begin() + ptrdiff_t(kept));
          count[s] = uint32_t(kept);
          if (count[s] > max_neighbors) chunk_over[k] = std::min(chunk_over[k], grid.original_index(s));
        }
        tracker.tick(grid.cell_end(uint32_t(c)) - grid.cell_begin(uint32_t(c)));
      }
    }
  };
  if (duplicates)
    parallel_blocks(chunks, 1, [&](size_t kb, size_t ke) { fill.template operator()<true>(kb, ke); });
  else
    parallel_blocks(chunks, 1, [&](size_t kb, size_t ke) { fill.template operator()<false>(kb, ke); });
  tracker.check();
  for (size_t k = 0; k < chunks; ++k)
    if (chunk_over[k] != UINT32_MAX) cap_point = std::min<size_t>(cap_point, chunk_over[k]);
  if (cap_point != SIZE_MAX) {
    size_t here = 0;
    for (size_t s = 0; s < n; ++s)
      if (grid.original_index(uint32_t(s)) == cap_point) here = count[s];
    too_many(cap_point, here, *std::max_element(count.begin(), count.end()), max_neighbors, std::to_string(radius));
  }

  NeighborLists lists;
  lists.offset.resize(n + 1);
  lists.offset[0] = 0;
  for (size_t s = 0; s < n; ++s) {
    lists.offset[s + 1] = lists.offset[s] + count[s];
    if (count[s] > lists.max_count) {
      lists.max_count = count[s];
      lists.max_point = uint32_t(s);
    }
  }
  lists.index.resize(lists.offset[n]);
  parallel_blocks(chunks, 1, [&](size_t kb, size_t ke) {
    for (size_t k = kb; k < ke; ++k) {
      const size_t cb = k * chunk_cells;
      const uint64_t dst = lists.offset[grid.cell_begin(uint32_t(cb))];
      std::copy(chunk_index[k].begin(), chunk_index[k].end(), lists.index.begin() + dst);
      std::vector<uint32_t>().swap(chunk_index[k]);
    }
  });
  return lists;
}

namespace {

/// The longest radius around point s that holds at most `most` of the others (distinct
/// representatives) now within radius[s]: the (most)-th nearest's distance, or, where the
/// (most + 1)-th lies at the same distance, the last shorter one (0 if none is shorter).
double crowded_radius(const NeighborGrid& grid, const std::vector<uint32_t>& rep, const std::vector<double>& radius,
                      uint32_t s, size_t most) {
  std::vector<double> d2;
  grid.for_each_within(grid.sorted_point(s), radius[s], [&](uint32_t t, double d) {
    if (t != s && rep[t] == t) d2.push_back(d);
  });
  std::sort(d2.begin(), d2.end());
  const double over = d2[most];  // the first that must be left out
  const auto last = std::lower_bound(d2.begin(), d2.end(), over);
  if (last == d2.begin()) return 0.0;
  const double keep = *(last - 1);
  double r = std::sqrt(keep);
  // for_each_within takes d2 <= r * r: r * r must stay below `over` after rounding.
  while (r > 0 && r * r >= over) r = std::nextafter(r, 0.0);
  return r;
}

}  // namespace

namespace {

/// A cell holding more representatives than this is crowded: a cluster far denser than the
/// median radius the cells are sized by (a small object scanned finely beside a large one),
/// whose points would each scan all of it.
constexpr size_t kCrowdedCell = 128;

/// The representatives of the crowded cells and of the cells around them (every point within
/// one cell of a crowded cell's points) on a finer grid, of cells as wide as the median radius
/// of the crowded cells' points: a crowded point whose radius is at most a cell here finds
/// there every point it would find here. `finer` is empty where no cell is crowded, or a finer
/// grid would not be finer.
struct CrowdedCells {
  std::optional<NeighborGrid> finer;
  std::vector<uint32_t> to_here;  ///< per sorted point of `finer`: its sorted index in the grid
  std::vector<uint8_t> crowded;   ///< per sorted point of the grid: 1 in a crowded cell
};

CrowdedCells crowded_part(const NeighborGrid& grid, const std::vector<uint32_t>& rep, const std::vector<double>& radius) {
  CrowdedCells out;
  const auto cells = uint32_t(grid.cell_count());
  const std::vector<uint8_t> take =  // 2: crowded, 1: next to one
      crowded_cells(grid, kCrowdedCell, [&](uint32_t s) { return rep[s] == s; });
  if (take.empty()) return out;
  std::vector<double> radii;
  for (uint32_t c = 0; c < cells; ++c)
    if (take[c] == 2)
      for (uint32_t s = grid.cell_begin(c); s < grid.cell_end(c); ++s)
        if (rep[s] == s) radii.push_back(radius[s]);
  std::nth_element(radii.begin(), radii.begin() + ptrdiff_t(radii.size() / 2), radii.end());
  const double cell = radii[radii.size() / 2];
  if (!(cell > 0 && cell < 0.5 * grid.cell_size())) return out;
  std::vector<Vec3> points;
  std::vector<uint32_t> from;
  out.crowded.assign(grid.point_count(), 0);
  for (uint32_t c = 0; c < cells; ++c) {
    if (!take[c]) continue;
    for (uint32_t s = grid.cell_begin(c); s < grid.cell_end(c); ++s) {
      out.crowded[s] = take[c] == 2;
      if (rep[s] != s) continue;
      points.push_back(grid.sorted_point(s));
      from.push_back(s);
    }
  }
  try {
    out.finer.emplace(points.data(), points.size(), cell);
  } catch (const Error&) {
    out.crowded.clear();  // a grid too fine for its key: searched on the grid
    return out;
  }
  out.to_here.resize(points.size());
  for (uint32_t t = 0; t < points.size(); ++t) out.to_here[t] = from[out.finer->original_index(t)];
  return out;
}

}  // namespace

NeighborLists build_neighbor_lists(const NeighborGrid& grid, const std::vector<uint32_t>& rep,
                                   std::vector<double>& radius, size_t max_neighbors, bool shorten,
                                   ProgressTracker& tracker) {
  const size_t n = grid.point_count();
  // Per fixed chunk of points: each point's own neighbours (within its radius, ascending), and
  // the pairs (t, s) where s reaches t but t's smaller radius does not reach s.
  const size_t chunk = 2048, chunks = (n + chunk - 1) / chunk;
  std::vector<std::vector<uint32_t>> own(chunks);
  std::vector<std::vector<uint64_t>> back(chunks);
  std::vector<uint32_t> own_count(n, 0);
  const CrowdedCells crowded = crowded_part(grid, rep, radius);
  parallel_blocks(chunks, 1, [&](size_t kb, size_t ke) {
    std::vector<std::pair<uint32_t, double>> found;  // a crowded point's, from the finer grid
    // The representatives in the cells of one query box (box_lo..box_hi) by coordinate, and
    // a point's squared distances to them; the positions within its radius.
    std::vector<double> bx, by, bz, bd;
    std::vector<uint32_t> bt, within;
    NeighborGrid::CellCoord box_lo{}, box_hi{};
    bool box_known = false;
    for (size_t k = kb; k < ke; ++k) {
      if (tracker.cancelled()) return;
      for (size_t s = k * chunk; s < std::min(n, (k + 1) * chunk); ++s) {
        if (rep[s] != s) continue;
        const size_t before = own[k].size();
        const double rs = radius[s];
        const auto take = [&](uint32_t t, double d2) {
          if (t == s || rep[t] != t) return;
          own[k].push_back(t);
          if (d2 > radius[t] * radius[t]) back[k].push_back((uint64_t(t) << 32) | s);
        };
        if (crowded.finer && crowded.crowded[s] && rs <= grid.cell_size()) {
          // The same points and distances, in the grid's order.
          found.clear();
          crowded.finer->for_each_within(grid.sorted_point(uint32_t(s)), rs,
                                         [&](uint32_t t, double d2) { found.push_back({crowded.to_here[t], d2}); });
          std::sort(found.begin(), found.end());
          for (const auto& [t, d2] : found) take(t, d2);
        } else {
          // As grid.for_each_within(p, rs, take), with the box's points gathered once for a run
          // of points with the same box (most points of a cell: a box is whole cells), each
          // point's distances measured in one vector loop and filtered sixteen at a time
          // (select_within). The same points, distances and order: the box's cells in
          // increasing order, each cell's points in order, the distance squared_distance(q, p).
          // (Point by point, a hash look-up per cell and a branch per point in it were most of
          // an uneven sampling's neighbour search.)
          const Vec3 p = grid.sorted_point(uint32_t(s));
          const Vec3 rv{rs, rs, rs};
          const NeighborGrid::CellCoord lo = grid.coord_of(p - rv), hi = grid.coord_of(p + rv);
          if (!box_known || lo != box_lo || hi != box_hi) {
            box_lo = lo, box_hi = hi, box_known = true;
            bx.clear(), by.clear(), bz.clear(), bt.clear();
            grid.for_each_cell_in(lo, hi, [&](uint32_t c) {
              for (uint32_t t = grid.cell_begin(c); t < grid.cell_end(c); ++t) {
                if (rep[t] != t) continue;  // (take() skips them)
                const Vec3& q = grid.sorted_point(t);
                bx.push_back(q.x), by.push_back(q.y), bz.push_back(q.z), bt.push_back(t);
              }
            });
            bd.resize(bt.size());
            within.resize(bt.size() + 16);
          }
          const size_t m = bt.size();
          squared_distances(bx.data(), by.data(), bz.data(), m, p, bd.data());
          const size_t count = select_within(bd.data(), m, -INFINITY, rs * rs, nullptr, 0, within.data());
          for (size_t j = 0; j < count; ++j) take(bt[within[j]], bd[within[j]]);
        }
        own_count[s] = uint32_t(own[k].size() - before);
      }
      tracker.tick(std::min(n, (k + 1) * chunk) - k * chunk);
    }
  });
  tracker.check();
  if (shorten) {
    // Radii that hold more than max_neighbors shortened; the lists then built again (only a
    // cloud with such points pays the second pass). A point's own count never grows, so
    // once is enough.
    std::vector<uint32_t> crowded;
    for (size_t s = 0; s < n; ++s)
      if (own_count[s] > max_neighbors) crowded.push_back(uint32_t(s));
    if (!crowded.empty()) {
      std::vector<double> shorter(crowded.size());
      parallel_blocks(crowded.size(), 16, [&](size_t b, size_t e) {
        for (size_t i = b; i < e; ++i) shorter[i] = crowded_radius(grid, rep, radius, crowded[i], max_neighbors);
      });
      for (size_t i = 0; i < crowded.size(); ++i) radius[crowded[i]] = shorter[i];
      NeighborLists again = build_neighbor_lists(grid, rep, radius, max_neighbors, true, tracker);
      again.shortened = crowded.size();
      return again;
    }
  }
  // The pairs by their first point (stable: for each t its s ascend, chunks being in order).
  std::vector<uint64_t> pairs;
  for (auto& b : back) {
    pairs.insert(pairs.end(), b.begin(), b.end());
    std::vector<uint64_t>().swap(b);
  }
  std::vector<size_t> back_start(n + 1, 0);
  for (uint64_t p : pairs) ++back_start[(p >> 32) + 1];
  for (size_t s = 0; s < n; ++s) back_start[s + 1] += back_start[s];
  std::vector<uint64_t> by_point(pairs.size());
  {
    std::vector<size_t> at(back_start.begin(), back_start.end() - 1);
    for (uint64_t p : pairs) by_point[at[p >> 32]++] = p;
  }
  std::vector<uint64_t>().swap(pairs);
  NeighborLists lists;
  lists.offset.assign(n + 1, 0);
  for (size_t s = 0; s < n; ++s) {
    const size_t count = own_count[s] + (back_start[s + 1] - back_start[s]);
    lists.offset[s + 1] = lists.offset[s] + count;
    if (count > lists.max_count) {
      lists.max_count = count;
      lists.max_point = uint32_t(s);
    }
  }
  if (!shorten && lists.max_count > max_neighbors) {
    size_t lowest = SIZE_MAX, count = 0;
    for (size_t s = 0; s < n; ++s) {
      const size_t here = lists.offset[s + 1] - lists.offset[s];
      if (here > max_neighbors && grid.original_index(uint32_t(s)) < lowest) {
        lowest = grid.original_index(uint32_t(s));
        count = here;
      }
    }
    too_many(lowest, count, lists.max_count, max_neighbors, "its local radius");
  }
  lists.index.resize(lists.offset[n]);
  parallel_blocks(chunks, 1, [&](size_t kb, size_t ke) {
    for (size_t k = kb; k < ke; ++k) {
      const uint32_t* mine = own[k].data();
      for (size_t s = k * chunk; s < std::min(n, (k + 1) * chunk); ++s) {
        uint32_t* out = lists.index.data() + lists.offset[s];
        const uint32_t* a = mine;
        const uint32_t* a_end = mine + own_count[s];
        const uint64_t* b = by_point.data() + back_start[s];
        const uint64_t* b_end = by_point.data() + back_start[s + 1];
        while (a != a_end || b != b_end) {
          if (b == b_end || (a != a_end && *a < uint32_t(*b))) *out++ = *a++;
          else *out++ = uint32_t(*b++);
        }
        mine = a_end;
      }
      std::vector<uint32_t>().swap(own[k]);
    }
  });
  return lists;
}

}  // namespace particlemesh::detail
