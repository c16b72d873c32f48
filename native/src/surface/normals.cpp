#include "particlemesh/surface/normals.h"

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <cstring>
#include <numeric>
#include <optional>

#include <Eigen/Eigenvalues>

#include "core/disjoint_sets.h"
#include "core/first_touch.h"
#include "core/parallel.h"
#include "particlemesh/core/error.h"
#include "spatial/grid_search.h"
#include "surface/normals_impl.h"
#include "surface/raw_triangulation.h"
#include "spatial/spacing_impl.h"

namespace PM_NAMESPACE {
namespace detail {

namespace {
// Above this ratio of the two smallest variances a neighbourhood is too thick for one plane.
constexpr double kMaxFlatness = 0.2;
// Two planes at a thick point whose normals are more than ~37 degrees apart make a crease.
constexpr double kCreaseCos = 0.8;
// A face of a crease reaches the other plane: its nearest point off that plane lies within
// this fraction of the radius of it. A sheet across a gap (1.2 spacings or more, 0.6 of the
// radius) does not.
constexpr double kCreaseReach = 0.5;
// A plane's outliers lie on one side of it when those on the other side weigh at most this
// fraction of them (see the choice of a thick point's plane below).
constexpr double kOneSided = 0.05;
// Which pairs judge whether reference normals are a consistent orientation: both points
// decided by a reference at least this far out of their tangent plane, their plane-fit
// directions this close to parallel (one sheet, one plane).
constexpr double kClearReference = 0.5;
constexpr double kSamePlaneCos = 0.9;
// Above this fraction of such pairs facing opposite ways (the two sides of a part thinner
// than the spacing aside: neighbours in one plane that rightly do), reference normals are
// not a consistent orientation and only vote per piece. Measured (bench/RESULTS.md, "Which
// way the surface faces"): 39 models' own normals at most 1.05 %; PCL's estimated normals of
// a range scan (bun0.pcd) 2.6 %, of colored_cloud.pcd 12 %.
constexpr double kMaxReferenceDisagreement = 0.015;
// Normals turned toward a sensor's viewpoint (PCL's NormalEstimation, the origin by default)
// face inward on the far side of a closed object seen from outside: their sign flips along
// its silhouette, one chain of disagreeing neighbour pairs around it, 4.5-6.6 sqrt(points)
// long on spheres of 5k-500k points. The longest chain on 39 models' own normals was 1.5
// sqrt(points) (thin parts' rims). Above this many sqrt(points), the references are
// inconsistent.
constexpr double kMaxFlipChain = 2.5;
// Two neighbours facing opposite ways are a thin part's two sides when each lies at least
// this fraction of their distance behind the other's normal.
constexpr double kTwoSidesOffset = 0.02;
}  // namespace

namespace {

/// The offsets from p to its neighbours within the radius, p's own (zero) first.
void gather_near(const NeighborGrid& grid, const NeighborLists& lists, uint32_t s, double r2, std::vector<Vec3>& near) {
  const Vec3 p = grid.sorted_point(s);
  near.clear();
  near.push_back(Vec3{});
  for (const uint32_t* q = lists.begin(s); q != lists.end(s); ++q) {
    const Vec3 d = grid.sorted_point(*q) - p;
    if (squared_norm(d) <= r2) near.push_back(d);
  }
}

/// The first and second moments of a set of offsets: their count, sum and sum of products.
struct Moments {
  int count = 0;
  double x = 0, y = 0, z = 0, xx = 0, xy = 0, xz = 0, yy = 0, yz = 0, zz = 0;
  void add(const Vec3& d) { add_if(d, true); }
  /// add(d) where `in`, else +0.0 added to every sum: the same sums (see pca_normals_sorted).
  void add_if(const Vec3& d, bool in) {
    const Vec3 e = in ? d : Vec3{};
    count += in;
    x += e.x;
    y += e.y;
    z += e.z;
    xx += e.x * e.x;
    xy += e.x * e.y;
    xz += e.x * e.z;
    yy += e.y * e.y;
    yz += e.y * e.z;
    zz += e.z * e.z;
  }
};

/// PCA of the offsets: the normal, and the ratio of the two smallest variances (small for
/// points that lie close to one plane). From the moments, in one pass over the neighbours (a
/// list of the offsets and a second pass for the covariance cost a quarter of the stage);
/// the offsets are from the point itself, so the mean is small and the difference exact
/// enough.
Vec3 pca_normal(const Moments& m, double* flatness) {
  const double c = m.count;
  Eigen::Matrix3d cov;
  cov << m.xx - m.x * m.x / c, m.xy - m.x * m.y / c, m.xz - m.x * m.z / c,  //
      m.xy - m.x * m.y / c, m.yy - m.y * m.y / c, m.yz - m.y * m.z / c,   //
      m.xz - m.x * m.z / c, m.yz - m.y * m.z / c, m.zz - m.z * m.z / c;
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig;
  eig.computeDirect(cov);
  const Eigen::Vector3d ev = eig.eigenvalues();  // ascending
  if (flatness) *flatness = ev(1) > 0 ? ev(0) / ev(1) : 1.0;
  const Eigen::Vector3d v = eig.eigenvectors().col(0);
  return normalized(Vec3{v.x(), v.y(), v.z()});
}

/// A plane fitted to the offsets within `band` of the plane through the point with normal n.
struct Plane {
  Vec3 normal, centroid;
  int count = 0;
};
Plane fit_plane(const std::vector<Vec3>& near, const Vec3& n, double band) {
  Moments m;
  for (const Vec3& d : near)
    if (std::abs(dot(d, n)) <= band) m.add(d);
  Plane p;
  p.count = m.count;
  if (m.count < 3) return p;
  p.normal = pca_normal(m, nullptr);
  p.centroid = Vec3{m.x, m.y, m.z} * (1.0 / m.count);
  return p;
}

/// The normal of a point on two fitted planes A and B (the offsets `near` are from the point),
/// or nullopt when they make no crease there. A crease ends each face at the point: each
/// face's own points (off the other plane) lie on one side of the other plane, and its nearest
/// reaches within `reach` of it. Facing sheets and the plane of the triangles bridging them
/// are no crease (the point's own sheet goes on past that plane on both sides), nor is a sheet
/// that ends beside another across a gap (the other sheet keeps the gap's distance).
std::optional<Vec3> crease_normal(const std::vector<Vec3>& near, const Plane& A, const Plane& B, double band,
                                  double reach) {
  struct Face {
    Vec3 sum;  // of its own points' offsets
    int side[2] = {0, 0};
    double nearest = INFINITY;  // own point closest to the other plane
    void add(const Vec3& d, double h) {
      sum = sum + d;
      ++side[h > 0];
      nearest = std::min(nearest, std::abs(h));
    }
    bool ends_at_crease(double reach) const {
      const int all = side[0] + side[1];
      return all >= 2 && std::min(side[0], side[1]) * 10 <= all && nearest <= reach;
    }
  } fa, fb;
  for (const Vec3& d : near) {
    const double ha = dot(d, A.normal), hb = dot(d, B.normal);
    const bool in_a = std::abs(ha) <= band, in_b = std::abs(hb) <= band;
    if (in_a && !in_b) fa.add(d, hb);
    if (in_b && !in_a) fb.add(d, ha);
  }
  if (!fa.ends_at_crease(reach) || !fb.ends_at_crease(reach)) return std::nullopt;
  // The bisector is within 90 degrees of both faces' normals, so the triangles of both faces
  // pass the corner test there. Each plane's normal is first turned away from the other
  // face's points, so that the two agree in sense (both out of a convex crease).
  const Vec3 na = dot(A.normal, fb.sum) > 0 ? -A.normal : A.normal;
  const Vec3 nb = dot(B.normal, fa.sum) > 0 ? -B.normal : B.normal;
  const Vec3 mid = na + nb;
  if (!(squared_norm(mid) > 1e-6)) return std::nullopt;
  return normalized(mid);
}

}  // namespace

std::vector<Vec3> pca_normals_sorted(const NeighborGrid& grid, const std::vector<uint32_t>& rep,
                                     const NeighborLists& lists, const std::vector<double>& radius,
                                     ProgressTracker& tracker, const std::vector<Triangle>* triangles) {
  const size_t n = grid.point_count();
  std::vector<Vec3> normals;
  resize_touched(normals, n);  // (zero where no plane is found)
  // 1. Every point's plane. Points that already lie close to one plane keep it (noise and the
  //    steps of a depth scan or a lattice do not call for more); a thick neighbourhood may be
  //    two sheets, and is looked at again below.
  std::vector<uint8_t> thick(n, 0);
  parallel_blocks(n, 2048, [&](size_t b, size_t e) {
    if (tracker.cancelled()) return;
    for (size_t s = b; s < e; ++s) {
      if (rep[s] != s) continue;
      const double r2 = radius[s] * radius[s];
      const Vec3 p = grid.sorted_point(uint32_t(s));
      Moments m;
      m.add(Vec3{});  // the point itself
      for (const uint32_t* q = lists.begin(uint32_t(s)); q != lists.end(uint32_t(s)); ++q) {
        const Vec3 d = grid.sorted_point(*q) - p;
        // Without a branch (about a quarter of a list lies beyond the radius, in no pattern
        // a branch predictor learns): a neighbour beyond adds +0.0 to every sum, which
        // changes none of them (a sum that starts at +0.0 is never -0.0).
        const bool in = squared_norm(d) <= r2;
        m.add_if(d, in);
      }
      if (m.count < 3) continue;  // too few neighbours for a plane: unknown (0,0,0)
      double flatness = 0;
      normals[s] = pca_normal(m, &flatness);
      thick[s] = triangles != nullptr && flatness > kMaxFlatness;
    }
    tracker.tick(e - b);
  });
  tracker.check();
  std::vector<uint32_t> redo;
  for (uint32_t s = 0; s < n; ++s)
    if (thick[s]) redo.push_back(s);
  if (!redo.empty()) {
    // 2. At a thick point, the raw triangles there propose planes; the one most of the
    //    neighbours lie close to wins. Their triangles, in triangle order, for these points only.
    std::vector<uint32_t> slot(n, UINT32_MAX);
    for (uint32_t i = 0; i < redo.size(); ++i) slot[redo[i]] = i;
    std::vector<uint32_t> tri_off(redo.size() + 1, 0), tri_ids;
    for (const Triangle& t : *triangles)
      for (uint32_t v : t)
        if (slot[v] != UINT32_MAX) ++tri_off[slot[v] + 1];
    std::partial_sum(tri_off.begin(), tri_off.end(), tri_off.begin());
    tri_ids.resize(tri_off.back());
    {
      std::vector<uint32_t> fill(tri_off.begin(), tri_off.end() - 1);
      for (uint32_t t = 0; t < triangles->size(); ++t)
        for (uint32_t v : (*triangles)[t])
          if (slot[v] != UINT32_MAX) tri_ids[fill[slot[v]]++] = t;
    }
    tracker.check();
    parallel_blocks(redo.size(), 256, [&](size_t b, size_t e) {
      if (tracker.cancelled()) return;
      std::vector<Vec3> near;
      struct Candidate {
        Vec3 normal;
        double score;  // inliers weighted by closeness
        size_t count;  // inliers
        // The outliers on either side of the plane, weighted as the inliers: one side nearly
        // empty where the plane is the surface's own (see one_sided).
        double above, below;
      };
      std::vector<Candidate> tried;
      for (size_t i = b; i < e; ++i) {
        const uint32_t s = redo[i];
        const double r2 = radius[s] * radius[s];
        const double band = 0.25 * radius[s];
        const double crease_band = 0.75 * band;
        gather_near(grid, lists, s, r2, near);
        // Inliers count more the closer they are: next to the point its own sheet dominates
        // even where another sheet ends nearby (the free ends of a folded sheet).
        tried.clear();
        for (uint32_t j = tri_off[i]; j < tri_off[i + 1]; ++j) {
          const Triangle& t = (*triangles)[tri_ids[j]];
          const Vec3 a = grid.sorted_point(t[0]);
          const Vec3 tn = normalized(cross(grid.sorted_point(t[1]) - a, grid.sorted_point(t[2]) - a));
          // Planes within ~8 degrees of one already scored would score about the same.
          bool seen = false;
          for (const Candidate& x : tried) seen |= std::abs(dot(x.normal, tn)) > 0.99;
          if (seen) continue;
          double score = 0, above = 0, below = 0;
          size_t count = 0;
          for (const Vec3& d : near) {
            const double w = 1.0 - squared_norm(d) / r2;  // ~exp(-4 d^2 / r^2), 0 at the radius
            const double h = dot(d, tn), weight = (w * w) * (w * w);
            if (std::abs(h) <= band) {
              score += weight;
              ++count;
            } else {
              (h > 0 ? above : below) += weight;
            }
          }
          tried.push_back({tn, score, count, above, below});
        }
        const auto one_sided = [](const Candidate& c) {
          return std::min(c.above, c.below) <= kOneSided * (c.above + c.below);
        };
        const auto best_plane = [&](const Vec3* other, bool sided) {
          int best = -1;
          for (int c = 0; c < int(tried.size()); ++c) {
            if (other && (tried[c].count < 3 || std::abs(dot(tried[c].normal, *other)) > kCreaseCos)) continue;
            if (sided && !one_sided(tried[c])) continue;
            if (best < 0 || tried[c].score > tried[best].score) best = c;
          }
          return best;
        };
        // A surface lies on one side of its own plane at the sampling's scale: the other sheet
        // of a thin part, the other face of a crease, the rest of a curved surface all lie on
        // the side it bends to. A plane with neighbours well out on both sides cuts across the
        // surface: around a thin part sampled in rings (a limb of a quad mesh, a turned part)
        // one ring lies in one plane, outscores the surface's own plane and would turn the
        // normal along the part, so that no triangle along it passes co-normality and the
        // part falls apart into capped pieces. Such a best plane gives way to the best
        // one-sided plane when that one also lies nearer the plain PCA normal of the
        // neighbourhood (the average, which a plane across the part is far from; at a saddle,
        // where the surface's own plane is two-sided too, it keeps it).
        const Vec3 pca = normals[s];  // step 1's, not replaced yet
        int first = best_plane(nullptr, false);
        if (first >= 0 && !one_sided(tried[first])) {
          const int sided = best_plane(nullptr, true);
          if (sided >= 0 && std::abs(dot(tried[sided].normal, pca)) > std::abs(dot(tried[first].normal, pca)))
            first = sided;
        }
        if (first < 0 || !(tried[first].score > 0) || tried[first].count < 3) continue;
        const Plane A = fit_plane(near, tried[first].normal, band);
        normals[s] = A.normal;
        // A crease: a second plane, at a clear angle to the first, through the point too.
        const int second = best_plane(&A.normal, false);
        if (second < 0) continue;
        const Plane B = fit_plane(near, tried[second].normal, band);
        if (B.count < 3 || std::abs(dot(A.normal, B.normal)) > kCreaseCos) continue;
        // The point's distance to each fitted plane (it is the origin of the offsets).
        const double da = std::abs(dot(A.centroid, A.normal)), db = std::abs(dot(B.centroid, B.normal));
        if (da > crease_band || db > crease_band) {
          if (db < da) normals[s] = B.normal;  // the point lies on the second face, not the first
          continue;
        }
        if (const auto n = crease_normal(near, A, B, band, kCreaseReach * radius[s])) normals[s] = *n;
      }
    });
    tracker.check();
  }
  for (size_t s = 0; s < n; ++s)
    if (rep[s] != s) normals[s] = normals[rep[s]];
  return normals;
}

namespace {
/// The most points in one chain of pairs: pairs that share a point, or whose points are
/// neighbours, are one chain. Serial: the pairs are few (a silhouette's, not a cloud's).
size_t longest_chain(const std::vector<std::array<uint32_t, 2>>& pairs, const NeighborLists& lists) {
  std::vector<uint32_t> at;
  for (const auto& pair : pairs) at.insert(at.end(), pair.begin(), pair.end());
  std::sort(at.begin(), at.end());
  at.erase(std::unique(at.begin(), at.end()), at.end());
  const auto index = [&](uint32_t s) { return uint32_t(std::lower_bound(at.begin(), at.end(), s) - at.begin()); };
  DisjointSets sets(at.size());
  for (const auto& pair : pairs) sets.unite(index(pair[0]), index(pair[1]));
  for (uint32_t i = 0; i < at.size(); ++i)
    for (const uint32_t* q = lists.begin(at[i]); q != lists.end(at[i]); ++q) {
      const uint32_t j = index(*q);
      if (j < at.size() && at[j] == *q) sets.unite(i, j);
    }
  std::vector<uint32_t> size(at.size(), 0);
  size_t longest = 0;
  for (uint32_t i = 0; i < at.size(); ++i) longest = std::max<size_t>(longest, ++size[sets.find(i)]);
  return longest;
}
}  // namespace

bool orient_normals_by_reference(const NeighborGrid& grid, const std::vector<uint32_t>& rep,
                                 const NeighborLists& lists, const std::vector<double>& radius,
                                 std::vector<Vec3>& normals, const std::vector<Vec3>& reference,
                                 ProgressTracker& tracker) {
  const size_t n = grid.point_count();
  const auto r2 = [&](uint32_t s, uint32_t t) {
    const double r = pair_limit(radius[s], radius[t]);
    return r * r;
  };
  // 0 = undecided, 1 = decided, 2 = decided by a clear reference (|cos| >= kClearReference).
  // Where the reference clearly says which way a point faces it decides; elsewhere
  // (reference nearly in the tangent plane, or missing) the neighbours of the same sheet that
  // are decided vote, round after round.
  // Each pass is parallel over fixed blocks of points; what a pass decides is applied after
  // it, and the counts are integers: the same whatever the thread count.
  constexpr size_t kGrain = 8192;
  std::vector<uint8_t> decided(n, 0);
  std::vector<uint8_t> undecided(n, 0);  // the first pass's open points
  parallel_blocks(n, kGrain, [&](size_t b, size_t e) {
    if (tracker.cancelled()) return;
    for (size_t s = b; s < e; ++s) {
      if (rep[s] != s || !(squared_norm(normals[s]) > 0)) continue;
      const Vec3 r = reference[s];
      const double len = norm(r);
      const double c = len > 0 ? dot(normals[s], r) / len : 0.0;
      if (std::abs(c) >= 0.3) {
        if (c < 0) normals[s] = -normals[s];
        decided[s] = std::abs(c) >= kClearReference ? 2 : 1;
      } else {
        undecided[s] = 1;
      }
    }
  });
  tracker.check();
  std::vector<uint32_t> open;
  for (size_t s = 0; s < n; ++s)
    if (undecided[s]) open.push_back(uint32_t(s));
  std::vector<uint8_t>().swap(undecided);
  std::vector<double> votes;
  for (int round = 0; round < 64 && !open.empty(); ++round) {
    tracker.check();
    votes.assign(open.size(), 0.0);
    parallel_blocks(open.size(), 1024, [&](size_t b, size_t e) {
      if (tracker.cancelled()) return;
      for (size_t i = b; i < e; ++i) {
        const uint32_t s = open[i];
        double vote = 0;
        const Vec3 p = grid.sorted_point(s);
        for (const uint32_t* q = lists.begin(s); q != lists.end(s); ++q) {
          if (!decided[*q]) continue;
          const Vec3 d = grid.sorted_point(*q) - p;
          if (squared_norm(d) > r2(s, *q)) continue;
          // Same-sheet neighbours (the edge in both tangent planes) count, gap-crossing ones
          // count reversed, like the spanning tree's signed edges.
          const double slope = (std::abs(dot(d, normals[s])) + std::abs(dot(d, normals[*q]))) / (2 * norm(d));
          const double agree = dot(normals[s], normals[*q]);
          vote += slope > 0.5 ? -agree : agree;
        }
        votes[i] = vote;
      }
    });
    tracker.check();
    std::vector<uint32_t> still;
    bool any = false;
    for (size_t i = 0; i < open.size(); ++i) {
      const uint32_t s = open[i];
      if (votes[i] == 0) {
        still.push_back(s);
        continue;
      }
      if (votes[i] < 0) normals[s] = -normals[s];
      decided[s] = 1;
      any = true;
    }
    if (!any) break;
    open.swap(still);
  }
  // Are the references consistent? Neighbours of one sheet in one plane (the edge lies in
  // both tangent planes, the planes nearly parallel), both clearly decided by their
  // references, should agree, but for the two sides of a part thinner than the spacing: each
  // lies behind the other's normal (or, normals facing inward, in front of it). Normals
  // turned toward a scanner's viewpoint on a closed object, for instance, face inward on its
  // far side: they disagree along the silhouette, one long chain of flips.
  const size_t blocks = (n + kGrain - 1) / kGrain;
  struct Counts {
    size_t pairs = 0, clear = 0;
    std::vector<std::array<uint32_t, 2>> flips;  // disagreeing pairs that are not a thin part's two sides
  };
  std::vector<Counts> counts(blocks);
  parallel_blocks(blocks, 1, [&](size_t kb, size_t ke) {
    for (size_t k = kb; k < ke; ++k) {
      if (tracker.cancelled()) return;
      Counts& c = counts[k];
      for (size_t s = k * kGrain; s < std::min(n, (k + 1) * kGrain); ++s) {
        if (rep[s] != s || decided[s] != 2) continue;
        ++c.clear;
        const Vec3 p = grid.sorted_point(uint32_t(s));
        for (const uint32_t* q = lists.begin(uint32_t(s)); q != lists.end(uint32_t(s)); ++q) {
          if (*q <= s || decided[*q] != 2) continue;
          const Vec3 d = grid.sorted_point(*q) - p;
          if (squared_norm(d) > r2(uint32_t(s), *q)) continue;
          const double a = dot(d, normals[s]), b = -dot(d, normals[*q]), length = norm(d);
          const double slope = (std::abs(a) + std::abs(b)) / (2 * length);
          const double agree = dot(normals[s], normals[*q]);
          if (slope > 0.3 || std::abs(agree) < kSamePlaneCos) continue;
          ++c.pairs;
          if (agree >= 0) continue;
          const bool two_sides = a * b > 0 && std::min(std::abs(a), std::abs(b)) >= kTwoSidesOffset * length;
          if (!two_sides) c.flips.push_back({uint32_t(s), *q});
        }
      }
    }
  });
  tracker.check();
  Counts all;
  for (Counts& c : counts) {
    all.pairs += c.pairs;
    all.clear += c.clear;
    all.flips.insert(all.flips.end(), c.flips.begin(), c.flips.end());
  }
  // Duplicates take their representative's normal (a representative is its own).
  parallel_blocks(n, kGrain, [&](size_t b, size_t e) {
    for (size_t s = b; s < e; ++s)
      if (rep[s] != s) normals[s] = normals[rep[s]];
  });
  if (double(all.flips.size()) > kMaxReferenceDisagreement * double(all.pairs)) return false;
  return double(longest_chain(all.flips, lists)) <= kMaxFlipChain * std::sqrt(double(all.clear));
}

void orient_normals_mst(const NeighborGrid& grid, const std::vector<uint32_t>& rep,
                        const NeighborLists& lists, const std::vector<double>& radius, std::vector<Vec3>& normals,
                        const std::vector<Vec3>& reference, ProgressTracker& tracker, bool noisy) {
  const size_t n = grid.point_count();
  // Noisy samplings: a cost for taking an edge between two sheets (see normals_impl.h). On
  // clean samplings two sheets apart are two sheets (a thin part's sides), and the plain cost
  // stays. Measured in bench/RESULTS.md, "Which way the surface faces".
  const double between_sheets = noisy ? 1.0 : 0.0;
  // Edges s < t of the neighbour graph, keyed by (cost as float bits, edge index): the keys
  // order the edges by cost, ties broken by position in the list, and are all distinct.
  // One pass: each block of points lists its edges, then the blocks are placed in order.
  struct Found {
    uint32_t from, to;
    uint32_t bits;  // the cost's (a non-negative float's bits order as the float)
    bool turn;      // whether the edge turns one normal against the other
  };
  const size_t eblock = 2048, eblocks = (n + eblock - 1) / eblock;
  std::vector<std::vector<Found>> found(eblocks);
  parallel_blocks(eblocks, 1, [&](size_t bb, size_t be) {
    for (size_t blk = bb; blk < be; ++blk) {
      found[blk].reserve(8 * eblock);  // about 5 per point on even samplings
      for (size_t s = blk * eblock; s < std::min(n, (blk + 1) * eblock); ++s) {
        if (rep[s] != s || !(squared_norm(normals[s]) > 0)) continue;
        const Vec3 p = grid.sorted_point(uint32_t(s));
        const Vec3 ns = normals[s];
        for (const uint32_t* q = std::upper_bound(lists.begin(uint32_t(s)), lists.end(uint32_t(s)), uint32_t(s));
             q != lists.end(uint32_t(s)); ++q) {
          const Vec3 d = grid.sorted_point(*q) - p;
          const double r = pair_limit(radius[s], radius[*q]);
          if (!(squared_norm(normals[*q]) > 0) || squared_norm(d) > r * r) continue;
          const Vec3 nt = normals[*q];
          const double len = norm(d);
          // Slope of the edge out of the tangent planes: ~0 within a sheet, ~1 across a gap.
          const double slope = (std::abs(dot(d, ns)) + std::abs(dot(d, nt))) / (2 * len);
          const bool across = slope > 0.5;
          const float cost = float(1.0 - std::abs(dot(ns, nt)) + (across ? between_sheets + 1.0 - slope : slope));
          uint32_t bits;
          std::memcpy(&bits, &cost, sizeof bits);
          // Within a sheet the normals should agree; across a gap they should be opposite.
          found[blk].push_back({uint32_t(s), *q, bits, (dot(ns, nt) < 0) != across});
        }
      }
    }
  });
  std::vector<uint64_t> offset(eblocks + 1, 0);
  for (size_t blk = 0; blk < eblocks; ++blk) offset[blk + 1] = offset[blk] + found[blk].size();
  const uint64_t m = offset[eblocks];
  if (m >= (uint64_t(1) << 31)) throw Error(Status::LimitExceeded, "too many neighbour pairs for normal orientation");
  std::vector<uint32_t> edge_from(m), edge_to(m);
  std::vector<uint64_t> keys(m);
  parallel_blocks(eblocks, 1, [&](size_t bb, size_t be) {
    for (size_t blk = bb; blk < be; ++blk) {
      uint64_t k = offset[blk];
      for (const Found& f : found[blk]) {
        edge_from[k] = f.from;
        edge_to[k] = f.to;
        // The low bit of the index slot carries the edge's turn (k < 2^31 is checked above).
        keys[k] = (uint64_t(f.bits) << 32) | (k << 1) | uint64_t(f.turn);
        ++k;
      }
      std::vector<Found>().swap(found[blk]);
    }
  });
  tracker.check();
  // The minimum spanning forest under these keys. They are distinct, so the forest is unique
  // (the one Kruskal's algorithm gives); it is found by Boruvka's rounds rather than by
  // sorting every edge: each component takes its cheapest outgoing edge (a parallel pass over
  // the edges still between components), and the components those edges join merge.
  //
  // Hoppe's propagation turns each normal to agree with its tree neighbour's (or oppose it,
  // across a gap), from the root down: a point's turn is the parity of the turning edges on
  // its tree path. That parity is kept with the merges (a union-find with parity), so no
  // traversal of the tree is needed: flip[v] is v's turn relative to its component's label,
  // and a label's turn relative to its parent label is turn_of[label].
  std::vector<uint32_t> comp(n), parent(n), labels, live;
  std::vector<uint8_t> flip(n, 0), turn_of(n, 0);
  std::iota(comp.begin(), comp.end(), 0u);
  std::iota(parent.begin(), parent.end(), 0u);
  // The root of x, and x's turn relative to it in `turn` (halving the path on the way).
  auto find = [&](uint32_t x, uint8_t& turn) {
    turn = 0;
    while (parent[x] != x) {
      const uint32_t up = parent[x];
      if (parent[up] != up) {
        turn_of[x] ^= turn_of[up];
        parent[x] = parent[up];
      }
      turn ^= turn_of[x];
      x = parent[x];
    }
    return x;
  };
  live.resize(m);
  std::iota(live.begin(), live.end(), 0u);
  {
    // Every endpoint of an edge is a component of its own at the start.
    std::vector<uint8_t> endpoint(n, 0);
    parallel_blocks(m, 65536, [&](size_t b, size_t e) {
      for (size_t k = b; k < e; ++k)
        for (uint32_t v : {edge_from[k], edge_to[k]}) std::atomic_ref<uint8_t>(endpoint[v]).store(1, std::memory_order_relaxed);
    });
    for (uint32_t s = 0; s < n; ++s)
      if (endpoint[s]) labels.push_back(s);
  }
  constexpr uint64_t kNone = ~uint64_t(0);
  std::vector<std::atomic<uint64_t>> best(n);
  bool first_round = true;
  while (!live.empty()) {
    tracker.check();
    parallel_blocks(labels.size(), 8192, [&](size_t b, size_t e) {
      for (size_t i = b; i < e; ++i) best[labels[i]].store(kNone, std::memory_order_relaxed);
    });
    parallel_blocks(live.size(), 8192, [&](size_t b, size_t e) {
      for (size_t i = b; i < e; ++i) {
        const uint32_t k = live[i];
        const uint64_t key = keys[k];
        for (uint32_t c : {comp[edge_from[k]], comp[edge_to[k]]}) {
          uint64_t cur = best[c].load(std::memory_order_relaxed);
          while (key < cur && !best[c].compare_exchange_weak(cur, key, std::memory_order_relaxed)) {
          }
        }
      }
    });
    if (first_round) {
      // Every label is a point: the chosen edges make trees whose two ends of one edge chose
      // it both. Rooted at the lower of those two, each point's root and turn come from
      // pointer jumping, in parallel (serial joins were a visible part of this stage).
      std::vector<uint32_t> ptr(n), ptr2(n);
      std::vector<uint8_t> par(n, 0), par2(n, 0);
      parallel_blocks(labels.size(), 8192, [&](size_t b, size_t e) {
        for (size_t i = b; i < e; ++i) {
          const uint32_t c = labels[i];
          const uint64_t key = best[c].load(std::memory_order_relaxed);
          const uint32_t k = uint32_t((key & 0xffffffffu) >> 1);
          const uint32_t w = edge_from[k] == c ? edge_to[k] : edge_from[k];
          const bool root = best[w].load(std::memory_order_relaxed) == key && c < w;
          ptr[c] = root ? c : w;
          par[c] = root ? 0 : uint8_t(key & 1u);
        }
      });
      for (bool moved = true; moved;) {
        std::atomic<bool> any{false};
        parallel_blocks(labels.size(), 8192, [&](size_t b, size_t e) {
          bool local = false;
          for (size_t i = b; i < e; ++i) {
            const uint32_t c = labels[i], up = ptr[c];
            ptr2[c] = ptr[up];
            par2[c] = par[c] ^ par[up];
            local = local || ptr[up] != up;
          }
          if (local) any.store(true, std::memory_order_relaxed);
        });
        ptr.swap(ptr2);
        par.swap(par2);
        moved = any.load();
      }
      parallel_blocks(labels.size(), 8192, [&](size_t b, size_t e) {
        for (size_t i = b; i < e; ++i) {
          const uint32_t c = labels[i];
          comp[c] = ptr[c];
          flip[c] = par[c];
        }
      });
      std::vector<uint32_t> next_labels;
      for (uint32_t c : labels)
        if (ptr[c] == c) next_labels.push_back(c);
      labels.swap(next_labels);
      first_round = false;
    } else {
      // Join along the chosen edges (each is in the forest; two components may choose the same),
      // serially over the labels: the same joins for any thread count.
      for (uint32_t c : labels) {
        const uint64_t key = best[c].load(std::memory_order_relaxed);
        if (key == kNone) continue;
        const uint32_t k = uint32_t((key & 0xffffffffu) >> 1);
        const uint32_t from = edge_from[k], to = edge_to[k];
        uint8_t ta, tb;
        const uint32_t a = find(comp[from], ta), b = find(comp[to], tb);
        if (a == b) continue;
        // turn(to) = turn(from) ^ the edge's turn; the child root's turn relative to the other.
        const uint32_t child = std::max(a, b);
        parent[child] = std::min(a, b);
        turn_of[child] = uint8_t(flip[from] ^ ta ^ flip[to] ^ tb ^ uint8_t(key & 1u));
      }
      // The roots are the next labels; every old label points straight at its root (find
      // only halves paths), so that the points relabel in one step. Old labels that are no
      // roots are never looked at again.
      std::vector<uint32_t> next_labels;
      for (uint32_t c : labels) {
        uint8_t t;
        const uint32_t root = find(c, t);
        if (root == c) next_labels.push_back(c);
        parent[c] = root;
        turn_of[c] = t;
      }
      parallel_blocks(n, 8192, [&](size_t b, size_t e) {
        for (size_t v = b; v < e; ++v) {
          flip[v] ^= turn_of[comp[v]];
          comp[v] = parent[comp[v]];
        }
      });
      labels.swap(next_labels);
    }
    // Keep the edges still between components, in their order (the same for any thread
    // count): each block compacts its part, then the parts close up.
    const size_t block = 65536, blocks = (live.size() + block - 1) / block;
    std::vector<size_t> kept(blocks);
    parallel_blocks(blocks, 1, [&](size_t bb, size_t be) {
      for (size_t b = bb; b < be; ++b) {
        size_t out = b * block;
        for (size_t i = b * block; i < std::min(live.size(), (b + 1) * block); ++i)
          if (comp[edge_from[live[i]]] != comp[edge_to[live[i]]]) live[out++] = live[i];
        kept[b] = out - b * block;
      }
    });
    size_t size = 0;
    for (size_t b = 0; b < blocks; ++b) {
      std::copy_n(live.begin() + ptrdiff_t(b * block), kept[b], live.begin() + ptrdiff_t(size));
      size += kept[b];
    }
    live.resize(size);
  }
  std::vector<std::atomic<uint64_t>>().swap(best);
  std::vector<uint32_t>().swap(edge_from);
  std::vector<uint32_t>().swap(edge_to);
  std::vector<uint64_t>().swap(keys);
  // Each tree's root is its highest point (then the lowest index among equals), and its normal
  // is turned to point up; every other point follows by its turn relative to the root.
  auto higher = [&](uint32_t a, uint32_t b) {
    const Vec3 &p = grid.sorted_point(a), &q = grid.sorted_point(b);
    if (p.z != q.z) return p.z > q.z;
    if (p.x != q.x) return p.x > q.x;
    return p.y > q.y;
  };
  auto in_forest = [&](size_t s) { return rep[s] == s && squared_norm(normals[s]) > 0; };
  std::vector<uint32_t> top(n, UINT32_MAX);
  for (uint32_t s = 0; s < n; ++s) {
    if (!in_forest(s)) continue;
    uint32_t& t = top[comp[s]];
    if (t == UINT32_MAX || higher(s, t)) t = s;
  }
  // root_flip[c]: whether component c's label turns, so that its top point faces up.
  std::vector<uint8_t> root_flip(n, 0);
  parallel_blocks(n, 8192, [&](size_t b, size_t e) {
    for (size_t c = b; c < e; ++c) {
      if (top[c] == UINT32_MAX) continue;
      const Vec3 nr = normals[top[c]];
      const bool down = nr.z < 0 || (nr.z == 0 && (nr.x < 0 || (nr.x == 0 && nr.y < 0)));
      root_flip[c] = uint8_t(down) ^ flip[top[c]];
    }
  });
  tracker.check();
  parallel_blocks(n, 8192, [&](size_t b, size_t e) {
    for (size_t s = b; s < e; ++s)
      if (in_forest(s) && (flip[s] ^ root_flip[comp[s]])) normals[s] = -normals[s];
  });
  if (!reference.empty()) {
    // The reference normals vote which way each tree faces (in point order: a fixed sum).
    std::vector<double> agreement(n, 0.0);
    for (uint32_t s = 0; s < n; ++s)
      if (in_forest(s)) agreement[comp[s]] += dot(normals[s], reference[s]);
    parallel_blocks(n, 8192, [&](size_t b, size_t e) {
      for (size_t s = b; s < e; ++s)
        if (in_forest(s) && agreement[comp[s]] < 0) normals[s] = -normals[s];
    });
  }
  for (size_t s = 0; s < n; ++s)
    if (rep[s] != s) normals[s] = normals[rep[s]];
}

}  // namespace detail

std::vector<Vec3> estimate_normals(const PointCloud& cloud, const NormalOptions& options) {
  validate_point_cloud(cloud);
  if (cloud.size() < 3) throw Error(Status::InvalidInput, "at least three points are needed to estimate normals");
  if (!(options.radius >= 0) || !std::isfinite(options.radius))
    throw Error(Status::InvalidArgument, "normal radius must be >= 0 (0 = 2 x spacing)");
  detail::ProgressTracker tracker(options.progress);
  return detail::with_threads(options.threads, [&] {
    // The raw smallest-sphere triangles with L = radius give the robust plane fits their candidates.
    TriangulateOptions topt;
    topt.spacing = options.radius / 2;
    topt.max_neighbors = size_t(1) << 20;
    const detail::RawTriangulation raw = detail::run_raw_triangulation(cloud, topt, tracker, 0.0, 0.6,
                                                                         detail::TriangleIndices::Sorted);
    const std::vector<double>& radius = raw.max_edge;
    tracker.stage("estimating normals", 0.6, 0.85, cloud.size());
    std::vector<Vec3> sorted = detail::pca_normals_sorted(*raw.grid, raw.rep, raw.neighbors, radius, tracker, &raw.triangles);
    tracker.stage("orienting normals", 0.85, 1.0);
    detail::orient_normals_mst(*raw.grid, raw.rep, raw.neighbors, radius, sorted, {}, tracker);
    std::vector<Vec3> out(cloud.size());
    for (uint32_t s = 0; s < cloud.size(); ++s) out[raw.grid->original_index(s)] = sorted[s];
    tracker.finish();
    return out;
  });
}

}  // namespace particlemesh
