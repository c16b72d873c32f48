// The particle field: F and its gradient against a brute-force sum, the local search, the
// defaults (radius from the spacing, threshold from the lattice field) and bad input.
#include "particlemesh/volume/field.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <random>
#include <vector>

#include "particlemesh/core/error.h"
#include "particlemesh/sample/shapes.h"
#include "particlemesh/spatial/spacing.h"
#include "support/test_support.h"

using namespace particlemesh;

namespace {

double brute_value(const std::vector<Vec3>& P, const std::vector<double>& R, const std::vector<double>& W, Kernel k,
                   const Vec3& x, Vec3* grad) {
  double v = 0;
  Vec3 g{};
  for (size_t i = 0; i < P.size(); ++i) {
    const double s = squared_distance(x, P[i]) / (R[i] * R[i]);
    v += W[i] * kernel_value(k, s);
    g += (x - P[i]) * (2 * W[i] * kernel_derivative(k, s) / (R[i] * R[i]));
  }
  if (grad) *grad = g;
  return v;
}

Error error_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const Error& e) {
    return e;
  }
  return Error(Status::Ok, "no error");
}

}  // namespace

TEST(ParticleField, ValueAndGradientMatchBruteForce) {
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> u(0, 1), r(0.05, 0.3), w(-0.5, 2.0);
  const PointCloud c = test::random_cloud(400, 3);
  std::vector<double> radii, strengths;
  for (size_t i = 0; i < c.size(); ++i) {
    radii.push_back(r(rng));
    strengths.push_back(w(rng));
  }
  for (Kernel k : {Kernel::Wyvill, Kernel::Poly4, Kernel::Poly6, Kernel::Blinn}) {
    FieldParams p;
    p.kernel = k;
    p.threshold = 0.5;
    p.radii = radii;
    p.strengths = strengths;
    const ParticleField f(c, p);
    EXPECT_EQ(f.size(), c.size());
    EXPECT_DOUBLE_EQ(f.max_radius(), *std::max_element(radii.begin(), radii.end()));
    for (int q = 0; q < 300; ++q) {
      const Vec3 x{u(rng) * 1.2 - 0.1, u(rng) * 1.2 - 0.1, u(rng) * 1.2 - 0.1};
      Vec3 gb, gf;
      const double vb = brute_value(c.positions, radii, strengths, k, x, &gb);
      const double vf = f.value_and_gradient(x, &gf);
      ASSERT_NEAR(vf, vb, 1e-12) << kernel_name(k);
      ASSERT_NEAR(f.value(x), vb, 1e-12);
      ASSERT_NEAR(norm(gf - gb), 0.0, 1e-9);
      ASSERT_NEAR(norm(f.gradient(x) - gb), 0.0, 1e-9);
      ASSERT_EQ(f.inside(x), vb >= 0.5);
    }
  }
}

TEST(ParticleField, GradientMatchesFiniteDifferences) {
  const PointCloud c = test::random_cloud(200, 5);
  const ParticleField f(c, FieldParams{Kernel::Poly6, 0.2, 1.0, {}, {}, {}});
  std::mt19937_64 rng(2);
  std::uniform_real_distribution<double> u(0.1, 0.9);
  for (int q = 0; q < 100; ++q) {
    const Vec3 x{u(rng), u(rng), u(rng)};
    const double d = 1e-6;
    const Vec3 fd{(f.value(x + Vec3{d, 0, 0}) - f.value(x - Vec3{d, 0, 0})) / (2 * d),
                  (f.value(x + Vec3{0, d, 0}) - f.value(x - Vec3{0, d, 0})) / (2 * d),
                  (f.value(x + Vec3{0, 0, d}) - f.value(x - Vec3{0, 0, d})) / (2 * d)};
    EXPECT_NEAR(norm(f.gradient(x) - fd), 0.0, 1e-5 * std::max(1.0, norm(fd)));
  }
}

