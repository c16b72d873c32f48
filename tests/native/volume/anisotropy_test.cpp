// Anisotropic kernels (Yu and Turk 2013) and what they are for: the kernels themselves (PCA,
// clamping, volume kept, the isotropic fallback, centre smoothing, determinism, errors), the
// field they make (value and gradient, the calibrated threshold), and the surface targets on a
// jittered block, a one-particle sheet and the real SPH frames.
#include "particlemesh/volume/anisotropy.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <numeric>
#include <random>

#include "particlemesh/core/error.h"
#include "particlemesh/io/mesh_io.h"
#include "particlemesh/mesh/components.h"
#include "particlemesh/mesh/topology_report.h"
#include "particlemesh/volume/field.h"
#include "particlemesh/volume/polygonize.h"
#include "support/test_support.h"

using namespace particlemesh;

namespace {

// A block of nx x ny x nz particles, spacing s, every coordinate jittered uniformly by +-j s.
PointCloud jittered_block(int nx, int ny, int nz, double s, double j, uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(-j, j);
  PointCloud c;
  for (int z = 0; z < nz; ++z)
    for (int y = 0; y < ny; ++y)
      for (int x = 0; x < nx; ++x) c.positions.push_back({(x + u(rng)) * s, (y + u(rng)) * s, (z + u(rng)) * s});
  return c;
}

double det3(const std::array<double, 6>& m) {
  return m[0] * (m[1] * m[2] - m[5] * m[5]) - m[3] * (m[3] * m[2] - m[5] * m[4]) + m[4] * (m[3] * m[5] - m[1] * m[4]);
}

// Semi-axes of the ellipsoid x^T M x < 1, longest first (the eigenvalues of M by Jacobi).
std::array<double, 3> semi_axes(const std::array<double, 6>& m) {
  double a[3][3] = {{m[0], m[3], m[4]}, {m[3], m[1], m[5]}, {m[4], m[5], m[2]}};
  for (int sweep = 0; sweep < 50; ++sweep)
    for (int p = 0; p < 3; ++p)
      for (int q = p + 1; q < 3; ++q) {
        if (std::abs(a[p][q]) < 1e-300) continue;
        const double th = 0.5 * std::atan2(2 * a[p][q], a[q][q] - a[p][p]);
        const double c = std::cos(th), s = std::sin(th);
        for (int k = 0; k < 3; ++k) {
          const double x = a[k][p], y = a[k][q];
          a[k][p] = c * x - s * y;
          a[k][q] = s * x + c * y;
        }
        for (int k = 0; k < 3; ++k) {
          const double x = a[p][k], y = a[q][k];
          a[p][k] = c * x - s * y;
          a[q][k] = s * x + c * y;
        }
      }
  std::array<double, 3> ax = {1 / std::sqrt(a[0][0]), 1 / std::sqrt(a[1][1]), 1 / std::sqrt(a[2][2])};
  std::sort(ax.begin(), ax.end(), std::greater<>());
  return ax;
}

double enclosed_volume(const TriMesh& m) {
  double v = 0;
  for (const Triangle& t : m.triangles) v += dot(m.positions[t[0]], cross(m.positions[t[1]], m.positions[t[2]])) / 6;
  return v;
}

double area(const TriMesh& m) {
  double a = 0;
  for (const Triangle& t : m.triangles)
    a += 0.5 * norm(cross(m.positions[t[1]] - m.positions[t[0]], m.positions[t[2]] - m.positions[t[0]]));
  return a;
}

// Closed, manifold, consistently oriented; `outward`: every closed piece has positive volume
// (no cavities expected).
void expect_watertight(const TriMesh& m, bool outward = true) {
  const TopologyReport r = topology_report(m);
  EXPECT_TRUE(r.closed);
  EXPECT_TRUE(r.manifold);
  EXPECT_TRUE(r.consistently_oriented);
  EXPECT_EQ(r.boundary_edges, 0u);
  EXPECT_EQ(r.nonmanifold_vertices, 0u);
  EXPECT_EQ(r.degenerate_triangles, 0u);
  EXPECT_EQ(r.vertices_used, r.vertices);
  if (outward) {
    EXPECT_TRUE(r.outward);
  }
}

// The smallest share, over the pieces of at least `min_triangles` triangles, of a piece's area
// whose winding agrees with the outward direction -grad F at the triangle: near 1 when every
// piece faces the way the field says, cavities included (a flipped piece would score near 0);
// the share over the whole mesh into *overall. As for spherical kernels (polygonize_test),
// marching cubes folds a few triangles where the surface bends within a cell.
double worst_piece_facing(const TriMesh& m, const ParticleField& f, size_t min_triangles, double* overall) {
  const MeshComponents c = mesh_components(m);
  std::vector<double> agree(c.triangles.size(), 0), all(c.triangles.size(), 0);
  for (const Triangle& t : m.triangles) {
    const Vec3 n = cross(m.positions[t[1]] - m.positions[t[0]], m.positions[t[2]] - m.positions[t[0]]);
    const Vec3 x = (m.positions[t[0]] + m.positions[t[1]] + m.positions[t[2]]) / 3.0;
    const uint32_t k = c.vertex_component[t[0]];
    all[k] += norm(n);
    if (dot(n, -f.gradient(x)) > 0) agree[k] += norm(n);
  }
  double worst = 1;
  for (size_t k = 0; k < all.size(); ++k)
    if (c.triangles[k] >= min_triangles && all[k] > 0) worst = std::min(worst, agree[k] / all[k]);
  *overall = std::accumulate(agree.begin(), agree.end(), 0.0) / std::accumulate(all.begin(), all.end(), 0.0);
  return worst;
}

// The flat top (y up) of a block of particles 0..n-1 spacings, away from its edges: the
// surface's height spread (standard deviation) and its normals' RMS tilt from vertical, in
// spacings and degrees, over the vertices within half a spacing of the top layer or above it
// and at least 4 spacings from the side faces.
struct FlatTop {
  double height_sd = 0, tilt_deg = 0, mean_height = 0;
  size_t vertices = 0;
};
FlatTop flat_top(const TriMesh& m, double s, int nx, int ny, int nz) {
  const double top = (ny - 1) * s;
  std::vector<double> h;
  double tilt2 = 0;
  for (size_t i = 0; i < m.positions.size(); ++i) {
    const Vec3& p = m.positions[i];
    if (p.y < top - 0.5 * s || p.x < 4 * s || p.x > (nx - 5) * s || p.z < 4 * s || p.z > (nz - 5) * s) continue;
    h.push_back(p.y);
    const double a = std::acos(std::clamp(m.normals[i].y, -1.0, 1.0)) * 180 / std::numbers::pi;
    tilt2 += a * a;
  }
  FlatTop r;
  r.vertices = h.size();
  if (h.empty()) return r;
  r.mean_height = std::accumulate(h.begin(), h.end(), 0.0) / double(h.size());
  double var = 0;
  for (double v : h) var += (v - r.mean_height) * (v - r.mean_height);
  r.height_sd = std::sqrt(var / double(h.size())) / s;
  r.mean_height = (r.mean_height - top) / s;
  r.tilt_deg = std::sqrt(tilt2 / double(h.size()));
  return r;
}

PolygonizeOptions anisotropic() {
  PolygonizeOptions o;
  o.anisotropy.enabled = true;
  return o;
}

}  // namespace

