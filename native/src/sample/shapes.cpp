#include "particlemesh/sample/shapes.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <limits>
#include <random>
#include <unordered_map>

#include "particlemesh/core/error.h"
#include "core/hashing.h"
#include "core/parallel.h"

namespace PM_NAMESPACE {

namespace {

constexpr double kPi = std::numbers::pi;

double uniform01(std::mt19937_64& rng) { return double(rng() >> 11) * 0x1.0p-53; }

/// The kept points of a dart-throwing Poisson-disk sample, bucketed in cells of side r0: a
/// dart is free when no kept point lies within r0 of it. A dart's own cell is looked at
/// first (once the surface is covered nearly every dart is refused, most often by it), then
/// the neighbours by how near they come: the 6 across a face, the 12 across an edge and the 8
/// across a corner, each only if some point of it can lie within r0 of the dart (about 21 of
/// the 26). The cells are an open-addressing table (linear probing on the cell's hash, as
/// std::unordered_map's buckets and nodes cost two more dependent reads per look-up); each
/// holds its points as a list through the kept points' array. The answer is whether any kept
/// point lies within r0, which does not depend on the order the cells are read in.
class PoissonDiskGrid {
 public:
  explicit PoissonDiskGrid(double r0) : inv_(1.0 / r0), r2_(r0 * r0) { rehash(1024); }
  bool free(const Vec3& p) const {
    const double s[3] = {p.x * inv_, p.y * inv_, p.z * inv_};
    std::array<int32_t, 3> c;
    double below[3], above[3];  // the dart's distance to its cell's faces, in cells, squared
    for (int a = 0; a < 3; ++a) {
      const double f = std::floor(s[a]);
      c[size_t(a)] = int32_t(f);
      below[a] = (s[a] - f) * (s[a] - f);
      above[a] = (1 - (s[a] - f)) * (1 - (s[a] - f));
    }
    if (near(c, p)) return false;
    // Every point of a neighbour lies at least sqrt(gap) cells away, as coord() scales the
    // coordinates; the margin covers the rounding of those products (a few units in the last
    // place of the largest scaled coordinate) and of 1 / r0.
    const double reach =
        1 + 16 * std::numeric_limits<double>::epsilon() * (1 + std::max({std::abs(s[0]), std::abs(s[1]), std::abs(s[2])}));
    for (const auto& d : kNeighbours) {
      double gap = 0;
      for (int a = 0; a < 3; ++a) gap += d[a] < 0 ? below[a] : d[a] > 0 ? above[a] : 0.0;
      if (gap >= reach) continue;
      if (near({c[0] + d[0], c[1] + d[1], c[2] + d[2]}, p)) return false;
    }
    return true;
  }
  void add(const Vec3& p) {
    if (2 * (used_ + 1) > keys_.size()) rehash(2 * keys_.size());
    const uint64_t key = detail::hash_cell(coord(p));
    size_t i = key & mask_;
    while (heads_[i] != kNone && keys_[i] != key) i = (i + 1) & mask_;
    if (heads_[i] == kNone) {
      keys_[i] = key;
      ++used_;
    }
    next_.push_back(heads_[i]);
    heads_[i] = uint32_t(points_.size());
    points_.push_back(p);
  }

 private:
  static constexpr uint32_t kNone = 0xffffffffu;
  // The 26 neighbours, faces first, then edges, then corners.
  static constexpr auto kNeighbours = [] {
    std::array<std::array<int, 3>, 26> out{};
    size_t k = 0;
    for (int nonzero = 1; nonzero <= 3; ++nonzero)
      for (int dx = -1; dx <= 1; ++dx)
        for (int dy = -1; dy <= 1; ++dy)
          for (int dz = -1; dz <= 1; ++dz)
            if ((dx != 0) + (dy != 0) + (dz != 0) == nonzero) out[k++] = {dx, dy, dz};
    return out;
  }();