TEST(ParticleField, ContributorsAreExactlyTheParticlesWhoseSupportHoldsX) {
  const PointCloud c = test::random_cloud(1000, 9);
  std::vector<double> radii(c.size());
  for (size_t i = 0; i < c.size(); ++i) radii[i] = 0.03 + 0.1 * double(i % 7) / 7;
  FieldParams p;
  p.radii = radii;
  p.threshold = 1;
  const ParticleField f(c, p);
  std::mt19937_64 rng(4);
  std::uniform_real_distribution<double> u(0, 1);
  for (int q = 0; q < 200; ++q) {
    const Vec3 x{u(rng), u(rng), u(rng)};
    std::vector<size_t> got, want;
    f.for_each_contributor(x, [&](size_t i, double s) {
      got.push_back(i);
      EXPECT_NEAR(s, squared_distance(x, f.position(i)) / (radii[i] * radii[i]), 1e-12);
      EXPECT_LT(s, 1.0);
    });
    for (size_t i = 0; i < c.size(); ++i)
      if (squared_distance(x, c.positions[i]) < radii[i] * radii[i]) want.push_back(i);
    std::sort(got.begin(), got.end());
    ASSERT_EQ(got, want);
  }
}

TEST(ParticleField, LatticeFieldCountsTheLatticeSupport) {
  // R <= spacing: only the particle itself.
  EXPECT_DOUBLE_EQ(lattice_field(Kernel::Poly4, 1.0, 1.0), 1.0);
  EXPECT_DOUBLE_EQ(lattice_field(Kernel::Poly4, 0.5, 1.0), 1.0);
  // R slightly above the spacing: itself plus the 6 face neighbours at s = (1/1.2)^2.
  const double s1 = 1 / (1.2 * 1.2);
  EXPECT_NEAR(lattice_field(Kernel::Wyvill, 1.2, 1.0), 1 + 6 * kernel_value(Kernel::Wyvill, s1), 1e-14);
  // Scale invariance and the continuum limit (R / spacing > 64 switches to the integral).
  EXPECT_DOUBLE_EQ(lattice_field(Kernel::Poly6, 2.0, 1.0), lattice_field(Kernel::Poly6, 0.02, 0.01));
  for (Kernel k : {Kernel::Wyvill, Kernel::Poly4, Kernel::Poly6, Kernel::Blinn}) {
    const double a = lattice_field(k, 63.9, 1.0), b = lattice_field(k, 64.1, 1.0);
    EXPECT_NEAR(b / a, std::pow(64.1 / 63.9, 3), 2e-3) << kernel_name(k);
  }
  EXPECT_THROW(lattice_field(Kernel::Wyvill, 0, 1), Error);
  EXPECT_THROW(lattice_field(Kernel::Wyvill, 1, -1), Error);
  EXPECT_THROW(lattice_field(Kernel::Wyvill, std::nan(""), 1), Error);
}

