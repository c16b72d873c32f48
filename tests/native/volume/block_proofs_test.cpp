// Polygonize samples only the blocks that may hold surface (volume/block_proofs.h): the blocks
// it proves inside or outside get no samples, and the mesh is byte for byte the one from
// sampling every block. The reference here is the same cloud with one more particle far
// away with a negative strength of -1e-300: any negative strength turns the proofs off (the
// bounds need strengths >= 0), and that particle changes neither the grid (it lies beyond the
// others on +x; the grid starts below the supports) nor the surface.
#include <gtest/gtest.h>
#include <tbb/task_arena.h>

#include <cstring>
#include <random>
#include <string>

#include "particlemesh/io/mesh_io.h"
#include "particlemesh/volume/polygonize.h"
#include "support/test_support.h"
#include "volume/anisotropic_sampling.h"
#include "volume/block_proofs.h"
#include "volume/sphere_sampling.h"

using namespace particlemesh;
using particlemesh::detail::BlockProof;
using particlemesh::detail::kSampleBlock;
using particlemesh::detail::prove_block;
using particlemesh::detail::sample_block_spherical;

namespace {

/// A jittered simple cubic block of k x 2k x k particles of spacing s (a settled fluid).
PointCloud packed_block(int k, double s, uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(-0.05, 0.05);
  PointCloud c;
  for (int z = 0; z < k; ++z)
    for (int y = 0; y < 2 * k; ++y)
      for (int x = 0; x < k; ++x) c.positions.push_back({(x + u(rng)) * s, (y + u(rng)) * s, (z + u(rng)) * s});
  return c;
}

template <class T>
bool same_bytes(const std::vector<T>& a, const std::vector<T>& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(T)) == 0;
}

/// Polygonize with the proofs (as given) and without (the far negative particle), and
/// compare. Returns the stats with proofs.
PolygonizeStats expect_same_mesh_as_sampling_everything(const PointCloud& c, PolygonizeOptions o,
                                                        const std::string& what) {
  SCOPED_TRACE(what);
  const PolygonizeResult with = polygonize(c, o);
  PointCloud ref = c;
  Vec3 far = c.positions[0];
  for (const Vec3& p : c.positions) far.x = std::max(far.x, p.x);
  const double reach = o.radii.empty() ? with.stats.max_radius : *std::max_element(o.radii.begin(), o.radii.end());
  far.x += 10 * reach + 1;
  ref.positions.push_back(far);
  if (o.strengths.empty()) o.strengths.assign(c.size(), 1.0);
  o.strengths.push_back(-1e-300);
  if (!o.radii.empty()) o.radii.push_back(o.radii.back());
  o.threshold = with.stats.threshold;
  o.radius = with.stats.radius;
  o.cell_size = with.stats.cell_size;
  const PolygonizeResult without = polygonize(ref, o);
  EXPECT_EQ(without.stats.inside_blocks + without.stats.outside_blocks, 0u);
  EXPECT_EQ(with.mesh.triangles, without.mesh.triangles);
  EXPECT_TRUE(same_bytes(with.mesh.positions, without.mesh.positions));
  EXPECT_TRUE(same_bytes(with.mesh.normals, without.mesh.normals));
  EXPECT_GT(with.mesh.triangles.size(), 0u);
  return with.stats;
}

}  // namespace

TEST(PolygonizeProofs, PackedBlocksSampleOnlyNearTheSurfaceAndMeshAsBefore) {
  const PointCloud c = packed_block(20, 0.02, 7);
  for (Kernel k : {Kernel::Wyvill, Kernel::Poly4, Kernel::Poly6}) {
    PolygonizeOptions o;
    o.kernel = k;
    o.radius = 0.04;
    o.cell_size = 0.01;
    const PolygonizeStats st = expect_same_mesh_as_sampling_everything(c, o, kernel_name(k));
    // Most of the block's interior is proven inside and never sampled.
    EXPECT_GT(st.inside_blocks, st.reached_blocks / 5) << kernel_name(k);
    EXPECT_EQ(st.sampled_blocks + st.inside_blocks + st.outside_blocks, st.reached_blocks);
    EXPECT_LT(st.sampled_blocks, st.reached_blocks);
  }
  // Finer cells (more blocks per radius) and the default radius and threshold.
  PolygonizeOptions fine;
  fine.cell_size = 0.005;
  expect_same_mesh_as_sampling_everything(c, fine, "default radius, h = R / 8");
  // A threshold just under the packed field: the bounds are tested close to T everywhere.
  PolygonizeOptions tight;
  tight.radius = 0.04;
  tight.threshold = 0.8 * lattice_field(Kernel::Wyvill, 0.04, 0.02);
  expect_same_mesh_as_sampling_everything(c, tight, "threshold near the packed field");
}