  std::array<int32_t, 3> coord(const Vec3& p) const {
    return {int32_t(std::floor(p.x * inv_)), int32_t(std::floor(p.y * inv_)), int32_t(std::floor(p.z * inv_))};
  }
  bool near(const std::array<int32_t, 3>& c, const Vec3& p) const {
    const uint64_t key = detail::hash_cell(c);
    for (size_t i = key & mask_; heads_[i] != kNone; i = (i + 1) & mask_)
      if (keys_[i] == key) {
        for (uint32_t j = heads_[i]; j != kNone; j = next_[j])
          if (squared_distance(points_[j], p) < r2_) return true;
        return false;
      }
    return false;
  }
  void rehash(size_t size) {
    std::vector<uint64_t> old_keys = std::move(keys_);
    std::vector<uint32_t> old_heads = std::move(heads_);
    keys_.assign(size, 0);
    heads_.assign(size, kNone);
    mask_ = size - 1;
    for (size_t o = 0; o < old_heads.size(); ++o) {
      if (old_heads[o] == kNone) continue;
      size_t i = old_keys[o] & mask_;
      while (heads_[i] != kNone) i = (i + 1) & mask_;
      keys_[i] = old_keys[o];
      heads_[i] = old_heads[o];
    }
  }

  double inv_, r2_;
  std::vector<uint64_t> keys_;   // a cell's hash (two cells of one hash share a slot: still exact)
  std::vector<uint32_t> heads_;  // its newest point, kNone for an empty slot
  std::vector<Vec3> points_;
  std::vector<uint32_t> next_;   // per point: the previous point of its cell
  size_t mask_ = 0, used_ = 0;
};

void add_quad(std::vector<Triangle>& t, uint32_t a, uint32_t b, uint32_t c, uint32_t d) {
  t.push_back({a, b, c});
  t.push_back({a, c, d});
}

// A closed tube mesh around a closed curve given by position and derivative functions.
template <class Curve, class Deriv>
TriMesh tube_mesh(Curve curve, Deriv deriv, double radius, int nu, int nv) {
  // Rotation-minimising frames (double reflection, Wang et al. 2008), with the closure twist
  // spread evenly along the curve so the last ring meets the first.
  std::vector<Vec3> P(size_t(nu) + 1), Tg(size_t(nu) + 1), Nr(size_t(nu) + 1);
  for (int i = 0; i <= nu; ++i) {
    const double t = 2 * kPi * i / nu;
    P[size_t(i)] = curve(t);
    Tg[size_t(i)] = normalized(deriv(t));
  }
  Vec3 up = std::abs(Tg[0].z) < 0.9 ? Vec3{0, 0, 1} : Vec3{1, 0, 0};
  Nr[0] = normalized(cross(cross(Tg[0], up), Tg[0]));
  for (int i = 0; i < nu; ++i) {
    const Vec3 v1 = P[size_t(i) + 1] - P[size_t(i)];
    const double c1 = dot(v1, v1);
    const Vec3 rL = Nr[size_t(i)] - v1 * (2 / c1 * dot(v1, Nr[size_t(i)]));
    const Vec3 tL = Tg[size_t(i)] - v1 * (2 / c1 * dot(v1, Tg[size_t(i)]));
    const Vec3 v2 = Tg[size_t(i) + 1] - tL;
    const double c2 = dot(v2, v2);
    Nr[size_t(i) + 1] = c2 > 0 ? rL - v2 * (2 / c2 * dot(v2, rL)) : rL;
  }
  // Angle between the transported frame at the end and the start frame.
  const Vec3 b0 = cross(Tg[0], Nr[0]);
  const double twist = std::atan2(dot(Nr[size_t(nu)], b0), dot(Nr[size_t(nu)], Nr[0]));
  TriMesh m;
  for (int i = 0; i < nu; ++i) {
    const double a = -twist * i / nu;
    const Vec3 n0 = Nr[size_t(i)], b = cross(Tg[size_t(i)], n0);
    const Vec3 n = n0 * std::cos(a) + b * std::sin(a);
    const Vec3 bb = cross(Tg[size_t(i)], n);
    for (int j = 0; j < nv; ++j) {
      const double phi = 2 * kPi * j / nv;
      const Vec3 dir = n * std::cos(phi) + bb * std::sin(phi);
      m.positions.push_back(P[size_t(i)] + dir * radius);
      m.normals.push_back(dir);
    }
  }
  // (T, n, b) is right-handed and phi turns from n to b, so this winding faces outward.
  auto id = [&](int i, int j) { return uint32_t(((i + nu) % nu) * nv + (j + nv) % nv); };
  for (int i = 0; i < nu; ++i)
    for (int j = 0; j < nv; ++j) add_quad(m.triangles, id(i, j), id(i, j + 1), id(i + 1, j + 1), id(i + 1, j));
  return m;
}

}  // namespace

PointCloud fibonacci_sphere(size_t n, double radius, Vec3 center) {
  PointCloud c;
  c.positions.resize(n);
  c.normals.resize(n);
  const double golden = kPi * (3.0 - std::sqrt(5.0));
  for (size_t i = 0; i < n; ++i) {
    const double z = 1.0 - (2.0 * double(i) + 1.0) / double(n);
    const double r = std::sqrt(std::max(0.0, 1.0 - z * z));
    const double phi = golden * double(i);
    const Vec3 d{r * std::cos(phi), r * std::sin(phi), z};
    c.normals[i] = d;
    c.positions[i] = center + d * radius;
  }
  return c;
}

TriMesh torus_mesh(double R, double r, int nu, int nv) {
  if (nu < 3 || nv < 3) throw Error(Status::InvalidArgument, "torus needs at least 3 x 3 segments");
  TriMesh m;
  for (int i = 0; i < nu; ++i)
    for (int j = 0; j < nv; ++j) {
      const double u = 2 * kPi * i / nu, v = 2 * kPi * j / nv;
      const Vec3 n{std::cos(u) * std::cos(v), std::sin(u) * std::cos(v), std::sin(v)};
      m.positions.push_back({(R + r * std::cos(v)) * std::cos(u), (R + r * std::cos(v)) * std::sin(u), r * std::sin(v)});
      m.normals.push_back(n);
    }
  auto id = [&](int i, int j) { return uint32_t(((i + nu) % nu) * nv + (j + nv) % nv); };
  for (int i = 0; i < nu; ++i)
    for (int j = 0; j < nv; ++j) add_quad(m.triangles, id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1));
  return m;
}