TEST(ParticleField, DefaultsComeFromTheSpacing) {
  PointCloud c;
  for (int i = 0; i < 10; ++i)
    for (int j = 0; j < 10; ++j)
      for (int k = 0; k < 10; ++k) c.positions.push_back({0.1 * i, 0.1 * j, 0.1 * k});
  const double spacing = estimate_spacing(c.positions.data(), c.size()).spacing;
  const ParticleField f(c, FieldParams{Kernel::Poly6, 0, 0, {}, {}, {}});
  EXPECT_TRUE(f.radius_defaulted());
  EXPECT_TRUE(f.threshold_defaulted());
  EXPECT_DOUBLE_EQ(f.spacing(), spacing);
  EXPECT_DOUBLE_EQ(f.params().radius, kDefaultRadiusFactor * spacing);
  EXPECT_DOUBLE_EQ(f.threshold(), kDefaultThresholdFraction * lattice_field(Kernel::Poly6, 2 * spacing, spacing));
  // A sheet one particle thick is packed more sparsely than a block of its spacing, and at
  // 2 x spacing a fifth of it falls outside the surface: the default radius grows so that its
  // own field reaches a block's (measured at the grown radius, the packing asks for about as
  // much again: the map is a lattice's, the sheet is not one).
  const PointCloud sheet = square_lattice(20, 20, 0.1);
  const ParticleField s(sheet, FieldParams{Kernel::Poly6, 0, 0, {}, {}, {}});
  EXPECT_TRUE(s.radius_defaulted());
  EXPECT_DOUBLE_EQ(s.spacing(), estimate_spacing(sheet.positions.data(), sheet.size()).spacing);
  EXPECT_GT(s.params().radius, 1.1 * kDefaultRadiusFactor * s.spacing());
  EXPECT_NEAR(s.params().radius, field_at_particles(s).density_radius, 0.1 * s.params().radius);
  EXPECT_GT(field_at_particles(s).enclosed_fraction, 0.9);
  EXPECT_LT(field_at_particles(ParticleField(sheet, FieldParams{Kernel::Poly6, 2 * s.spacing(), 0, {}, {}, {}}))
                .enclosed_fraction,
            0.85);
  // A thin shell sampled evenly reads as sparse too, but its field at 2 x spacing already
  // holds every particle: it keeps that radius (and its mesh).
  const PointCloud shell = fibonacci_sphere(20000);
  const ParticleField sf(shell, FieldParams{});
  const FieldAtParticles sat = field_at_particles(sf);
  EXPECT_DOUBLE_EQ(sf.params().radius, kDefaultRadiusFactor * sf.spacing());
  EXPECT_GT(sat.enclosed_fraction, 0.99);
  EXPECT_GT(sat.density_radius, 1.1 * sf.params().radius);
  // Given values are kept and no spacing is estimated.
  const ParticleField g(c, FieldParams{Kernel::Poly6, 0.3, 0.7, {}, {}, {}});
  EXPECT_FALSE(g.radius_defaulted());
  EXPECT_FALSE(g.threshold_defaulted());
  EXPECT_EQ(g.spacing(), 0.0);
  EXPECT_EQ(g.params().radius, 0.3);
  EXPECT_EQ(g.threshold(), 0.7);
  // Per-particle radii: the reference radius is their median; strengths scale the default T,
  // which is a constant per kernel (no spacing estimate when no radius is defaulted).
  FieldParams p;
  p.radii.assign(c.size(), 0.25);
  p.radii[0] = 5;
  p.strengths.assign(c.size(), 2.0);
  const ParticleField h(c, p);
  EXPECT_EQ(h.params().radius, 0.25);
  EXPECT_EQ(h.max_radius(), 5.0);
  EXPECT_DOUBLE_EQ(h.threshold(), 0.5 * 2.0 * lattice_field(Kernel::Wyvill, 2, 1));
  EXPECT_EQ(h.spacing(), 0.0);
  EXPECT_TRUE(h.threshold_defaulted());
  // The stated constants.
  EXPECT_NEAR(0.5 * lattice_field(Kernel::Wyvill, 2, 1), 3.3333, 1e-4);
  EXPECT_NEAR(0.5 * lattice_field(Kernel::Poly4, 2, 1), 3.9375, 1e-4);
  EXPECT_NEAR(0.5 * lattice_field(Kernel::Poly6, 2, 1), 2.5781, 1e-4);
  EXPECT_NEAR(0.5 * lattice_field(Kernel::Blinn, 2, 1), 1.2334, 1e-4);
  // Positions come back in input order.
  for (size_t i = 0; i < c.size(); ++i) ASSERT_EQ(h.position(i), c.positions[i]);
}