// ---- the kernels -----------------------------------------------------------------------------

// Inside a regular lattice the neighbourhood is symmetric: the kernel is the sphere of radius
// R, centred on the particle. On a one-particle sheet it is a pancake: longest axes in the
// sheet, the ratio clamped to k_r, the volume that of the sphere (det M = 1 / R^6).
TEST(AnisotropicKernels, SpheresInsideALatticePancakesOnASheet) {
  std::vector<Vec3> lattice;
  for (int z = -6; z <= 6; ++z)
    for (int y = -6; y <= 6; ++y)
      for (int x = -6; x <= 6; ++x) lattice.push_back({double(x), double(y), double(z)});
  AnisotropyOptions o;
  o.enabled = true;
  const double R = 2;
  const auto k = anisotropic_kernels(lattice, R, {}, o);
  const size_t centre = lattice.size() / 2;  // (0, 0, 0)
  ASSERT_EQ(lattice[centre], (Vec3{0, 0, 0}));
  EXPECT_TRUE(k[centre].anisotropic);
  EXPECT_EQ(k[centre].neighbors, 256u);  // lattice points within 4 of the origin, less itself
  // (The sums run in float: to ~1e-7 relative.)
  EXPECT_NEAR(k[centre].mean_offset, 0, 1e-7);
  EXPECT_EQ(k[centre].centre, lattice[centre]);  // no smoothing by default
  for (double a : semi_axes(k[centre].metric)) EXPECT_NEAR(a, R, 1e-6);

  std::vector<Vec3> sheet;
  for (int y = -8; y <= 8; ++y)
    for (int x = -8; x <= 8; ++x) sheet.push_back({double(x), double(y), 0.0});
  const auto ks = anisotropic_kernels(sheet, R, {}, o);
  const KernelEllipsoid& mid = ks[sheet.size() / 2];
  ASSERT_TRUE(mid.anisotropic);
  const auto ax = semi_axes(mid.metric);
  // (The sums run in float, and Eigen's closed-form eigensolver is accurate to ~1e-8 on a
  // repeated eigenvalue: the axes to ~1e-7 relative.)
  EXPECT_NEAR(ax[0], ax[1], 1e-6);
  EXPECT_NEAR(ax[0] / ax[2], o.max_stretch, 1e-6);  // no spread across: clamped to k_r
  EXPECT_NEAR(ax[0] * ax[1] * ax[2], R * R * R, 1e-6);
  EXPECT_NEAR(det3(mid.metric) * std::pow(R, 6), 1.0, 1e-6);
  // The short axis is across the sheet: s grows fastest along z.
  EXPECT_NEAR(1 / std::sqrt(mid.metric[2]), ax[2], 1e-6);

  // A larger k_r stretches further, up to the data's own spread.
  AnisotropyOptions wide = o;
  wide.max_stretch = 10;
  const auto ax10 = semi_axes(anisotropic_kernels(sheet, R, {}, wide)[sheet.size() / 2].metric);
  EXPECT_NEAR(ax10[0] / ax10[2], 10, 1e-6);
  AnisotropyOptions round = o;
  round.max_stretch = 1;
  for (double a : semi_axes(anisotropic_kernels(sheet, R, {}, round)[sheet.size() / 2].metric)) EXPECT_NEAR(a, R, 1e-6);
}

