// Thinning (the add-on's coarse viewport preview): an even subset that still meshes as a surface.
#include "particlemesh/sample/thin.h"

#include <gtest/gtest.h>

#include <cmath>

#include "particlemesh/core/error.h"
#include "particlemesh/mesh/topology_report.h"
#include "particlemesh/sample/shapes.h"
#include "particlemesh/spatial/neighbor_grid.h"
#include "particlemesh/surface/reconstruct.h"
#include "particlemesh/spatial/local_spacing.h"
#include "particlemesh/spatial/spacing.h"
#include "support/test_support.h"

using namespace particlemesh;

namespace {

PointCloud jittered_sphere(size_t n, double sigma_in_spacings, uint64_t seed) {
  PointCloud c = fibonacci_sphere(n);
  const double r0 = estimate_spacing(c.positions.data(), c.size()).spacing;
  return test::jittered(std::move(c), sigma_in_spacings * r0, seed);
}

PointCloud subset(const PointCloud& c, const std::vector<uint32_t>& idx) {
  PointCloud out;
  for (uint32_t i : idx) {
    out.positions.push_back(c.positions[i]);
    if (c.has_normals()) out.normals.push_back(c.normals[i]);
  }
  return out;
}

}  // namespace

TEST(ThinPoints, KeptPointsAreApartAndCoverEveryDroppedOne) {
  const PointCloud c = jittered_sphere(20000, 0.1, 3);
  const double r0 = estimate_spacing(c.positions.data(), c.size()).spacing;
  const double rho = 2.5 * r0;
  const std::vector<uint32_t> kept = thin_points(c.positions.data(), c.size(), rho);
  ASSERT_FALSE(kept.empty());
  EXPECT_EQ(kept.front(), 0u);  // greedy in input order: the first point always stays
  EXPECT_TRUE(std::is_sorted(kept.begin(), kept.end()));
  // About one point per disk of radius rho/2..rho on the sphere: far fewer, not too few.
  EXPECT_LT(kept.size(), c.size() / 4);
  EXPECT_GT(kept.size(), c.size() / 25);

  // Kept points are at least rho apart; a dropped point has a kept point of lower index
  // closer than rho (which is why it was dropped, and which covers it).
  std::vector<Vec3> kp;
  for (uint32_t i : kept) kp.push_back(c.positions[i]);
  const NeighborGrid grid(kp.data(), kp.size(), rho);
  std::vector<char> is_kept(c.size(), 0);
  for (uint32_t i : kept) is_kept[i] = 1;
  size_t too_close = 0, unexplained = 0;
  for (uint32_t i = 0; i < c.size(); ++i) {
    bool lower_close = false;
    grid.for_each_within(c.positions[i], rho, [&](uint32_t s, double d2) {
      const uint32_t k = kept[grid.original_index(s)];
      if (k == i || d2 >= rho * rho) return;
      if (is_kept[i]) ++too_close;
      if (k < i) lower_close = true;
    });
    if (!is_kept[i] && !lower_close) ++unexplained;
  }
  EXPECT_EQ(too_close, 0u);
  EXPECT_EQ(unexplained, 0u);

  // Same points, same subset; duplicates of a kept point go.
  EXPECT_EQ(thin_points(c.positions.data(), c.size(), rho), kept);
  std::vector<Vec3> twice = c.positions;
  twice.insert(twice.end(), c.positions.begin(), c.positions.end());
  EXPECT_EQ(thin_points(twice.data(), twice.size(), rho), kept);
}

TEST(ThinPoints, ThinnedSphereStillMeshesAsOneClosedOutwardSphere) {
  for (double factor : {1.5, 2.0, 3.0}) {
    const PointCloud c = jittered_sphere(60000, 0.05, 11);
    const double r0 = estimate_spacing(c.positions.data(), c.size()).spacing;
    const PointCloud t = subset(c, thin_points(c.positions.data(), c.size(), factor * r0));
    const SurfaceResult r = reconstruct_surface(t);  // spacing, normals: estimated
    const TopologyReport rep = topology_report(r.mesh);
    const std::string what = "thinned by " + std::to_string(factor) + " spacings";
    EXPECT_EQ(rep.components, 1u) << what;
    EXPECT_EQ(rep.closed_components, 1u) << what;
    EXPECT_TRUE(rep.manifold) << what;
    EXPECT_TRUE(rep.outward) << what;
    EXPECT_EQ(rep.euler_characteristic, 2) << what;
    EXPECT_EQ(rep.vertices_used, t.size()) << what;
    for (const Vec3& p : r.mesh.positions) EXPECT_NEAR(norm(p), 1.0, 0.01) << what;
  }
}