// The field at the particles' own centres: packed particles at the default radius are inside
// their surface and say their radius is right; irregular ones (uniform random points, whose
// median nearest-neighbour distance is about half their mean spacing) are mostly outside it,
// and the radius their packing suggests takes most of them in.
TEST(ParticleField, FieldAtTheParticlesSaysHowTheyArePacked) {
  PointCloud block;
  for (int i = 0; i < 12; ++i)
    for (int j = 0; j < 12; ++j)
      for (int k = 0; k < 12; ++k) block.positions.push_back({0.5 * i, 0.5 * j, 0.5 * k});
  for (Kernel kernel : {Kernel::Wyvill, Kernel::Poly4, Kernel::Poly6}) {
    const FieldAtParticles at = field_at_particles(ParticleField(block, FieldParams{kernel, 0, 0, {}, {}, {}}));
    EXPECT_GT(at.enclosed_fraction, 0.99);  // all but a few corners
    EXPECT_NEAR(at.density_radius, 1.0, 1e-5);
  }
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  PointCloud random;
  for (int i = 0; i < 4000; ++i) random.positions.push_back({u(rng), u(rng), u(rng)});
  const double spacing = estimate_spacing(random.positions.data(), random.size()).spacing;
  const ParticleField f(random, FieldParams{Kernel::Wyvill, kDefaultRadiusFactor * spacing, 0, {}, {}, {}});
  const FieldAtParticles at = field_at_particles(f);
  EXPECT_LT(at.enclosed_fraction, 0.2);
  EXPECT_GT(at.density_radius, 1.25 * f.params().radius);
  EXPECT_LT(at.density_radius, 2.0 * f.params().radius);  // at most 2x: the particle alone
  const FieldAtParticles again = field_at_particles(ParticleField(random, FieldParams{Kernel::Wyvill, at.density_radius, 0, {}, {}, {}}));
  EXPECT_GT(again.enclosed_fraction, 0.5);
  // The default radius is that suggestion, so the default field takes most of them in.
  const ParticleField d(random, FieldParams{});
  EXPECT_TRUE(d.radius_defaulted());
  EXPECT_EQ(d.spacing(), spacing);
  EXPECT_EQ(d.params().radius, at.density_radius);
  EXPECT_EQ(field_at_particles(d).enclosed_fraction, again.enclosed_fraction);
  // The default radius does not depend on a given threshold (it is decided at the default).
  for (double t : {0.5, 3.0, 9.0})
    EXPECT_EQ(ParticleField(random, FieldParams{Kernel::Wyvill, 0, t, {}, {}, {}}).params().radius, d.params().radius);
  // Per-particle radii and anisotropic kernels suggest no radius; the share is still measured.
  FieldParams radii;
  radii.radii.assign(random.size(), f.params().radius);
  const FieldAtParticles per = field_at_particles(ParticleField(random, radii));
  EXPECT_EQ(per.density_radius, 0.0);
  EXPECT_EQ(per.enclosed_fraction, at.enclosed_fraction);
}