// A flat face: the outer layer's kernels are squeezed across the face, the bulk's are not.
TEST(AnisotropicKernels, SqueezedAcrossAFace) {
  std::vector<Vec3> half;
  for (int z = -10; z <= 0; ++z)
    for (int y = -8; y <= 8; ++y)
      for (int x = -8; x <= 8; ++x) half.push_back({double(x), double(y), double(z)});
  AnisotropyOptions o;
  o.enabled = true;
  const auto k = anisotropic_kernels(half, 2.0, {}, o);
  auto at = [&](int z) {
    for (size_t i = 0; i < half.size(); ++i)
      if (half[i] == Vec3{0, 0, double(z)}) return k[i];
    return KernelEllipsoid{};
  };
  const KernelEllipsoid top = at(0), deep = at(-5);
  const double across = 1 / std::sqrt(top.metric[2]);  // the semi-axis along z
  const auto ax = semi_axes(top.metric);
  EXPECT_NEAR(across, ax[2], 1e-6);
  EXPECT_LT(across, 0.55 * 2.0);
  EXPECT_GT(ax[0], 1.3 * 2.0);
  EXPECT_GT(top.mean_offset, 0.2);
  EXPECT_LT(deep.mean_offset, 1e-7);
  for (double a : semi_axes(deep.metric)) EXPECT_NEAR(a, 2.0, 1e-6);
}