TriMesh trefoil_tube_mesh(double scale, double tube_radius, int nu, int nv) {
  if (nu < 8 || nv < 3) throw Error(Status::InvalidArgument, "trefoil tube needs at least 8 x 3 segments");
  auto curve = [scale](double t) {
    return Vec3{std::sin(t) + 2 * std::sin(2 * t), std::cos(t) - 2 * std::cos(2 * t), -std::sin(3 * t)} * scale;
  };
  auto deriv = [scale](double t) {
    return Vec3{std::cos(t) + 4 * std::cos(2 * t), -std::sin(t) + 4 * std::sin(2 * t), -3 * std::cos(3 * t)} * scale;
  };
  return tube_mesh(curve, deriv, tube_radius, nu, nv);
}

TriMesh box_mesh(Vec3 size) {
  if (!(size.x > 0 && size.y > 0 && size.z > 0) || !is_finite(size))
    throw Error(Status::InvalidArgument, "box size must be finite and > 0 along every axis");
  TriMesh m;
  for (int i = 0; i < 8; ++i) m.positions.push_back({i & 1 ? size.x : 0, i & 2 ? size.y : 0, i & 4 ? size.z : 0});
  // Corner i has x from bit 0, y from bit 1, z from bit 2; each face's quad winds outward.
  add_quad(m.triangles, 0, 2, 3, 1);  // z = 0
  add_quad(m.triangles, 4, 5, 7, 6);  // z = size.z
  add_quad(m.triangles, 0, 1, 5, 4);  // y = 0
  add_quad(m.triangles, 2, 6, 7, 3);  // y = size.y
  add_quad(m.triangles, 0, 4, 6, 2);  // x = 0
  add_quad(m.triangles, 1, 3, 7, 5);  // x = size.x
  return m;
}