TEST(ParticleField, BadInputGivesClearErrors) {
  const PointCloud c = test::random_cloud(10, 1);
  auto build = [&](FieldParams p, PointCloud cloud) { return [p, cloud] { ParticleField f(cloud, p); }; };
  PointCloud nan = c;
  nan.positions[3].y = std::nan("");
  Error e = error_of(build(FieldParams{Kernel::Wyvill, 1, 1, {}, {}, {}}, nan));
  EXPECT_EQ(e.status(), Status::InvalidInput);
  EXPECT_NE(std::string(e.what()).find("positions[3].y is NaN"), std::string::npos) << e.what();

  EXPECT_EQ(error_of(build(FieldParams{Kernel::Wyvill, 1, 1, {}, {}, {}}, PointCloud{})).status(), Status::InvalidInput);
  for (double r : {-1.0, std::nan(""), std::numeric_limits<double>::infinity()}) {
    e = error_of(build(FieldParams{Kernel::Wyvill, r, 1, {}, {}, {}}, c));
    EXPECT_EQ(e.status(), Status::InvalidArgument);
    EXPECT_NE(std::string(e.what()).find("radius"), std::string::npos);
  }
  for (double t : {-1.0, std::nan("")}) {
    e = error_of(build(FieldParams{Kernel::Wyvill, 1, t, {}, {}, {}}, c));
    EXPECT_EQ(e.status(), Status::InvalidArgument);
    EXPECT_NE(std::string(e.what()).find("threshold"), std::string::npos);
  }
  FieldParams p{Kernel::Wyvill, 1, 1, std::vector<double>(10, 0.1), {}, {}};
  p.radii[7] = 0;
  e = error_of(build(p, c));
  EXPECT_EQ(e.status(), Status::InvalidArgument);
  EXPECT_NE(std::string(e.what()).find("radii[7] is 0"), std::string::npos) << e.what();
  p.radii.resize(9, 0.1);
  EXPECT_NE(std::string(error_of(build(p, c)).what()).find("radii has 9 values for 10"), std::string::npos);
  FieldParams q{Kernel::Wyvill, 1, 1, {}, std::vector<double>(10, 1.0), {}};
  q.strengths[2] = std::nan("");
  EXPECT_NE(std::string(error_of(build(q, c)).what()).find("strengths[2] is NaN"), std::string::npos);
  // The default threshold from a subnormal median strength underflowed to T = 0 (found by
  // fuzzing); from a huge one (1e30, the largest accepted) it is fine.
  FieldParams z{Kernel::Wyvill, 1, 0, {}, std::vector<double>(10, 4.9e-324), {}};
  e = error_of(build(z, c));
  EXPECT_EQ(e.status(), Status::InvalidArgument);
  EXPECT_NE(std::string(e.what()).find("give a threshold"), std::string::npos) << e.what();
  z.strengths.assign(10, kMaxStrength);
  EXPECT_NO_THROW(build(z, c)());
  // Strengths near DBL_MAX overflowed the field's sums: NaN normals at the hits (fuzzing).
  z.strengths[4] = -1.7e308;
  e = error_of(build(z, c));
  EXPECT_EQ(e.status(), Status::InvalidArgument);
  EXPECT_NE(std::string(e.what()).find("strengths[4] is"), std::string::npos) << e.what();
  EXPECT_NE(std::string(e.what()).find("at most 1e30"), std::string::npos) << e.what();
  // 1e50 is finite in double but not in the polygonizer's float samples: NaN vertices before
  // the limit came down from 1e100 (found by fuzzing).
  z.strengths[4] = 1e50;
  EXPECT_NE(std::string(error_of(build(z, c)).what()).find("strengths[4] is 1.0000000000000001e+50"), std::string::npos);
  EXPECT_EQ(error_of(build(FieldParams{static_cast<Kernel>(9), 1, 1, {}, {}, {}}, c)).status(), Status::InvalidArgument);
  // A default needs the spacing: one particle cannot give it.
  PointCloud one;
  one.positions.push_back({0, 0, 0});
  e = error_of(build(FieldParams{Kernel::Wyvill, 0, 1, {}, {}, {}}, one));
  EXPECT_EQ(e.status(), Status::InvalidInput);
  EXPECT_NE(std::string(e.what()).find("give a radius"), std::string::npos) << e.what();
  EXPECT_NO_THROW(build(FieldParams{Kernel::Wyvill, 1, 0.5, {}, {}, {}}, one)());
  EXPECT_NO_THROW(build(FieldParams{Kernel::Wyvill, 1, 0, {}, {}, {}}, one)());  // default T needs no spacing
}