TEST(AnisotropicKernels, FewNeighboursKeepTheSphereAndSmoothingMovesTheCentre) {
  // A short line of 5 particles: 4 neighbours each, fewer than N_eps = 25.
  std::vector<Vec3> line;
  for (int i = 0; i < 5; ++i) line.push_back({double(i), 0, 0});
  AnisotropyOptions o;
  o.enabled = true;
  const auto k = anisotropic_kernels(line, 1.5, {}, o);
  for (const auto& e : k) {
    EXPECT_FALSE(e.anisotropic);
    for (double a : semi_axes(e.metric)) EXPECT_NEAR(a, 1.5, 1e-12);  // exactly the sphere
  }
  EXPECT_EQ(k[0].neighbors, 3u);  // within 2 x 1.5 = 3
  o.min_neighbors = 2;
  const auto k2 = anisotropic_kernels(line, 1.5, {}, o);
  EXPECT_TRUE(k2[2].anisotropic);
  const auto ax = semi_axes(k2[2].metric);  // a cigar along x
  EXPECT_NEAR(ax[0] / ax[2], o.max_stretch, 1e-6);
  EXPECT_NEAR(1 / std::sqrt(k2[2].metric[0]), ax[0], 1e-6);
  // No smoothing by default; with lambda the end particle moves toward its neighbours' mean.
  EXPECT_EQ(k2[0].centre, line[0]);
  o.smoothing = 0.5;
  const auto k3 = anisotropic_kernels(line, 1.5, {}, o);
  // Weights 1 - (d / 3)^3 of the neighbours at 0, 1, 2, 3 of particle 0.
  const double w1 = 1 - 1.0 / 27, w2 = 1 - 8.0 / 27;
  const double mean = (w1 * 1 + w2 * 2) / (1 + w1 + w2);
  EXPECT_NEAR(k3[0].centre.x, 0.5 * mean, 1e-6);
  EXPECT_NEAR(k3[2].centre.x, 2.0, 1e-6);  // the middle one is balanced
}

TEST(AnisotropicKernels, SameForAnyThreadCountAndClearErrors) {
  const PointCloud c = test::random_cloud(20000, 3, 10.0);
  AnisotropyOptions o;
  o.enabled = true;
  o.smoothing = 0.3;
  const auto a = anisotropic_kernels(c.positions, 0.6, {}, o, 1);
  const auto b = anisotropic_kernels(c.positions, 0.6, {}, o, 2);
  ASSERT_EQ(a.size(), b.size());
  size_t aniso = 0;
  for (size_t i = 0; i < a.size(); ++i) {
    ASSERT_EQ(a[i].centre, b[i].centre);
    ASSERT_EQ(a[i].metric, b[i].metric);
    aniso += a[i].anisotropic;
  }
  EXPECT_GT(aniso, a.size() / 2);

  auto status = [](const std::function<void()>& f, const std::string& want) {
    try {
      f();
    } catch (const Error& e) {
      EXPECT_EQ(e.status(), Status::InvalidArgument);
      EXPECT_NE(std::string(e.what()).find(want), std::string::npos) << e.what();
      return;
    }
    ADD_FAILURE() << "no error for " << want;
  };
  for (auto [field, value] : {std::pair{"neighbor_radius", 0.0}, {"max_stretch", 0.5}, {"smoothing", 1.5},
                              {"max_stretch", std::nan("")}}) {
    AnisotropyOptions bad = o;
    if (std::string(field) == "neighbor_radius") bad.neighbor_radius = value;
    if (std::string(field) == "max_stretch") bad.max_stretch = value;
    if (std::string(field) == "smoothing") bad.smoothing = value;
    status([&] { anisotropic_kernels(c.positions, 0.6, {}, bad); }, field);
    PolygonizeOptions po;
    po.anisotropy = bad;
    po.anisotropy.enabled = true;
    status([&] { polygonize(c, po); }, field);
  }
  AnisotropyOptions bad = o;
  bad.min_neighbors = -1;
  status([&] { anisotropic_kernels(c.positions, 0.6, {}, bad); }, "min_neighbors");
  status([&] { anisotropic_kernels(c.positions, 0.6, {1.0}, o); }, "radii has 1 values");
  status([&] { anisotropic_kernels(c.positions, -1.0, {}, o); }, "radius is -1");
}

