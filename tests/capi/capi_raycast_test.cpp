// The ray-casting C ABI: the same hits as the C++ API, first-hit and all-hits
// batches with query-then-copy, CSG, and statuses + messages for misuse, with outputs
// untouched on failure.
#include "particlemesh/particlemesh.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstddef>
#include <string>
#include <vector>

#include "particlemesh/volume/ray_csg.h"
#include "particlemesh/volume/raycast.h"
#include "support/test_support.h"

using namespace particlemesh;

namespace {

std::string last() { return pm_last_error_message(); }

struct Field {
  pm_cloud* cloud = nullptr;
  pm_field* field = nullptr;
  Field(const std::vector<double>& pos, int32_t kernel, double radius, double threshold,
        const double* strengths = nullptr) {
    EXPECT_EQ(pm_cloud_create(pos.data(), nullptr, pos.size() / 3, &cloud), PM_OK);
    pm_field_options o;
    pm_field_options_init(&o);
    o.kernel = kernel;
    o.radius = radius;
    o.threshold = threshold;
    EXPECT_EQ(pm_field_create(cloud, nullptr, strengths, &o, &field), PM_OK) << last();
  }
  ~Field() {
    pm_field_destroy(field);
    pm_cloud_destroy(cloud);
  }
};

// Rays through the middle of a 2 x 2 x 2 box from all around.
void rays(size_t n, std::vector<double>* o, std::vector<double>* d) {
  for (size_t i = 0; i < n; ++i) {
    const double a = 0.37 * double(i), b = 0.11 * double(i);
    const double dx = std::cos(a) * std::cos(b), dy = std::sin(b), dz = std::sin(a) * std::cos(b);
    const double off = 0.02 * double(i % 40);
    o->insert(o->end(), {1 - 6 * dx + off * dz, 1 - 6 * dy, 1 - 6 * dz - off * dx});
    d->insert(d->end(), {dx, dy, dz});
  }
}

}  // namespace

TEST(CapiRaycast, BatchesMatchTheCppApi) {
  const PointCloud c = test::random_cloud(200, 4, 2.0);
  std::vector<double> pos;
  for (const Vec3& p : c.positions) pos.insert(pos.end(), {p.x, p.y, p.z});
  Field f(pos, PM_KERNEL_POLY6, 0.5, 0.6);
  double R = 0, T = 0;
  ASSERT_EQ(pm_field_get_params(f.field, &R, &T), PM_OK);
  EXPECT_EQ(R, 0.5);
  EXPECT_EQ(T, 0.6);
  FieldParams fp;
  fp.kernel = Kernel::Poly6;
  fp.radius = 0.5;
  fp.threshold = 0.6;
  const RayCaster caster(ParticleField(c, fp));

  std::vector<double> o, d;
  const size_t n = 300;
  rays(n, &o, &d);
  std::vector<double> t(n), P(3 * n), N(3 * n);
  std::vector<int32_t> ent(n);
  size_t hit_count = 0;
  ASSERT_EQ(pm_raycast_first(f.field, o.data(), d.data(), n, nullptr, t.data(), P.data(), N.data(), ent.data(),
                             &hit_count),
            PM_OK)
      << last();
  EXPECT_GT(hit_count, n / 4);
  pm_ray_hits* all = nullptr;
  ASSERT_EQ(pm_raycast_all(f.field, o.data(), d.data(), n, nullptr, &all), PM_OK) << last();
  size_t rc = 0, hc = 0;
  ASSERT_EQ(pm_ray_hits_get_counts(all, &rc, &hc), PM_OK);
  EXPECT_EQ(rc, n);
  std::vector<uint64_t> off(n + 1);
  std::vector<double> at(hc), ap(3 * hc), an(3 * hc);
  std::vector<int32_t> ae(hc), si(n);
  ASSERT_EQ(pm_ray_hits_copy_offsets(all, off.data(), off.size()), PM_OK);
  ASSERT_EQ(pm_ray_hits_copy(all, at.data(), ap.data(), an.data(), ae.data(), hc), PM_OK);
  ASSERT_EQ(pm_ray_hits_copy_starts_inside(all, si.data(), n), PM_OK);
  EXPECT_EQ(off[n], hc);
  size_t hits_seen = 0;
  for (size_t i = 0; i < n; ++i) {
    const Vec3 oi{o[3 * i], o[3 * i + 1], o[3 * i + 2]}, di{d[3 * i], d[3 * i + 1], d[3 * i + 2]};
    const RayHits h = caster.all_hits(oi, di);
    ASSERT_EQ(off[i + 1] - off[i], h.hits.size()) << i;
    EXPECT_EQ(si[i], h.starts_inside ? 1 : 0);
    for (size_t k = 0; k < h.hits.size(); ++k) {
      const size_t j = off[i] + k;
      EXPECT_EQ(at[j], h.hits[k].t);
      EXPECT_EQ(ap[3 * j + 1], h.hits[k].position.y);
      EXPECT_EQ(an[3 * j + 2], h.hits[k].normal.z);
      EXPECT_EQ(ae[j], h.hits[k].entering ? 1 : 0);
    }
    if (h.hits.empty()) {
      EXPECT_TRUE(std::isinf(t[i]));
      EXPECT_EQ(P[3 * i], 0.0);
    } else {
      ++hits_seen;
      EXPECT_EQ(t[i], h.hits[0].t);
      EXPECT_EQ(P[3 * i], h.hits[0].position.x);
      EXPECT_EQ(N[3 * i + 1], h.hits[0].normal.y);
      EXPECT_EQ(ent[i], 1);
    }
  }
  EXPECT_EQ(hits_seen, hit_count);
  // Values of F through the ABI.
  double v = 0;
  ASSERT_EQ(pm_field_values(f.field, ap.data(), 1, &v), PM_OK);
  EXPECT_NEAR(v, 0.6, 1e-9);
  pm_ray_hits_destroy(all);
}

