// Modified butterfly subdivision (Zorin, Schroeder & Sweldens 1996) through OpenMesh's
// ModifiedButterflyT. The scheme is linear in the vertex data and its stencils depend on the
// connectivity only, so attributes are interpolated by running the same subdivider on copies
// of the connectivity whose "points" hold three attribute channels each; the copies refine
// identically (checked) and run in parallel with the positions. The triangles come out in
// the order and layout Loop's do (children of control triangle f at 4f..4f+3, corners as in
// smooth/subdivide.h), rebuilt level by level from the faces OpenMesh splits in place.
#include <atomic>
#include <chrono>
#include <string>

#include <OpenMesh/Core/Mesh/TriMesh_ArrayKernelT.hh>
#include <OpenMesh/Tools/Subdivider/Uniform/ModifiedButterFlyT.hh>
#include <tbb/parallel_for.h>

#include "core/parallel.h"
#include "particlemesh/core/error.h"
#include "smooth/schemes.h"

namespace PM_NAMESPACE::detail {

namespace {

struct ButterflyTraits : public OpenMesh::DefaultTraits {
  typedef OpenMesh::Vec3d Point;  // doubles: the original vertices stay bit-exact
  typedef OpenMesh::Vec3d Normal;
};
using ButterflyMesh = OpenMesh::TriMesh_ArrayKernelT<ButterflyTraits>;
using Butterfly = OpenMesh::Subdivider::Uniform::ModifiedButterflyT<ButterflyMesh, double>;

using Clock = std::chrono::steady_clock;
double seconds_since(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }

/// Face f of an OpenMesh triangle mesh as its corners h, next(h), next(next(h)): its winding.
Triangle face_corners(const ButterflyMesh& m, size_t f) {
  auto h = m.halfedge_handle(ButterflyMesh::FaceHandle(int(f)));
  const int a = m.to_vertex_handle(h).idx();
  h = m.next_halfedge_handle(h);
  const int b = m.to_vertex_handle(h).idx();
  h = m.next_halfedge_handle(h);
  const int c = m.to_vertex_handle(h).idx();
  return {uint32_t(a), uint32_t(b), uint32_t(c)};
}

/// The children of each canonical triangle of the level before, in Loop's order and layout
/// (see SmoothResult::mesh in subdivide.h): a (a, ab, ca), b (ab, b, bc), c (ca, bc, c) and
/// the middle (bc, ca, ab). OpenMesh splits a face in place: it keeps face f as the middle
/// child and appends the three corner children as faces n + 3f .. n + 3f + 2, and original
/// vertices keep their indices; both are checked, as is every child's winding.
/// parent_face[i]: OpenMesh's face of parents[i]; child_face, when given, gets the same for
/// the children (the next level's parent_face).
std::vector<Triangle> canonical_children(const std::vector<Triangle>& parents, const std::vector<uint32_t>& parent_face,
                                         const ButterflyMesh& mesh, std::vector<uint32_t>* child_face) {
  const size_t n = parents.size();
  if (mesh.n_faces() != 4 * n) throw Error(Status::Internal, "butterfly: a level did not split every face in four");
  std::vector<Triangle> out(4 * n);
  if (child_face) child_face->assign(4 * n, 0);
  std::atomic<bool> bad{false};
  // The rotation of `t` that has vertex v at position `at`; bad when v is not a corner.
  auto rotated = [&](const Triangle& t, uint32_t v, int at) {
    for (int r = 0; r < 3; ++r)
      if (t[size_t(r)] == v) return Triangle{t[size_t((r - at + 3) % 3)], t[size_t((r - at + 4) % 3)], t[size_t((r - at + 5) % 3)]};
    bad = true;
    return t;
  };
  auto same_cycle = [](const Triangle& a, const Triangle& b) {
    for (int r = 0; r < 3; ++r)
      if (a[0] == b[size_t(r)] && a[1] == b[size_t((r + 1) % 3)] && a[2] == b[size_t((r + 2) % 3)]) return true;
    return false;
  };
  parallel_blocks(n, 4096, [&](size_t begin, size_t end) {
    for (size_t i = begin; i < end; ++i) {
      const Triangle& p = parents[i];
      const size_t f = parent_face[i];
      const Triangle* corner[3] = {nullptr, nullptr, nullptr};
      Triangle children[3];
      for (size_t k = 0; k < 3; ++k) {
        const Triangle& c = children[k] = face_corners(mesh, n + 3 * f + k);
        for (size_t j = 0; j < 3; ++j)
          if (c[0] == p[j] || c[1] == p[j] || c[2] == p[j]) {
            corner[j] = &c;
            if (child_face) (*child_face)[4 * i + j] = uint32_t(n + 3 * f + k);
          }
      }
      if (!corner[0] || !corner[1] || !corner[2]) {
        bad = true;
        continue;
      }
      const Triangle a = rotated(*corner[0], p[0], 0), b = rotated(*corner[1], p[1], 1), c = rotated(*corner[2], p[2], 2);
      const uint32_t ab = a[1], ca = a[2], bc = b[2];
      const Triangle middle{bc, ca, ab};
      if (b[0] != ab || c[0] != ca || c[1] != bc || !same_cycle(middle, face_corners(mesh, f))) bad = true;
      out[4 * i] = a;
      out[4 * i + 1] = b;
      out[4 * i + 2] = c;
      out[4 * i + 3] = middle;
      if (child_face) (*child_face)[4 * i + 3] = uint32_t(f);
    }
  });
  if (bad) throw Error(Status::Internal, "butterfly: OpenMesh split a face other than the way its children are ordered");
  return out;
}

}  // namespace

void butterfly_subdivide(const ControlMesh& control, const SmoothOptions& options,
                         ProgressTracker& progress, SmoothResult& out) {
  const size_t nv = control.positions.size(), nf = control.triangles.size();
  auto t0 = Clock::now();
  progress.stage("building the half-edge mesh (OpenMesh)", 0.05, 0.2);

  ButterflyMesh base;
  base.reserve(nv, nv + nf, nf);
  for (const auto& p : control.positions) base.add_vertex(OpenMesh::Vec3d(p.x, p.y, p.z));
  for (size_t f = 0; f < nf; ++f) {
    const Triangle& t = control.triangles[f];
    const auto fh = base.add_face(ButterflyMesh::VertexHandle(int(t[0])), ButterflyMesh::VertexHandle(int(t[1])),
                                  ButterflyMesh::VertexHandle(int(t[2])));
    if (!fh.is_valid())  // the control mesh is a checked manifold, so this is our bug
      throw Error(Status::Internal, "OpenMesh refused control triangle " + std::to_string(f) +
                                        " of the checked mesh");
  }

  // One mesh for the positions, one more per three attribute channels.
  int channels = 0;
  for (const auto& a : control.attributes) channels += a.components;
  const int extra = (channels + 2) / 3;
  std::vector<ButterflyMesh> meshes(size_t(1 + extra), base);
  base.clear();
  {
    int offset = 0;
    std::vector<double> flat(nv * size_t(channels));
    for (const auto& a : control.attributes) {
      for (size_t i = 0; i < nv; ++i)
        for (int j = 0; j < a.components; ++j)
          flat[i * size_t(channels) + size_t(offset + j)] = double(a.values[i * size_t(a.components) + size_t(j)]);
      offset += a.components;
    }
    for (int m = 0; m < extra; ++m)
      for (size_t i = 0; i < nv; ++i) {
        OpenMesh::Vec3d p(0, 0, 0);
        for (int j = 0; j < 3 && 3 * m + j < channels; ++j) p[j] = flat[i * size_t(channels) + size_t(3 * m + j)];
        meshes[size_t(1 + m)].set_point(ButterflyMesh::VertexHandle(int(i)), p);
      }
  }

  std::vector<Butterfly> subdividers(meshes.size());
  // OpenMesh's SubdividerT destructor calls the pure virtual cleanup() when still attached,
  // which terminates; detach explicitly on every exit, including a cancel (exception).
  struct DetachAll {
    std::vector<Butterfly>& s;
    ~DetachAll() {
      for (auto& x : s) x.detach();
    }
  } detach_all{subdividers};
  for (size_t m = 0; m < meshes.size(); ++m) subdividers[m].attach(meshes[m]);
  double total = 0, done = 0;
  for (int l = 1; l <= options.levels; ++l) total += double(nf) * double(uint64_t(1) << (2 * l));
  std::vector<Triangle> canonical = control.triangles;
  std::vector<uint32_t> face_of(nf), child_face;  // OpenMesh's face of each canonical triangle
  for (size_t f = 0; f < nf; ++f) face_of[f] = uint32_t(f);
  for (int l = 1; l <= options.levels; ++l) {
    const double w = double(nf) * double(uint64_t(1) << (2 * l));
    progress.stage("butterfly level " + std::to_string(l) + " of " + std::to_string(options.levels),
                   0.2 + 0.65 * done / total, 0.2 + 0.65 * (done + w) / total);
    done += w;
    tbb::parallel_for(size_t(0), meshes.size(), [&](size_t m) { subdividers[m](1); });
    if (l < options.levels) {
      canonical = canonical_children(canonical, face_of, meshes[0], &child_face);
      face_of.swap(child_face);
    }
    progress.check();
  }
  // The last level's order once the subdividers have let go of their per-edge points.
  for (auto& sub : subdividers) sub.detach();
  if (options.levels > 0) canonical = canonical_children(canonical, face_of, meshes[0], nullptr);
  out.stats.seconds_refine = seconds_since(t0);

  auto t1 = Clock::now();
  progress.stage("output", 0.85, 0.95);
  const ButterflyMesh& pm = meshes[0];
  const size_t n_out = pm.n_vertices();
  out.mesh.positions.resize(n_out);
  for (size_t i = 0; i < n_out; ++i) {
    const auto& p = pm.point(ButterflyMesh::VertexHandle(int(i)));
    out.mesh.positions[i] = {p[0], p[1], p[2]};
  }
  std::vector<uint32_t>().swap(face_of);
  out.mesh.triangles = std::move(canonical);
  std::vector<double> flat(n_out * size_t(channels));
  for (int m = 0; m < extra; ++m) {
    const ButterflyMesh& am = meshes[size_t(1 + m)];
    bool same = am.n_vertices() == n_out && am.n_faces() == pm.n_faces();
    for (size_t f = 0; same && f < pm.n_faces(); ++f) same = face_corners(am, f) == face_corners(pm, f);
    if (!same) throw Error(Status::Internal, "the butterfly attribute mesh refined differently from the positions");
    for (size_t i = 0; i < n_out; ++i) {
      const auto& p = am.point(ButterflyMesh::VertexHandle(int(i)));
      for (int j = 0; j < 3 && 3 * m + j < channels; ++j) flat[i * size_t(channels) + size_t(3 * m + j)] = p[j];
    }
  }
  out.mesh.attributes.clear();
  int offset = 0;
  for (const auto& a : control.attributes) {
    const size_t k = size_t(a.components);
    VertexAttribute o{a.name, a.components, std::vector<float>(n_out * k)};
    for (size_t i = 0; i < n_out; ++i)
      for (size_t j = 0; j < k; ++j) o.values[i * k + j] = float(flat[i * size_t(channels) + size_t(offset) + j]);
    offset += a.components;
    out.mesh.attributes.push_back(std::move(o));
  }
  out.stats.seconds_output = seconds_since(t1);
}

}  // namespace particlemesh::detail