// Scale: the same particles 1e-20 and 1e20 times as large give the same ellipsoids, scaled
// (the sums run in float, in units of the neighbourhood: no overflow, no underflow).
TEST(AnisotropicKernels, SameShapesAtAnyScale) {
  const PointCloud c = jittered_block(8, 5, 8, 1.0, 0.15, 9);
  AnisotropyOptions o;
  o.enabled = true;
  o.smoothing = 0.5;
  const auto ref = anisotropic_kernels(c.positions, 1.8, {}, o);
  for (double scale : {1e-20, 1e20}) {
    std::vector<Vec3> p;
    for (const Vec3& x : c.positions) p.push_back(x * scale);
    const auto k = anisotropic_kernels(p, 1.8 * scale, {}, o);
    for (size_t i = 0; i < k.size(); i += 7) {
      ASSERT_EQ(k[i].anisotropic, ref[i].anisotropic);
      const auto a = semi_axes(k[i].metric), b = semi_axes(ref[i].metric);
      for (int j = 0; j < 3; ++j) EXPECT_NEAR(a[size_t(j)] / scale, b[size_t(j)], 1e-5 * b[size_t(j)]) << scale;
      EXPECT_NEAR(distance(k[i].centre / scale, ref[i].centre), 0.0, 1e-6);
    }
  }
}

// The kernels are a stage of their own in the progress, and cancelling there stops the call.
TEST(AnisotropicKernels, ReportProgressAndCancel) {
  const PointCloud c = jittered_block(20, 20, 20, 1.0, 0.15, 3);
  PolygonizeOptions o = anisotropic();
  bool seen = false;
  o.progress = [&](std::string_view stage, double) {
    if (stage == "anisotropic kernels") seen = true;
    return !seen;
  };
  try {
    polygonize(c, o);
    ADD_FAILURE() << "not cancelled";
  } catch (const Error& e) {
    EXPECT_EQ(e.status(), Status::Cancelled);
  }
  EXPECT_TRUE(seen);
}

// ---- the field -------------------------------------------------------------------------------

TEST(AnisotropicField, GradientIsTheDerivativeAndContributorsMatch) {
  const PointCloud c = jittered_block(8, 8, 8, 1.0, 0.15, 5);
  for (Kernel kernel : {Kernel::Wyvill, Kernel::Poly6, Kernel::Blinn}) {
    FieldParams p;
    p.kernel = kernel;
    p.radius = 2.0;
    p.threshold = 1.0;
    p.anisotropy.enabled = true;
    p.anisotropy.smoothing = 0.5;
    const ParticleField f(c, p);
    EXPECT_TRUE(f.anisotropic());
    EXPECT_GT(f.anisotropic_count(), c.size() / 2);
    EXPECT_GT(f.max_reach(), f.max_radius());
    std::mt19937_64 rng(2);
    std::uniform_real_distribution<double> u(-1.0, 8.0);
    for (int t = 0; t < 200; ++t) {
      const Vec3 x{u(rng), u(rng), u(rng)};
      Vec3 g;
      const double v = f.value_and_gradient(x, &g);
      const double h = 1e-6;
      for (int a = 0; a < 3; ++a) {
        Vec3 e{};
        (a == 0 ? e.x : a == 1 ? e.y : e.z) = h;
        const double fd = (f.value(x + e) - f.value(x - e)) / (2 * h);
        EXPECT_NEAR(g[a], fd, 1e-5 * (1 + std::abs(fd))) << kernel_name(kernel);
      }
      // The same sum by brute force over every particle's ellipsoid.
      double ref = 0, via = 0;
      for (size_t i = 0; i < f.size(); ++i) {
        const auto m = f.metric(i);
        const Vec3 d = x - f.position(i);
        ref += kernel_value(kernel, m[0] * d.x * d.x + m[1] * d.y * d.y + m[2] * d.z * d.z +
                                        2 * (m[3] * d.x * d.y + m[4] * d.x * d.z + m[5] * d.y * d.z));
      }
      f.for_each_contributor(x, [&](size_t, double s) { via += kernel_value(kernel, s); });
      EXPECT_NEAR(v, ref, 1e-12 * (1 + ref));
      EXPECT_NEAR(via, ref, 1e-12 * (1 + ref));
    }
  }
}