TriMesh cone_mesh(double r, double h, int nu) {
  if (!(r > 0 && h > 0) || !std::isfinite(r) || !std::isfinite(h) || nu < 3)
    throw Error(Status::InvalidArgument, "cone needs a finite radius and height > 0 and at least 3 sectors");
  TriMesh m;
  m.positions = {{0, 0, h}, {0, 0, 0}};  // apex, centre of the base
  for (int i = 0; i < nu; ++i) m.positions.push_back({r * std::cos(2 * kPi * i / nu), r * std::sin(2 * kPi * i / nu), 0});
  for (int i = 0; i < nu; ++i) {
    const uint32_t p = 2 + uint32_t(i), q = 2 + uint32_t((i + 1) % nu);
    m.triangles.push_back({p, q, 0});
    m.triangles.push_back({1, q, p});
  }
  return m;
}

TriMesh prism_mesh(double apex_deg, double height) {
  if (!(apex_deg > 0 && apex_deg < 180) || !(height > 0) || !std::isfinite(height))
    throw Error(Status::InvalidArgument, "prism needs an apex angle in (0, 180) degrees and a finite height > 0");
  const double a = apex_deg * kPi / 360;
  const Vec3 A{0, 0, 0}, B{std::cos(a), std::sin(a), 0}, C{std::cos(a), -std::sin(a), 0}, Z{0, 0, height};
  TriMesh m;
  m.positions = {A, B, C, A + Z, B + Z, C + Z};
  add_quad(m.triangles, 0, 2, 5, 3);  // side A-C
  add_quad(m.triangles, 2, 1, 4, 5);  // side C-B
  add_quad(m.triangles, 1, 0, 3, 4);  // side B-A
  m.triangles.push_back({0, 1, 2});
  m.triangles.push_back({3, 5, 4});
  return m;
}

TriMesh icosphere_mesh(int levels, double radius) {
  if (levels < 0 || levels > 9) throw Error(Status::InvalidArgument, "icosphere levels must be in [0, 9]");
  const double t = (1.0 + std::sqrt(5.0)) / 2.0;
  TriMesh m;
  m.positions = {{-1, t, 0}, {1, t, 0}, {-1, -t, 0}, {1, -t, 0}, {0, -1, t}, {0, 1, t},
                 {0, -1, -t}, {0, 1, -t}, {t, 0, -1}, {t, 0, 1}, {-t, 0, -1}, {-t, 0, 1}};
  m.triangles = {{0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11}, {1, 5, 9}, {5, 11, 4},
                 {11, 10, 2}, {10, 7, 6}, {7, 1, 8},  {3, 9, 4},  {3, 4, 2},   {3, 2, 6}, {3, 6, 8},
                 {3, 8, 9},  {4, 9, 5},  {2, 4, 11}, {6, 2, 10}, {8, 6, 7},   {9, 8, 1}};
  for (auto& p : m.positions) p = normalized(p);
  for (int l = 0; l < levels; ++l) {
    std::unordered_map<uint64_t, uint32_t> mid;
    auto midpoint = [&](uint32_t a, uint32_t b) {
      const uint64_t key = a < b ? (uint64_t(a) << 32 | b) : (uint64_t(b) << 32 | a);
      auto it = mid.find(key);
      if (it != mid.end()) return it->second;
      m.positions.push_back(normalized(m.positions[a] + m.positions[b]));
      const uint32_t id = uint32_t(m.positions.size() - 1);
      mid.emplace(key, id);
      return id;
    };
    std::vector<Triangle> next;
    for (const auto& tr : m.triangles) {
      const uint32_t a = midpoint(tr[0], tr[1]), b = midpoint(tr[1], tr[2]), c = midpoint(tr[2], tr[0]);
      next.push_back({tr[0], a, c});
      next.push_back({tr[1], b, a});
      next.push_back({tr[2], c, b});
      next.push_back({a, b, c});
    }
    m.triangles = std::move(next);
  }
  m.normals = m.positions;
  for (auto& p : m.positions) p = p * radius;
  return m;
}