// pm_field_options' appended anisotropy fields: the same ellipsoidal field as the C++ API,
// off by default and for callers with the older, shorter struct.
TEST(CapiRaycast, AnisotropicField) {
  const PointCloud c = test::random_cloud(600, 5, 2.0);
  std::vector<double> pos;
  for (const Vec3& p : c.positions) pos.insert(pos.end(), {p.x, p.y, p.z});
  pm_cloud* cloud = nullptr;
  ASSERT_EQ(pm_cloud_create(pos.data(), nullptr, c.size(), &cloud), PM_OK);
  pm_field_options o;
  pm_field_options_init(&o);
  EXPECT_EQ(o.anisotropic, 0);
  EXPECT_EQ(o.aniso_max_stretch, AnisotropyOptions{}.max_stretch);
  o.radius = 0.4;
  o.anisotropic = 1;
  o.aniso_smoothing = 0.25;
  pm_field* f = nullptr;
  ASSERT_EQ(pm_field_create(cloud, nullptr, nullptr, &o, &f), PM_OK) << last();
  double T = 0;
  ASSERT_EQ(pm_field_get_params(f, nullptr, &T), PM_OK);
  FieldParams fp;
  fp.radius = 0.4;
  fp.anisotropy.enabled = true;
  fp.anisotropy.smoothing = 0.25;
  const RayCaster caster(ParticleField(c, fp));
  EXPECT_GT(caster.field().anisotropic_count(), c.size() / 2);
  EXPECT_EQ(T, caster.field().threshold());
  std::vector<double> ro, rd;
  const size_t n = 200;
  rays(n, &ro, &rd);
  std::vector<double> t(n);
  size_t hits = 0;
  ASSERT_EQ(pm_raycast_first(f, ro.data(), rd.data(), n, nullptr, t.data(), nullptr, nullptr, nullptr, &hits), PM_OK);
  EXPECT_GT(hits, n / 4);
  for (size_t i = 0; i < n; ++i) {
    const auto h = caster.first_hit({ro[3 * i], ro[3 * i + 1], ro[3 * i + 2]}, {rd[3 * i], rd[3 * i + 1], rd[3 * i + 2]});
    EXPECT_EQ(t[i], h ? h->t : INFINITY) << i;
  }
  pm_field_destroy(f);
  // The older struct: spherical kernels.
  o.struct_size = uint32_t(offsetof(pm_field_options, progress_user_data) + sizeof(void*));
  o.threshold = 1.0;
  ASSERT_EQ(pm_field_create(cloud, nullptr, nullptr, &o, &f), PM_OK) << last();
  fp.anisotropy.enabled = false;
  fp.threshold = 1.0;
  const RayCaster iso(ParticleField(c, fp));
  ASSERT_EQ(pm_raycast_first(f, ro.data(), rd.data(), n, nullptr, t.data(), nullptr, nullptr, nullptr, &hits), PM_OK);
  for (size_t i = 0; i < n; ++i) {
    const auto h = iso.first_hit({ro[3 * i], ro[3 * i + 1], ro[3 * i + 2]}, {rd[3 * i], rd[3 * i + 1], rd[3 * i + 2]});
    EXPECT_EQ(t[i], h ? h->t : INFINITY) << i;
  }
  pm_field_destroy(f);
  o.struct_size = sizeof(o);
  o.aniso_min_neighbors = -1;
  f = reinterpret_cast<pm_field*>(0x1);
  EXPECT_EQ(pm_field_create(cloud, nullptr, nullptr, &o, &f), PM_STATUS_INVALID_ARGUMENT);
  EXPECT_NE(last().find("min_neighbors"), std::string::npos) << last();
  EXPECT_EQ(f, reinterpret_cast<pm_field*>(0x1));
  pm_cloud_destroy(cloud);
}