// Two clusters far apart: the field's dense cell table would be too big, so cells are found
// through the grid's hash instead; the values are the same sums.
TEST(AnisotropicField, FarApartClustersUseTheHashedCells) {
  PointCloud c = jittered_block(6, 6, 6, 1.0, 0.15, 8);
  const size_t n = c.size();
  for (size_t i = 0; i < n; ++i) c.positions.push_back(c.positions[i] + Vec3{3000, 2000, 4000});
  FieldParams p;
  p.radius = 2.0;
  p.threshold = 1.0;
  p.anisotropy.enabled = true;
  const ParticleField f(c, p);
  for (const Vec3 off : {Vec3{0, 0, 0}, Vec3{3000, 2000, 4000}})
    for (int t = 0; t < 50; ++t) {
      const Vec3 x = off + Vec3{0.13 * t - 1, 0.07 * t, 5 - 0.11 * t};
      double ref = 0;
      for (size_t i = 0; i < f.size(); ++i) {
        const auto m = f.metric(i);
        const Vec3 d = x - f.position(i);
        ref += kernel_value(Kernel::Wyvill, m[0] * d.x * d.x + m[1] * d.y * d.y + m[2] * d.z * d.z +
                                                2 * (m[3] * d.x * d.y + m[4] * d.x * d.z + m[5] * d.y * d.z));
      }
      EXPECT_NEAR(f.value(x), ref, 1e-12 * (1 + ref));
    }
  // Both clusters mesh alike (the second is the first moved).
  PolygonizeOptions o = anisotropic();
  o.radius = 2.0;
  const PolygonizeResult r = polygonize(c, o);
  EXPECT_EQ(topology_report(r.mesh).components, 2u);
}

// The calibrated default threshold: on a regular lattice's face the field at half a spacing
// outside is lattice_face_field at ratio R / s (here exactly 2).
TEST(AnisotropicField, DefaultThresholdIsCalibratedOnTheParticles) {
  // Spherical kernels: the face field is about half the interior level.
  EXPECT_NEAR(lattice_face_field(Kernel::Wyvill, 2.0) / lattice_field(Kernel::Wyvill, 2.0, 1.0), 0.5, 0.03);
  AnisotropyOptions a;
  a.enabled = true;
  const double face = lattice_face_field(Kernel::Wyvill, 2.0, a);
  EXPECT_GT(face, 0.3 * lattice_field(Kernel::Wyvill, 2.0, 1.0));
  EXPECT_LT(face, 0.6 * lattice_field(Kernel::Wyvill, 2.0, 1.0));
  PointCloud c;
  for (int z = 0; z < 16; ++z)
    for (int y = 0; y < 16; ++y)
      for (int x = 0; x < 16; ++x) c.positions.push_back({double(x), double(y), double(z)});
  FieldParams p;
  p.anisotropy = a;
  const ParticleField f(c, p);
  EXPECT_TRUE(f.threshold_defaulted());
  EXPECT_DOUBLE_EQ(f.params().radius, 2.0);
  // The bulk particles' median level reads the ratio R / s = 2 back to within a few percent
  // (the particles a few layers under the faces of so small a block pull it down a little).
  EXPECT_NEAR(f.calibration_ratio(), 2.0, 0.05);
  EXPECT_NEAR(f.threshold(), face, 0.1 * face);
  // Mid-face, half a spacing out, the field is lattice_face_field exactly (the block's own
  // face is the lattice's), and the surface crosses the axis there.
  double v = 0;
  for (int i = 0; i < 8; ++i)
    for (int j = 0; j < 8; ++j) v += f.value({7 + (i + 0.5) / 8, 7 + (j + 0.5) / 8, 15.5}) / 64;
  EXPECT_NEAR(v, face, 1e-6 * face);  // (the block's PCA sums in float, the lattice's in double)
  double lo = 15.0, hi = 17.0;  // F > T at 15 (the outer layer), F = 0 < T at 17
  ASSERT_GT(f.value({7.5, 7.5, lo}), f.threshold());
  for (int it = 0; it < 60; ++it) (f.value({7.5, 7.5, 0.5 * (lo + hi)}) >= f.threshold() ? lo : hi) = 0.5 * (lo + hi);
  EXPECT_NEAR(lo, 15.5, 0.1);
}