PointCloud poisson_disk_sample(const TriMesh& mesh, double r0, uint64_t seed, double oversampling) {
  if (!(r0 > 0) || !std::isfinite(r0)) throw Error(Status::InvalidArgument, "r0 must be positive");
  if (!(oversampling > 0)) throw Error(Status::InvalidArgument, "oversampling must be positive");
  // Cumulative areas for area-uniform triangle choice.
  std::vector<double> cum(mesh.triangles.size());
  double area = 0;
  for (size_t f = 0; f < mesh.triangles.size(); ++f) {
    const auto& t = mesh.triangles[f];
    area += 0.5 * norm(cross(mesh.positions[t[1]] - mesh.positions[t[0]], mesh.positions[t[2]] - mesh.positions[t[0]]));
    cum[f] = area;
  }
  if (!(area > 0)) throw Error(Status::InvalidInput, "the mesh has no area to sample");
  const double want = oversampling * area / (r0 * r0);
  if (want > 2e8) throw Error(Status::LimitExceeded, "poisson_disk_sample would draw more than 2e8 candidates");
  const size_t candidates = size_t(std::ceil(want));
  std::mt19937_64 rng(seed);
  PointCloud out;
  PoissonDiskGrid grid(r0);
  // The darts' random numbers are drawn in their order, a chunk at a time; their triangles
  // (a search of the cumulative areas) and points are found in parallel; then each is kept
  // or refused in order: the same sample for any thread count.
  constexpr size_t kChunk = size_t(1) << 16;
  std::vector<double> draw(3 * std::min(candidates, kChunk));
  std::vector<Vec3> dart(draw.size() / 3);
  std::vector<uint32_t> face(dart.size());
  for (size_t c0 = 0; c0 < candidates; c0 += kChunk) {
    const size_t n = std::min(kChunk, candidates - c0);
    for (size_t i = 0; i < 3 * n; ++i) draw[i] = uniform01(rng);
    detail::parallel_blocks(n, 2048, [&](size_t begin, size_t end) {
      for (size_t i = begin; i < end; ++i) {
        const double pick = draw[3 * i] * area;
        const size_t f = std::min(size_t(std::lower_bound(cum.begin(), cum.end(), pick) - cum.begin()), cum.size() - 1);
        const auto& t = mesh.triangles[f];
        double u = draw[3 * i + 1], v = draw[3 * i + 2];
        if (u + v > 1) { u = 1 - u; v = 1 - v; }
        const Vec3 a = mesh.positions[t[0]], b = mesh.positions[t[1]], d = mesh.positions[t[2]];
        dart[i] = a + (b - a) * u + (d - a) * v;
        face[i] = uint32_t(f);
      }
    });
    for (size_t i = 0; i < n; ++i) {
      const Vec3& p = dart[i];
      if (!grid.free(p)) continue;
      grid.add(p);
      const auto& t = mesh.triangles[face[i]];
      const Vec3 a = mesh.positions[t[0]], b = mesh.positions[t[1]], d = mesh.positions[t[2]];
      out.positions.push_back(p);
      out.normals.push_back(normalized(cross(b - a, d - a)));
    }
  }
  return out;
}