// for_each_column_in (the runs a polygonized edge gathers its particles from): its runs,
// expanded, are for_each_cell_in's cells in the same order, each run consecutive cells of one
// (x, y) column; with the dense cell table (one cloud) and without it (two clouds far apart,
// where each cell is a run of its own), for boxes inside, across and outside the cells, 1 to
// 6 cells long along z (the row scan has cases for 2, 3 and 4 cells and a general one).
TEST(ParticleField, ColumnRunsAreTheBoxCellsInOrder) {
  PointCloud one = test::random_cloud(3000, 5);
  PointCloud two = one;
  for (const Vec3& p : one.positions) two.positions.push_back(p + Vec3{5000, -3000, 4000});
  for (int sparse = 0; sparse < 2; ++sparse) {
    FieldParams params;
    params.radius = 0.07;
    params.threshold = 0.5;
    const ParticleField f(sparse ? two : one, params);
    const NeighborGrid& grid = f.grid();
    std::mt19937_64 rng(29 + uint64_t(sparse));
    std::uniform_real_distribution<double> u(-0.3, 1.3), ext(0.0, 0.25);
    size_t longest = 0, cells_seen = 0;
    uint32_t z_lengths_seen = 0;  // bit k: a box k cells long along z (the row scan's cases)
    for (int t = 0; t < 4000; ++t) {
      Vec3 x{u(rng), u(rng), u(rng)};
      if (sparse && t % 2) x += Vec3{5000, -3000, 4000};
      const Vec3 lo_p = x - Vec3{ext(rng), ext(rng), ext(rng)}, hi_p = x + Vec3{ext(rng), ext(rng), ext(rng)};
      NeighborGrid::CellCoord lo = grid.coord_of(lo_p), hi = grid.coord_of(hi_p);
      if (t % 7 == 0) std::swap(lo[size_t(t % 3)], hi[size_t(t % 3)]);  // an empty box, sometimes
      std::vector<uint32_t> cells, runs;
      if (hi[2] >= lo[2]) z_lengths_seen |= 1u << std::min(hi[2] - lo[2] + 1, 31);
      f.for_each_cell_in(lo, hi, [&](uint32_t c) { cells.push_back(c); });
      f.for_each_column_in(lo, hi, [&](uint32_t c0, uint32_t c1) {
        ASSERT_LT(c0, c1);
        longest = std::max(longest, size_t(c1 - c0));
        for (uint32_t c = c0; c < c1; ++c) {
          const auto cc = grid.cell_coord(c), c0c = grid.cell_coord(c0);
          EXPECT_EQ(cc[0], c0c[0]);
          EXPECT_EQ(cc[1], c0c[1]);
          runs.push_back(c);
        }
      });
      ASSERT_EQ(runs, cells) << "sparse " << sparse << " box " << t;
      cells_seen += cells.size();
    }
    EXPECT_GT(cells_seen, 20000u);
    for (int k = 1; k <= 6; ++k) EXPECT_TRUE(z_lengths_seen >> k & 1u) << "no box " << k << " cells long along z";
    if (sparse) EXPECT_EQ(longest, 1u);  // the hashed cells: each its own run
    else EXPECT_GT(longest, 2u);         // the dense table: whole columns
  }
}

// Three particles of a radius 20 times the others': the grid's cells are sized by the others
// and those three kept apart; F, its gradient and the contributors are still every particle's.
TEST(ParticleField, AFewFarLargerRadiiAreKeptApartFromTheCells) {
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> u(0, 1), w(-0.5, 2.0);
  const PointCloud c = test::random_cloud(3000, 17);
  std::vector<double> radii(c.size(), 0.05), strengths;
  for (size_t i = 0; i < c.size(); ++i) strengths.push_back(w(rng));
  radii[10] = radii[2000] = 1.0;
  radii[2999] = 0.8;
  EXPECT_DOUBLE_EQ(particle_grid_radius(radii.data(), radii.size()), 0.05);
  FieldParams p;
  p.kernel = Kernel::Poly6;
  p.threshold = 0.5;
  p.radii = radii;
  p.strengths = strengths;
  const ParticleField f(c, p);
  EXPECT_DOUBLE_EQ(f.cell_reach(), 0.05);
  EXPECT_DOUBLE_EQ(f.max_radius(), 1.0);
  EXPECT_DOUBLE_EQ(f.grid().cell_size(), 0.05);
  ASSERT_EQ(f.grid().apart_begin(), c.size() - 3);
  for (int q = 0; q < 300; ++q) {
    // Inside the cloud and up to a large radius outside it (only the large ones reach there).
    const Vec3 x{u(rng) * 2.6 - 0.8, u(rng) * 2.6 - 0.8, u(rng) * 2.6 - 0.8};
    Vec3 gb, gf;
    const double vb = brute_value(c.positions, radii, strengths, p.kernel, x, &gb);
    ASSERT_NEAR(f.value_and_gradient(x, &gf), vb, 1e-12);
    ASSERT_NEAR(norm(gf - gb), 0.0, 1e-9);
    std::vector<size_t> got, want;
    f.for_each_contributor(x, [&](size_t i, double) { got.push_back(i); });
    for (size_t i = 0; i < c.size(); ++i)
      if (squared_distance(x, c.positions[i]) < radii[i] * radii[i]) want.push_back(i);
    std::sort(got.begin(), got.end());
    ASSERT_EQ(got, want);
  }
}