// ---- the surface -----------------------------------------------------------------------------

// The targets: a jittered block (spacing s, +-0.15 s) keeps a flat top and its volume.
TEST(AnisotropicPolygonize, JitteredBlockIsFlatAndKeepsItsVolume) {
  const int nx = 30, ny = 15, nz = 30;
  const double s = 0.1;
  const PointCloud c = jittered_block(nx, ny, nz, s, 0.15, 42);
  const PolygonizeResult an = polygonize(c, anisotropic());
  PolygonizeOptions spheres;  // the same radius
  spheres.radius = an.stats.radius;
  const PolygonizeResult iso = polygonize(c, spheres);
  EXPECT_TRUE(an.stats.anisotropic);
  EXPECT_EQ(an.stats.anisotropic_particles, c.size());
  const FlatTop ti = flat_top(iso.mesh, s, nx, ny, nz), ta = flat_top(an.mesh, s, nx, ny, nz);
  ASSERT_GT(ti.vertices, 1000u);
  ASSERT_GT(ta.vertices, 1000u);
  EXPECT_LE(ta.height_sd, 0.5 * ti.height_sd) << "iso " << ti.height_sd << " aniso " << ta.height_sd;
  EXPECT_LE(ta.tilt_deg, 0.5 * ti.tilt_deg) << "iso " << ti.tilt_deg << " aniso " << ta.tilt_deg;
  EXPECT_NEAR(ta.mean_height, 0.5, 0.1);  // the face half a spacing out
  const double particles_volume = double(c.size()) * s * s * s;
  EXPECT_NEAR(enclosed_volume(an.mesh) / particles_volume, 1.0, 0.05);
  expect_watertight(an.mesh);
  EXPECT_EQ(topology_report(an.mesh).components, 1u);
  EXPECT_EQ(topology_report(an.mesh).euler_characteristic, 2);
}

// A sheet one particle thick stays one closed surface, about twice the sheet's area (spherical
// kernels of the same radius break it into droplets or lose it; their default radius, grown
// for so sparse a packing, holds it as a thicker slab).
TEST(AnisotropicPolygonize, OneParticleSheetStaysOneSurface) {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(-0.15, 0.15);
  PointCloud c;
  for (int z = 0; z < 60; ++z)
    for (int x = 0; x < 60; ++x) c.positions.push_back({x + u(rng), u(rng), z + u(rng)});
  const PolygonizeResult an = polygonize(c, anisotropic());
  expect_watertight(an.mesh);
  const TopologyReport r = topology_report(an.mesh);
  EXPECT_EQ(r.components, 1u);
  EXPECT_EQ(r.euler_characteristic, 2);
  EXPECT_NEAR(area(an.mesh) / (2 * 60.0 * 60.0), 1.0, 0.15);
  PolygonizeOptions spheres;
  spheres.radius = an.stats.radius;
  EXPECT_LT(area(polygonize(c, spheres).mesh), 0.5 * area(an.mesh));
  const PolygonizeResult iso = polygonize(c);
  EXPECT_GT(iso.stats.radius, 1.1 * an.stats.radius);
  EXPECT_EQ(topology_report(iso.mesh).components, 1u);
  EXPECT_NEAR(area(iso.mesh) / (2 * 60.0 * 60.0), 1.0, 0.15);
}