PointCloud sample_implicit_surface(const std::function<double(const Vec3&)>& f,
                                   const std::function<Vec3(const Vec3&)>& grad, Vec3 lo, Vec3 hi, double r0,
                                   uint64_t seed, size_t candidates) {
  if (!(r0 > 0)) throw Error(Status::InvalidArgument, "r0 must be positive");
  const Vec3 ext = hi - lo;
  if (candidates == 0) {
    // Enough darts for a maximal sample: about 30 per r0^2 of the box's largest face x 6.
    const double face = std::max({ext.x * ext.y, ext.y * ext.z, ext.x * ext.z});
    candidates = size_t(std::min(2e7, 180.0 * face / (r0 * r0)));
  }
  // The darts come from one random sequence, a chunk at a time; each is pulled onto the
  // surface on its own, so the chunk's darts are projected in parallel and kept in their
  // order: the same sample for any thread count (the Newton steps are most of the time:
  // 2 x 10^7 darts for the double torus at r0 = 0.008).
  std::mt19937_64 rng(seed);
  std::vector<Vec3> on;
  constexpr size_t kChunk = size_t(1) << 16;
  std::vector<Vec3> dart(std::min(candidates, kChunk));
  std::vector<uint8_t> kept(dart.size());
  for (size_t c0 = 0; c0 < candidates; c0 += kChunk) {
    const size_t n = std::min(kChunk, candidates - c0);
    for (size_t i = 0; i < n; ++i)
      dart[i] = {lo.x + ext.x * uniform01(rng), lo.y + ext.y * uniform01(rng), lo.z + ext.z * uniform01(rng)};
    detail::parallel_blocks(n, 512, [&](size_t b, size_t e) {
      for (size_t i = b; i < e; ++i) {
        Vec3& p = dart[i];
        bool ok = false;
        for (int it = 0; it < 30; ++it) {
          const double v = f(p);
          const Vec3 g = grad(p);
          const double g2 = squared_norm(g);
          if (!(g2 > 1e-20)) break;
          const Vec3 step = g * (v / g2);
          p -= step;
          if (squared_norm(step) < 1e-24 * std::max(1.0, squared_norm(p))) {
            ok = std::abs(f(p)) < 1e-9;
            break;
          }
        }
        kept[i] = ok && p.x >= lo.x && p.y >= lo.y && p.z >= lo.z && p.x <= hi.x && p.y <= hi.y && p.z <= hi.z;
      }
    });
    for (size_t i = 0; i < n; ++i)
      if (kept[i]) on.push_back(dart[i]);
  }
  PointCloud out;
  PoissonDiskGrid grid(r0);
  for (const Vec3& p : on) {
    if (!grid.free(p)) continue;
    grid.add(p);
    out.positions.push_back(p);
    out.normals.push_back(normalized(grad(p)));
  }
  return out;
}

PointCloud double_torus_sample(double r0, uint64_t seed) {
  // g(x, y) = x (x-1)^2 (x-2) + y^2; f = g^2 + z^2 - c.
  constexpr double c = 0.04;
  auto g = [](const Vec3& p) { return p.x * (p.x - 1) * (p.x - 1) * (p.x - 2) + p.y * p.y; };
  auto f = [&](const Vec3& p) { const double gv = g(p); return gv * gv + p.z * p.z - c; };
  auto grad = [&](const Vec3& p) {
    const double x = p.x, gv = g(p);
    // d/dx [x (x-1)^2 (x-2)] = (x-1)^2 (x-2) + 2x (x-1)(x-2) + x (x-1)^2
    const double gx = (x - 1) * (x - 1) * (x - 2) + 2 * x * (x - 1) * (x - 2) + x * (x - 1) * (x - 1);
    return Vec3{2 * gv * gx, 2 * gv * 2 * p.y, 2 * p.z};
  };
  return sample_implicit_surface(f, grad, {-0.5, -1.2, -0.3}, {2.5, 1.2, 0.3}, r0, seed);
}

PointCloud square_lattice(int nx, int ny, double spacing) {
  PointCloud c;
  for (int i = 0; i < nx; ++i)
    for (int j = 0; j < ny; ++j) {
      c.positions.push_back({i * spacing, j * spacing, 0});
      c.normals.push_back({0, 0, 1});
    }
  return c;
}

PointCloud hex_lattice(int nx, int ny, double spacing) {
  PointCloud c;
  const double h = spacing * std::sqrt(3.0) / 2.0;
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) {
      c.positions.push_back({(i + 0.5 * (j & 1)) * spacing, j * h, 0});
      c.normals.push_back({0, 0, 1});
    }
  return c;
}

}  // namespace particlemesh