TEST(CapiRaycast, CsgOfAFieldWithItself) {
  std::vector<double> pos = {0, 0, 0, 0.8, 0, 0, 0.3, 0.5, 0};
  Field f(pos, PM_KERNEL_WYVILL, 1.0, 0.7);
  std::vector<double> o, d;
  rays(50, &o, &d);
  pm_ray_hits* un = nullptr;
  pm_ray_hits* di = nullptr;
  pm_ray_hits* alone = nullptr;
  ASSERT_EQ(pm_raycast_csg(f.field, f.field, PM_CSG_UNION, o.data(), d.data(), 50, nullptr, &un), PM_OK) << last();
  ASSERT_EQ(pm_raycast_csg(f.field, f.field, PM_CSG_DIFFERENCE, o.data(), d.data(), 50, nullptr, &di), PM_OK);
  ASSERT_EQ(pm_raycast_all(f.field, o.data(), d.data(), 50, nullptr, &alone), PM_OK);
  size_t a = 0, b = 0, c = 0, rc = 0;
  pm_ray_hits_get_counts(un, &rc, &a);
  pm_ray_hits_get_counts(di, &rc, &b);
  pm_ray_hits_get_counts(alone, &rc, &c);
  EXPECT_EQ(a, c);  // A ∪ A = A
  EXPECT_GT(a, 0u);
  EXPECT_EQ(b, 0u);  // A − A = ∅
  pm_ray_hits* bad = nullptr;
  EXPECT_EQ(pm_raycast_csg(f.field, f.field, 5, o.data(), d.data(), 50, nullptr, &bad), PM_STATUS_INVALID_ARGUMENT);
  EXPECT_NE(last().find("op is 5"), std::string::npos);
  EXPECT_EQ(bad, nullptr);
  pm_ray_hits_destroy(un);
  pm_ray_hits_destroy(di);
  pm_ray_hits_destroy(alone);
}