TEST(PolygonizeProofs, PerParticleRadiiStrengthsAndThreads) {
  const PointCloud c = packed_block(14, 0.02, 3);
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> u(0.035, 0.045), w(0.5, 1.5);
  PolygonizeOptions o;
  o.cell_size = 0.01;
  for (size_t i = 0; i < c.size(); ++i) {
    o.radii.push_back(u(rng));
    o.strengths.push_back(w(rng));
  }
  o.threshold = 3.0;
  const PolygonizeStats st = expect_same_mesh_as_sampling_everything(c, o, "per-particle radii and strengths");
  EXPECT_GT(st.inside_blocks, 0u);
  // Any thread count: the same mesh.
  o.threads = 1;
  const PolygonizeResult one = polygonize(c, o);
  o.threads = 0;
  const PolygonizeResult all = polygonize(c, o);
  EXPECT_EQ(one.mesh.triangles, all.mesh.triangles);
  EXPECT_TRUE(same_bytes(one.mesh.positions, all.mesh.positions));
}

TEST(PolygonizeProofs, SphFramesMeshAsBefore) {
  // splashsurf's parameters (particle radius r = 0.025), then the library's defaults: splashes
  // and thin films, where most proven blocks are outside.
  for (const char* name : {"particles/double_dam_break_frame_26_4732_particles.ply",
                           "particles/bunny_frame_14_7705_particles.ply", "particles/cube_2366_particles.ply"}) {
    PM_REQUIRE_DATA(path, name);
    const PointCloud c = read_point_cloud(path);
    const double r = 0.025;
    PolygonizeOptions o;
    o.radius = 4 * r;
    o.cell_size = 0.5 * r;
    o.threshold = 0.6 * lattice_field(Kernel::Wyvill, 4 * r, 2 * r);
    const PolygonizeStats st = expect_same_mesh_as_sampling_everything(c, o, name);
    EXPECT_GT(st.inside_blocks + st.outside_blocks, st.reached_blocks / 4) << name;
    expect_same_mesh_as_sampling_everything(c, PolygonizeOptions{}, std::string(name) + ", defaults");
  }
}

TEST(PolygonizeProofs, AnisotropicKernelsAndBlinnAreSampledWhole) {
  // The proofs need spherical kernels; the inside proof a polynomial one.
  const PointCloud c = packed_block(10, 0.02, 9);
  PolygonizeOptions o;
  o.radius = 0.04;
  o.anisotropy.enabled = true;
  PolygonizeResult r = polygonize(c, o);
  EXPECT_EQ(r.stats.sampled_blocks, r.stats.reached_blocks);
  o.anisotropy.enabled = false;
  o.kernel = Kernel::Blinn;
  r = polygonize(c, o);
  EXPECT_EQ(r.stats.inside_blocks, 0u);
  EXPECT_GT(r.mesh.triangles.size(), 0u);
}

// ---- the proofs themselves, against every node's sample ------------------------------------