TEST(AnisotropicPolygonize, SameMeshForAnyThreadCountAndVerticesOnTheSurface) {
  const PointCloud c = test::random_cloud(6000, 11, 12.0);
  PolygonizeOptions o = anisotropic();
  o.threads = 1;
  const PolygonizeResult a = polygonize(c, o);
  o.threads = 2;
  const PolygonizeResult b = polygonize(c, o);
  ASSERT_GT(a.mesh.triangles.size(), 1000u);
  EXPECT_EQ(a.mesh.positions, b.mesh.positions);
  EXPECT_EQ(a.mesh.normals, b.mesh.normals);
  EXPECT_EQ(a.mesh.triangles, b.mesh.triangles);
  EXPECT_EQ(a.stats.threshold, b.stats.threshold);
  expect_watertight(a.mesh, false);  // a random cloud has cavities
  // The vertices lie on F = T (refined on the true anisotropic field).
  FieldParams p;
  p.radius = a.stats.radius;
  p.threshold = a.stats.threshold;
  p.anisotropy = o.anisotropy;
  const ParticleField f(c, p);
  double worst = 0;
  for (const Vec3& v : a.mesh.positions) {
    Vec3 g;
    const double d = std::abs(f.value_and_gradient(v, &g) - f.threshold()) / std::max(norm(g), 1e-12);
    worst = std::max(worst, d);
  }
  EXPECT_LT(worst, 0.05 * a.stats.cell_size);
}

// Watertight, manifold and consistently oriented on the real SPH frames, at the defaults and at
// splashsurf's parameters (R = 4r, h = r / 2, T = 0.6 of the rest level), every piece facing
// the way the field says. (The splashy double dam break gets a few small closed cavities
// inside its sheets and droplets at the defaults: inward-facing pieces, each inside another.)
TEST(AnisotropicPolygonize, SphFramesAreWatertight) {
  for (const char* name : {"particles/double_dam_break_frame_26_4732_particles.ply",
                           "particles/bunny_frame_14_7705_particles.ply", "particles/cube_2366_particles.ply"}) {
    PM_REQUIRE_DATA(path, name);
    SCOPED_TRACE(name);
    const PointCloud c = read_point_cloud(path);
    const PolygonizeResult d = polygonize(c, anisotropic());
    expect_watertight(d.mesh, false);
    EXPECT_GT(d.mesh.triangles.size(), c.size());
    FieldParams p;
    p.radius = d.stats.radius;
    p.threshold = d.stats.threshold;
    p.anisotropy.enabled = true;
    double overall = 0;
    EXPECT_GT(worst_piece_facing(d.mesh, ParticleField(c, p), 64, &overall), 0.9);
    EXPECT_GT(overall, 0.995);
    PolygonizeOptions o = anisotropic();
    const double r = 0.025;
    o.radius = 4 * r;
    o.cell_size = 0.5 * r;
    o.threshold = 0.6 * lattice_field(Kernel::Wyvill, 4 * r, 2 * r);
    const PolygonizeResult s = polygonize(c, o);
    expect_watertight(s.mesh, false);
    p.radius = o.radius;
    p.threshold = o.threshold;
    EXPECT_GT(worst_piece_facing(s.mesh, ParticleField(c, p), 64, &overall), 0.9);
    EXPECT_GT(overall, 0.995);
    if (std::string(name).find("cube") != std::string::npos) {
      for (const PolygonizeResult* x : {&d, &s}) {
        EXPECT_TRUE(topology_report(x->mesh).outward);
        EXPECT_EQ(topology_report(x->mesh).components, 1u);
        EXPECT_EQ(topology_report(x->mesh).euler_characteristic, 2);
      }
      // A block of 13 x 14 x 13 particles 0.05 apart: its volume kept within 5 %.
      EXPECT_NEAR(enclosed_volume(d.mesh) / (2366 * 0.05 * 0.05 * 0.05), 1.0, 0.05);
    }
  }
}