TEST(CapiRaycast, MisuseGivesStatusesAndLeavesOutputsAlone) {
  std::vector<double> pos = {0, 0, 0};
  Field f(pos, PM_KERNEL_POLY4, 1.0, 0.5);
  std::vector<double> o = {0, 0, -3, 0, 0, -3}, d = {0, 0, 1, 0, 0, 0};
  double t[2] = {-7, -7};
  EXPECT_EQ(pm_raycast_first(f.field, o.data(), d.data(), 2, nullptr, t, nullptr, nullptr, nullptr, nullptr),
            PM_STATUS_INVALID_ARGUMENT);
  EXPECT_NE(last().find("directions[1] is zero"), std::string::npos) << last();
  EXPECT_EQ(t[0], -7);
  EXPECT_EQ(pm_raycast_first(nullptr, o.data(), d.data(), 1, nullptr, t, nullptr, nullptr, nullptr, nullptr),
            PM_STATUS_INVALID_ARGUMENT);
  EXPECT_NE(last().find("field is NULL"), std::string::npos);
  EXPECT_EQ(pm_raycast_first(f.field, nullptr, d.data(), 1, nullptr, t, nullptr, nullptr, nullptr, nullptr),
            PM_STATUS_INVALID_ARGUMENT);
  // Zero rays is fine with NULL arrays.
  EXPECT_EQ(pm_raycast_first(f.field, nullptr, nullptr, 0, nullptr, nullptr, nullptr, nullptr, nullptr, nullptr), PM_OK);
  pm_raycast_options ro;
  pm_raycast_options_init(&ro);
  EXPECT_TRUE(std::isinf(ro.t_max));
  ro.t_min = 5;
  ro.t_max = 1;
  EXPECT_EQ(pm_raycast_first(f.field, o.data(), d.data(), 1, &ro, t, nullptr, nullptr, nullptr, nullptr),
            PM_STATUS_INVALID_ARGUMENT);
  ro.struct_size = 0;
  EXPECT_EQ(pm_raycast_first(f.field, o.data(), d.data(), 1, &ro, t, nullptr, nullptr, nullptr, nullptr),
            PM_STATUS_INVALID_ARGUMENT);
  EXPECT_NE(last().find("struct_size"), std::string::npos);
  // An older, shorter options struct (only t_min) keeps working.
  pm_raycast_options_init(&ro);
  ro.struct_size = offsetof(pm_raycast_options, t_max);
  ro.t_min = 0;
  EXPECT_EQ(pm_raycast_first(f.field, o.data(), d.data(), 1, &ro, t, nullptr, nullptr, nullptr, nullptr), PM_OK);
  EXPECT_NEAR(t[0], 3 - std::sqrt(1 - std::sqrt(0.5)), 1e-12);  // Poly4: rs^2 = 1 - sqrt(T)
  // Cancelling from the progress callback.
  pm_raycast_options_init(&ro);
  ro.progress = [](void*, const char*, double) { return 1; };
  EXPECT_EQ(pm_raycast_first(f.field, o.data(), d.data(), 1, &ro, t, nullptr, nullptr, nullptr, nullptr),
            PM_STATUS_CANCELLED);
  // Copies too small.
  pm_ray_hits* h = nullptr;
  ASSERT_EQ(pm_raycast_all(f.field, o.data(), d.data(), 1, nullptr, &h), PM_OK);
  uint64_t off[1] = {99};
  EXPECT_EQ(pm_ray_hits_copy_offsets(h, off, 1), PM_STATUS_INVALID_ARGUMENT);
  EXPECT_EQ(off[0], 99u);
  double ht[1];
  EXPECT_EQ(pm_ray_hits_copy(h, ht, nullptr, nullptr, nullptr, 1), PM_STATUS_INVALID_ARGUMENT);
  EXPECT_NE(last().find("hit_count = 2"), std::string::npos) << last();
  pm_ray_hits_destroy(h);
  pm_ray_hits_destroy(nullptr);
  pm_field_destroy(nullptr);
  // Field creation errors.
  pm_field* ff = nullptr;
  pm_field_options fo;
  pm_field_options_init(&fo);
  fo.kernel = 9;
  EXPECT_EQ(pm_field_create(f.cloud, nullptr, nullptr, &fo, &ff), PM_STATUS_INVALID_ARGUMENT);
  EXPECT_EQ(ff, nullptr);
  fo.kernel = PM_KERNEL_WYVILL;  // default radius needs two distinct particles
  EXPECT_NE(pm_field_create(f.cloud, nullptr, nullptr, &fo, &ff), PM_OK);
  EXPECT_EQ(ff, nullptr);
}
