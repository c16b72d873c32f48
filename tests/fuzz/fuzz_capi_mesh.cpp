// Fuzz target: the C ABI's mesh entry points fed arbitrary arrays and parameter structs:
// pm_mesh_create (indices out of range, NaN positions or normals, degenerate, repeated and
// non-manifold triangles), pm_mesh_report, pm_mesh_ray_crossings (points anywhere, also on
// the vertices; the counts of two halves of the triangles add up), the copy functions with any capacity, attributes
// (pm_mesh_set_attribute / _get_attribute_* / _copy_attribute), corner attributes (the same
// calls' corner forms; carried by pm_smooth: finite, 3 x components per output triangle) and
// pm_triangle_edges on the raw triangles (any capacity), and pm_smooth with every option
// field fuzzed (scheme, levels, boundary, creases with any indices and sharpness, struct_size,
// a progress callback that may cancel). Checks: statuses and messages, outputs untouched on
// failure, a smoothed mesh has F x 4^levels triangles indexing its own finite vertices.
//
// Inputs stay small (at most 32 vertices, 48 triangles, results capped at 2^14 triangles).
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <string>
#include <vector>

#include "fuzz_support.h"

using namespace particlemesh;
using fuzz::check_status;

namespace {

struct Cancel {
  int calls = 0;
  int cancel_at = -1;
};

int progress(void* user, const char* stage, double fraction) {
  // A struct_size that covers `progress` but not `progress_user_data` gives NULL here.
  if (user == nullptr) return 0;
  auto* c = static_cast<Cancel*>(user);
  PM_FUZZ_CHECK(stage != nullptr);
  PM_FUZZ_CHECK(fraction >= 0 && fraction <= 1);
  return ++c->calls == c->cancel_at ? 1 : 0;
}

void check_mesh(const pm_mesh* mesh, size_t* out_nv = nullptr, size_t* out_nt = nullptr) {
  size_t nv = 0, nt = 0;
  check_status(pm_mesh_get_counts(mesh, &nv, &nt));
  std::vector<int32_t> tris(3 * nt + 3);
  check_status(pm_mesh_copy_triangles(mesh, tris.data(), nt));
  for (size_t i = 0; i < 3 * nt; ++i) PM_FUZZ_CHECK(tris[i] >= 0 && size_t(tris[i]) < nv);
  std::vector<double> pos(3 * nv + 3);
  check_status(pm_mesh_copy_positions(mesh, pos.data(), nv));
  for (size_t i = 0; i < 3 * nv; ++i) PM_FUZZ_CHECK(std::isfinite(pos[i]));
  pm_topology_report r{};
  r.struct_size = sizeof(r);
  check_status(pm_mesh_report(mesh, &r));
  PM_FUZZ_CHECK(r.vertices == nv && r.triangles == nt);
  PM_FUZZ_CHECK(r.boundary_edges + r.manifold_edges + r.nonmanifold_edges == r.edges);
  if (out_nv) *out_nv = nv;
  if (out_nt) *out_nt = nt;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  fuzz::Input in(data, size);
  const uint8_t mode = in.take<uint8_t>();
  const size_t nv = size_t(in.range(0, 32));
  const size_t nt = size_t(in.range(0, 48));
  std::vector<double> pos(3 * nv), nrm;
  for (double& v : pos) v = in.number(0.25);
  if (mode & 1) {
    nrm.resize(3 * nv);
    for (double& v : nrm) v = in.number(0.5);
  }
  std::vector<int32_t> tris(3 * nt);
  for (int32_t& t : tris)
    t = (mode & 2) && in.take<uint8_t>() == 0xFF ? in.take<int32_t>()  // sometimes any index
                                                  : int32_t(nv ? in.range(0, nv - 1) : 0);

  // The edges of the raw triangle list (any index, repeated vertices), with an edge capacity
  // that may be too small: a good call numbers every corner's edge (a, b), a < b; a refused
  // one says why (a bad triangle, or the count needed). The numbering keeps its working
  // block from call to call (any size after any other).
  if (mode & 128) {
    std::vector<uint32_t> utris(tris.begin(), tris.end());
    const size_t cap = in.flag() ? 3 * nt : size_t(in.range(0, 3 * nt));
    std::vector<uint32_t> edges(2 * cap + 2, 77), corners(3 * nt + 1, 77);
    size_t count = 0;
    const pm_status e = pm_triangle_edges(nt ? utris.data() : nullptr, nt, nv, int32_t(in.range(0, 3)), edges.data(),
                                          cap, corners.data(), &count);
    check_status(e);
    bool valid = true;
    for (size_t t = 0; t < nt; ++t) {
      const uint32_t* T = utris.data() + 3 * t;
      valid = valid && T[0] < nv && T[1] < nv && T[2] < nv && T[0] != T[1] && T[1] != T[2] && T[0] != T[2];
    }
    if (e == PM_OK) {
      PM_FUZZ_CHECK(valid && count <= cap);
      for (size_t c = 0; c < 3 * nt; ++c) {
        const uint32_t a = utris[c], b = utris[c % 3 == 2 ? c - 2 : c + 1];
        PM_FUZZ_CHECK(corners[c] < count);
        PM_FUZZ_CHECK(edges[2 * corners[c]] == std::min(a, b) && edges[2 * corners[c] + 1] == std::max(a, b));
      }
      for (size_t i = 0; i + 1 < count; ++i)
        PM_FUZZ_CHECK(edges[2 * i] < edges[2 * i + 1] &&
                      (edges[2 * i] < edges[2 * i + 2] || (edges[2 * i] == edges[2 * i + 2] && edges[2 * i + 1] < edges[2 * i + 3])));
      PM_FUZZ_CHECK(corners[3 * nt] == 77);
    } else {
      PM_FUZZ_CHECK(!valid || count > cap);
    }
  }

  pm_mesh* mesh = reinterpret_cast<pm_mesh*>(0x1);
  pm_status s = pm_mesh_create(nv ? pos.data() : nullptr, nv, nt ? tris.data() : nullptr, nt,
                               (mode & 1) ? nrm.data() : nullptr, &mesh);
  check_status(s);
  if (s != PM_OK) {
    PM_FUZZ_CHECK(mesh == reinterpret_cast<pm_mesh*>(0x1));
    return 0;
  }
  size_t got_nv = 0, got_nt = 0;
  check_mesh(mesh, &got_nv, &got_nt);
  PM_FUZZ_CHECK(got_nv == nv && got_nt == nt);

  // Ray crossings: at most one per triangle, and the counts of the triangles cut into two
  // lists over the same vertices add up to the whole list's (every triangle's share its own).
  if (mode & 64) {
    const size_t nq = size_t(in.range(0, 6));
    std::vector<double> q(3 * nq);
    for (double& v : q) v = in.flag() ? pos.empty() ? 0.0 : pos[size_t(in.range(0, pos.size() - 1))] : in.number(0.25);
    std::vector<uint64_t> whole(nq + 1, 77), first(nq + 1, 77), second(nq + 1, 77);
    const pm_status w = pm_mesh_ray_crossings(mesh, nq ? q.data() : nullptr, nq, 0, whole.data());
    check_status(w);
    bool finite = true;
    for (double v : q) finite = finite && std::isfinite(v);
    PM_FUZZ_CHECK((w == PM_OK) == finite);
    if (w == PM_OK) {
      const size_t cut = size_t(in.range(0, nt));
      pm_mesh* part[2] = {nullptr, nullptr};
      check_status(pm_mesh_create(nv ? pos.data() : nullptr, nv, cut ? tris.data() : nullptr, cut, nullptr, &part[0]));
      check_status(pm_mesh_create(nv ? pos.data() : nullptr, nv, nt - cut ? tris.data() + 3 * cut : nullptr, nt - cut,
                                  nullptr, &part[1]));
      PM_FUZZ_CHECK(part[0] && part[1]);
      check_status(pm_mesh_ray_crossings(part[0], nq ? q.data() : nullptr, nq, 1, first.data()));
      check_status(pm_mesh_ray_crossings(part[1], nq ? q.data() : nullptr, nq, 2, second.data()));
      for (size_t i = 0; i < nq; ++i) PM_FUZZ_CHECK(whole[i] <= nt && first[i] + second[i] == whole[i]);
      PM_FUZZ_CHECK(whole[nq] == 77);
      pm_mesh_destroy(part[0]);
      pm_mesh_destroy(part[1]);
    } else {
      PM_FUZZ_CHECK(whole[0] == 77);  // untouched on failure
    }
  }

  // Copies with a capacity that may be too small (the buffer holds `capacity` items).
  {
    const size_t cap = size_t(in.range(0, nv + 1));
    std::vector<float> buf(3 * cap + 3, -7.0f);
    const pm_status c = pm_mesh_copy_normals_f32(mesh, buf.data(), cap);
    check_status(c);
    if (c != PM_OK) PM_FUZZ_CHECK(buf[0] == -7.0f);
    const pm_status p = pm_mesh_copy_positions_f32(mesh, buf.data(), cap);
    check_status(p);
    if (p == PM_OK) PM_FUZZ_CHECK(cap >= nv);
  }

  // Attributes.
  if (mode & 4) {
    const int32_t comps = int32_t(in.range(0, 6)) - 1;  // -1..5
    const size_t claimed = nv + size_t(in.range(0, 2)) - (nv ? 1 : 0);
    std::vector<float> values(claimed * size_t(std::max(comps, 0)));
    for (float& v : values) v = float(in.number(1.0));
    const pm_status a = pm_mesh_set_attribute(mesh, in.flag() ? "colour" : "", comps, values.data(), claimed);
    check_status(a);
    size_t count = 0;
    check_status(pm_mesh_get_attribute_count(mesh, &count));
    PM_FUZZ_CHECK(count == (a == PM_OK ? 1u : 0u));
    const char* name = nullptr;
    const pm_status g = pm_mesh_get_attribute_name(mesh, size_t(in.range(0, 2)), &name);
    check_status(g);
    if (g == PM_OK) PM_FUZZ_CHECK(name != nullptr && std::string(name) == "colour");
    int32_t c = 0;
    const pm_status gc = pm_mesh_get_attribute_components(mesh, "colour", &c);
    check_status(gc);
    if (gc == PM_OK) {
      PM_FUZZ_CHECK(c == comps);
      const size_t cap = size_t(in.range(0, nv + 1));
      std::vector<float> out(cap * size_t(c) + 1);
      check_status(pm_mesh_copy_attribute(mesh, "colour", out.data(), cap));
    }
  }

  // Corner attributes (texture coordinates): any count, any components, any values.
  int32_t corner_components = 0;
  if (mode & 32) {
    const int32_t comps = int32_t(in.range(0, 4)) - 1;  // -1..3
    const size_t claimed = nt + size_t(in.range(0, 2)) - (nt ? 1 : 0);
    std::vector<float> values(3 * claimed * size_t(std::max(comps, 0)));
    for (float& v : values) v = in.flag() ? float(in.number(1.0)) : float(in.range(0, 4));
    const pm_status a = pm_mesh_set_corner_attribute(mesh, "uv", comps, values.data(), claimed);
    check_status(a);
    size_t count = 9;
    check_status(pm_mesh_get_corner_attribute_count(mesh, &count));
    PM_FUZZ_CHECK(count == (a == PM_OK ? 1u : 0u));
    int32_t c = 0;
    const pm_status gc = pm_mesh_get_corner_attribute_components(mesh, "uv", &c);
    check_status(gc);
    PM_FUZZ_CHECK((gc == PM_OK) == (a == PM_OK));
    if (gc == PM_OK) {
      PM_FUZZ_CHECK(c == comps);
      corner_components = c;
      const size_t cap = size_t(in.range(0, nt + 1));
      std::vector<float> out(3 * cap * size_t(c) + 1, -7.0f);
      const pm_status cp = pm_mesh_copy_corner_attribute(mesh, "uv", out.data(), cap);
      check_status(cp);
      if (cp != PM_OK) PM_FUZZ_CHECK(out[0] == -7.0f);
    }
  }

  // Smoothing with fuzzed options.
  if (mode & 8) {
    pm_smooth_options opt;
    pm_smooth_options_init(&opt);
    const uint8_t which = in.take<uint8_t>();
    if (which & 1) opt.scheme = int32_t(in.range(0, 3)) - 1;
    opt.levels = (which & 2) ? int32_t(in.range(0, 14)) - 2 : int32_t(in.range(0, 2));
    if (which & 4) opt.limit = int32_t(in.range(0, 2));
    if (which & 8) opt.boundary = int32_t(in.range(0, 3)) - 1;
    if (which & 16) opt.crease_method = int32_t(in.range(0, 3)) - 1;
    if (which & 32) opt.threads = int32_t(in.range(0, 3)) - 1;
    opt.max_triangles = (which & 64) ? in.take<uint64_t>() % (1u << 15) : (1u << 14);
    std::vector<int32_t> crease_edges;
    std::vector<float> sharpness;
    if (which & 128) {
      const size_t nc = size_t(in.range(0, 6));
      for (size_t i = 0; i < 2 * nc; ++i)
        crease_edges.push_back(in.flag() ? in.take<int32_t>() : int32_t(nv ? in.range(0, nv - 1) : 0));
      for (size_t i = 0; i < nc; ++i) sharpness.push_back(float(in.number(1.0)));
      opt.crease_count = nc;
      opt.crease_edges = nc ? crease_edges.data() : nullptr;
      opt.crease_sharpness = in.flag() && nc ? sharpness.data() : nullptr;
    }
    const uint8_t size_mode = in.take<uint8_t>();
    if (size_mode % 8 == 1) opt.struct_size = uint32_t(in.range(0, sizeof(opt) + 8));
    // The 2^14 cap must hold whatever struct_size says: a short struct gets the default
    // max_triangles (2^25), so keep the levels it may read small as well.
    if (opt.struct_size < offsetof(pm_smooth_options, max_triangles) + sizeof(uint64_t)) opt.levels = std::min(opt.levels, 2);
    Cancel cancel;
    if ((size_mode & 8) && opt.struct_size >= offsetof(pm_smooth_options, progress_user_data) + sizeof(void*)) {  // (a struct_size cutting a pointer in two is refused)
      opt.progress = progress;
      opt.progress_user_data = &cancel;
      cancel.cancel_at = int(in.range(0, 8));
    }
    pm_mesh* smooth = reinterpret_cast<pm_mesh*>(0x3);
    const pm_status r = pm_smooth(mesh, (size_mode & 16) ? nullptr : &opt, &smooth);
    check_status(r);
    if (r == PM_OK) {
      size_t snv = 0, snt = 0;
      check_mesh(smooth, &snv, &snt);
      if (!(size_mode & 16) && opt.struct_size == sizeof(opt)) PM_FUZZ_CHECK(snt == nt << (2 * opt.levels));
      int32_t has = 0;
      check_status(pm_mesh_has_normals(smooth, &has));
      PM_FUZZ_CHECK(has == 1);
      if (corner_components > 0) {  // carried: finite, one set per output corner
        int32_t c = 0;
        check_status(pm_mesh_get_corner_attribute_components(smooth, "uv", &c));
        PM_FUZZ_CHECK(c == corner_components);
        std::vector<float> out(3 * snt * size_t(c) + 1);
        check_status(pm_mesh_copy_corner_attribute(smooth, "uv", out.data(), snt));
        for (size_t i = 0; i + 1 < out.size(); ++i) PM_FUZZ_CHECK(std::isfinite(out[i]));
      }
      pm_mesh_destroy(smooth);
    } else {
      PM_FUZZ_CHECK(smooth == reinterpret_cast<pm_mesh*>(0x3));
      if (r == PM_STATUS_CANCELLED) PM_FUZZ_CHECK(cancel.calls == cancel.cancel_at);
    }
  }
  pm_mesh_destroy(mesh);
  return 0;
}