TEST(PolygonizeProofs, EveryProofHoldsAtEveryNode) {
  // Blocks all over clouds of several kinds, radii, cells and thresholds: where a block is
  // proven inside, every node's float sample is >= T; where outside, every one is < T. And
  // the proofs do prove most of a packed block's interior.
  struct Case {
    std::string name;
    PointCloud cloud;
    double radius, cell, threshold_fraction;
  };
  std::vector<Case> cases;
  PointCloud holes = packed_block(12, 1.0, 2);  // a packed block with a few small voids
  std::erase_if(holes.positions, [](const Vec3& p) {
    return distance(p, Vec3{6, 12, 6}) < 1.6 || distance(p, Vec3{4, 5, 7}) < 1.2 || distance(p, Vec3{8, 18, 3}) < 1.0;
  });
  cases.push_back({"packed with voids", holes, 2.0, 0.5, 0.5});
  cases.push_back({"packed, fine cells", packed_block(10, 1.0, 4), 2.0, 0.25, 0.5});
  cases.push_back({"packed, large radius", packed_block(10, 1.0, 5), 3.5, 0.5, 0.45});
  cases.push_back({"random", test::random_cloud(3000, 3, 14.0), 2.0, 0.5, 0.3});
  cases.push_back({"random, low threshold", test::random_cloud(1500, 4, 14.0), 1.5, 0.4, 0.1});
  size_t proven_inside = 0, proven_outside = 0, checked = 0;
  for (const Case& k : cases)
    for (Kernel kernel : {Kernel::Wyvill, Kernel::Poly4, Kernel::Poly6}) {
      FieldParams p;
      p.kernel = kernel;
      p.radius = k.radius;
      p.threshold = k.threshold_fraction * lattice_field(kernel, k.radius, 1.0);
      const ParticleField f(k.cloud, p);
      const double T = f.threshold(), h = k.cell;
      const Vec3 lo = f.support_min(), hi = f.support_max();
      // Blocks at an offset that is no multiple of the cell, to meet particles anywhere.
      std::vector<float> samples(size_t(kSampleBlock) * kSampleBlock * kSampleBlock);
      for (double z = lo.z - 0.37 * h; z < hi.z; z += 7 * h)
        for (double y = lo.y - 0.61 * h; y < hi.y; y += 7 * h)
          for (double x = lo.x - 0.13 * h; x < hi.x; x += 7 * h) {
            const Vec3 first{x, y, z};
            const BlockProof proof = prove_block(f, first, h);
            // Without the inside proof (polygonize's blocks beside one no support reaches):
            // the same outside proofs, no inside one.
            ASSERT_EQ(prove_block(f, first, h, false), proof == BlockProof::Inside ? BlockProof::None : proof);
            if (proof == BlockProof::None) continue;
            sample_block_spherical(f, first, h, samples.data());
            ++checked;
            for (float v : samples) {
              if (proof == BlockProof::Inside) {
                ASSERT_GE(double(v), T) << k.name << ", " << kernel_name(kernel) << " at " << x << " " << y << " " << z;
              } else {
                ASSERT_LT(double(v), T) << k.name << ", " << kernel_name(kernel) << " at " << x << " " << y << " " << z;
              }
            }
            (proof == BlockProof::Inside ? proven_inside : proven_outside) += 1;
          }
    }
  EXPECT_GT(proven_inside, 50u);
  EXPECT_GT(proven_outside, 50u);
  EXPECT_EQ(checked, proven_inside + proven_outside);

  // Tight cases for the upper bound: one particle on a node, T just under its peak (the bound
  // is exact there), and just over it (nothing reaches T).
  PointCloud one;
  one.positions = {{0, 0, 0}};
  for (double fraction : {0.999, 1.001}) {
    FieldParams p;
    p.radius = 2.0;
    p.threshold = fraction;
    const ParticleField f(one, p);
    const double h = 0.5;
    std::vector<float> samples(size_t(kSampleBlock) * kSampleBlock * kSampleBlock);
    const Vec3 first{-3 * h, -2 * h, -5 * h};  // the particle is node (3, 2, 5)
    const BlockProof proof = prove_block(f, first, h);
    sample_block_spherical(f, first, h, samples.data());
    const double top = *std::max_element(samples.begin(), samples.end());
    EXPECT_EQ(top, 1.0);
    EXPECT_EQ(proof, fraction < 1 ? BlockProof::None : BlockProof::Outside) << fraction;
  }
}