TEST(ThinPoints, ThinCloudCarriesNormalsAndAttributes) {
  PointCloud c = fibonacci_sphere(3000);
  VertexAttribute id{"id", 2, {}};
  for (size_t i = 0; i < c.size(); ++i) id.values.insert(id.values.end(), {float(i), -float(i)});
  c.attributes.push_back(id);
  const double r0 = estimate_spacing(c.positions.data(), c.size()).spacing;
  const std::vector<uint32_t> kept = thin_points(c.positions.data(), c.size(), 2 * r0);
  const PointCloud t = thin_cloud(c, 2 * r0);
  ASSERT_EQ(t.size(), kept.size());
  ASSERT_EQ(t.normals.size(), kept.size());
  ASSERT_EQ(t.attributes.size(), 1u);
  EXPECT_EQ(t.attributes[0].name, "id");
  ASSERT_EQ(t.attributes[0].values.size(), 2 * kept.size());
  for (size_t k = 0; k < kept.size(); ++k) {
    EXPECT_EQ(t.positions[k], c.positions[kept[k]]);
    EXPECT_EQ(t.normals[k], c.normals[kept[k]]);
    EXPECT_EQ(t.attributes[0].values[2 * k], float(kept[k]));
    EXPECT_EQ(t.attributes[0].values[2 * k + 1], -float(kept[k]));
  }
  validate_point_cloud(t);
}

TEST(ThinPoints, BadArgumentsAreNamed) {
  const PointCloud c = fibonacci_sphere(100);
  for (double bad : {0.0, -1.0, double(NAN), double(INFINITY)}) {
    try {
      thin_points(c.positions.data(), c.size(), bad);
      ADD_FAILURE() << "min_distance " << bad << " accepted";
    } catch (const Error& e) {
      EXPECT_EQ(e.status(), Status::InvalidArgument);
      EXPECT_NE(std::string(e.what()).find("min_distance"), std::string::npos) << e.what();
    }
  }
  std::vector<Vec3> p = c.positions;
  p[7].y = NAN;
  try {
    thin_points(p.data(), p.size(), 0.1);
    ADD_FAILURE() << "NaN accepted";
  } catch (const Error& e) {
    EXPECT_EQ(e.status(), Status::InvalidInput);
    EXPECT_NE(std::string(e.what()).find("point 7"), std::string::npos) << e.what();
  }
  EXPECT_TRUE(thin_points(nullptr, 0, 0.1).empty());
}

TEST(ThinPoints, PerPointDistancesThinEachRegionByItsOwnSpacing) {
  // Two halves of a sphere, one 2.8 times sparser, thinned by twice each point's own local
  // spacing: both halves keep about the same share of their points (one distance for all
  // would thin the dense half to the sparse one's spacing and leave the sparse one whole),
  // and every dropped point has a kept point of lower index within its own distance.
  PointCloud c;
  for (const Vec3& p : fibonacci_sphere(20000).positions)
    if (p.z < 0) c.positions.push_back(p);
  const size_t dense = c.size();
  for (const Vec3& p : fibonacci_sphere(2500).positions)
    if (p.z >= 0) c.positions.push_back(p);
  LocalSpacing ls = estimate_local_spacing(c.positions.data(), c.size());
  for (double& h : ls.spacing) h *= 2;
  const std::vector<uint32_t> kept = thin_points(c.positions.data(), c.size(), ls.spacing);
  size_t kept_dense = 0;
  for (uint32_t i : kept) kept_dense += i < dense;
  const double share_dense = double(kept_dense) / double(dense);
  const double share_sparse = double(kept.size() - kept_dense) / double(c.size() - dense);
  EXPECT_GT(share_dense, 0.15);
  EXPECT_LT(share_dense, 0.4);
  EXPECT_NEAR(share_sparse / share_dense, 1.0, 0.35);
  std::vector<char> is_kept(c.size(), 0);
  for (uint32_t i : kept) is_kept[i] = 1;
  for (uint32_t i = 0; i < c.size(); ++i) {
    bool covered = is_kept[i] != 0;
    for (uint32_t k : kept)
      if (k < i && distance(c.positions[k], c.positions[i]) < ls.spacing[i]) covered = true;
    ASSERT_TRUE(covered) << i;
  }
  const std::vector<double> wrong(3, 1.0);
  EXPECT_THROW(thin_points(c.positions.data(), c.size(), wrong), Error);
  std::vector<double> bad(c.size(), 1.0);
  bad[7] = 0;
  EXPECT_THROW(thin_points(c.positions.data(), c.size(), bad), Error);
}