// Which radii are kept apart: only a few far above the rest, never an even spread.
TEST(ParticleField, ParticleGridRadiusKeepsOnlyAFewFarLargerApart) {
  std::vector<double> one(10000, 0.3);
  EXPECT_EQ(particle_grid_radius(one.data(), one.size()), 0.3);
  one[77] = 6.0;  // one 20 times the rest
  EXPECT_EQ(particle_grid_radius(one.data(), one.size()), 0.3);
  one[78] = 0.6;  // twice the rest: cheaper apart too
  EXPECT_EQ(particle_grid_radius(one.data(), one.size()), 0.3);
  for (size_t i = 100; i < 5100; ++i) one[i] = 0.45;  // too many to keep apart: the cells' radius
  EXPECT_EQ(particle_grid_radius(one.data(), one.size()), 0.45);
  // A spread of 5 (Blender's random size, Houdini's pscale drawn from a range): cells of the
  // largest, as before.
  std::vector<double> spread;
  for (int i = 0; i < 10000; ++i) spread.push_back(0.01 + 0.04 * double(i) / 9999.0);
  EXPECT_EQ(particle_grid_radius(spread.data(), spread.size()), 0.05);
  // Twice the radius for a tenth of them: too many to visit at every evaluation.
  std::vector<double> tenth(10000, 1.0);
  for (size_t i = 0; i < tenth.size(); i += 10) tenth[i] = 2.0;
  EXPECT_EQ(particle_grid_radius(tenth.data(), tenth.size()), 2.0);
  // The order of the radii does not matter.
  std::vector<double> mixed = one;
  std::reverse(mixed.begin(), mixed.end());
  EXPECT_EQ(particle_grid_radius(mixed.data(), mixed.size()), 0.45);
  EXPECT_EQ(particle_grid_radius(nullptr, 0), 0.0);
  one[5] = -1;
  const Error e = error_of([&] { particle_grid_radius(one.data(), one.size()); });
  EXPECT_EQ(e.status(), Status::InvalidArgument);
  EXPECT_NE(std::string(e.what()).find("radii[5]"), std::string::npos) << e.what();
}

// The same with anisotropic kernels: the cells are sized by the others' radius, the three far
// larger kept apart; F and the contributors are still every ellipsoid's (summed by brute force
// from each particle's own centre and matrix).
TEST(ParticleField, AnisotropicKernelsKeepTheFewFarLargerApartToo) {
  std::mt19937_64 rng(9);
  std::uniform_real_distribution<double> u(0, 1);
  const PointCloud c = test::jittered(test::random_cloud(4000, 23), 0.002, 5);
  std::vector<double> radii(c.size(), 0.12);
  radii[3] = radii[1500] = radii[3999] = 1.5;
  FieldParams p;
  p.threshold = 0.5;
  p.radii = radii;
  p.anisotropy.enabled = true;
  const ParticleField f(c, p);
  EXPECT_EQ(f.grid().cell_size(), 0.12);
  ASSERT_EQ(f.grid().apart_begin(), c.size() - 3);
  EXPECT_LT(f.cell_reach(), 0.12 * std::pow(p.anisotropy.max_stretch, 2.0 / 3.0) + 1e-12);
  EXPECT_GT(f.max_reach(), 1.4);
  for (int q = 0; q < 200; ++q) {
    const Vec3 x{u(rng) * 2.4 - 0.7, u(rng) * 2.4 - 0.7, u(rng) * 2.4 - 0.7};
    double want = 0;
    std::vector<size_t> inside;
    for (size_t i = 0; i < c.size(); ++i) {
      const std::array<double, 6> m = f.metric(i);
      const Vec3 d = x - f.position(i);
      const double s = m[0] * d.x * d.x + m[1] * d.y * d.y + m[2] * d.z * d.z +
                       2.0 * (m[3] * d.x * d.y + m[4] * d.x * d.z + m[5] * d.y * d.z);
      if (s < 1.0) {
        want += kernel_value(p.kernel, s);
        inside.push_back(i);
      }
    }
    ASSERT_NEAR(f.value(x), want, 1e-12 * std::max(1.0, want));
    std::vector<size_t> got;
    f.for_each_contributor(x, [&](size_t i, double) { got.push_back(i); });
    std::sort(got.begin(), got.end());
    ASSERT_EQ(got, inside);
  }
}
