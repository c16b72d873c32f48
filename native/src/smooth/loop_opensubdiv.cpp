// Loop subdivision through OpenSubdiv: Far::TopologyRefiner refines the connectivity once,
// Far::PrimvarRefiner interpolates positions and every attribute channel through it, and
// PrimvarRefiner::Limit evaluates exact limit positions, tangents and attributes.
#include <chrono>
#include <cstring>
#include <memory>
#include <string>

#include <opensubdiv/far/primvarRefiner.h>
#include <opensubdiv/far/topologyDescriptor.h>
#include <opensubdiv/far/topologyRefiner.h>
#include <opensubdiv/far/topologyRefinerFactory.h>
#include <tbb/parallel_invoke.h>

#include "core/huge_pages.h"
#include "core/parallel.h"
#include "particlemesh/core/error.h"
#include "smooth/loop_limit.h"
#include "smooth/loop_refiner.h"
#include "smooth/schemes.h"

namespace PM_NAMESPACE::detail {

namespace {

using OpenSubdiv::Far::TopologyDescriptor;
using OpenSubdiv::Far::TopologyRefiner;
using RefinerFactory = OpenSubdiv::Far::TopologyRefinerFactory<TopologyDescriptor>;
using PrimvarRefiner = OpenSubdiv::Far::PrimvarRefinerReal<double>;
namespace Sdc = OpenSubdiv::Sdc;

using Clock = std::chrono::steady_clock;
double seconds_since(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }

/// A position as PrimvarRefiner wants it: Clear() and AddWithWeight(). Doubles throughout,
/// so refined and limit positions keep the input's precision.
struct Point3 {
  double p[3];
  void Clear() { p[0] = p[1] = p[2] = 0; }
  void AddWithWeight(const Point3& s, double w) {
    p[0] += w * s.p[0];
    p[1] += w * s.p[1];
    p[2] += w * s.p[2];
  }
};
static_assert(sizeof(Point3) == sizeof(Vec3));

/// One Vec3 of a buffer, viewed as a Point3 (the same sums, in the same order): the refined
/// levels are interpolated straight into Vec3 arrays, which the limit and the output take
/// as they are.
struct PointRef {
  Vec3* v;
  void Clear() { *v = Vec3{}; }
  void AddWithWeight(const PointRef& s, double w) {
    v->x += w * s.v->x;
    v->y += w * s.v->y;
    v->z += w * s.v->z;
  }
};

/// The buffer PrimvarRefiner indexes: operator[] hands out a view (PointRef) by value.
struct PointBuffer {
  Vec3* data;
  PointRef operator[](int i) const { return PointRef{data + i}; }
};

/// All attribute channels of one vertex (n doubles), viewed in a vertex-major buffer.
struct Channels {
  double* v;
  int n;
  void Clear() {
    for (int i = 0; i < n; ++i) v[i] = 0;
  }
  void AddWithWeight(const Channels& s, double w) {
    for (int i = 0; i < n; ++i) v[i] += w * s.v[i];
  }
};

/// The buffer PrimvarRefiner indexes: operator[] hands out a view (Channels) by value.
struct ChannelBuffer {
  double* data;
  int n;
  Channels operator[](int i) const { return Channels{data + size_t(i) * size_t(n), n}; }
};

Sdc::Options::VtxBoundaryInterpolation to_sdc(BoundaryRule b) {
  switch (b) {
    case BoundaryRule::EdgeAndCorner: return Sdc::Options::VTX_BOUNDARY_EDGE_AND_CORNER;
    case BoundaryRule::EdgeOnly: return Sdc::Options::VTX_BOUNDARY_EDGE_ONLY;
  }
  throw Error(Status::InvalidArgument, "unknown boundary rule " + std::to_string(int(b)));
}

}  // namespace

void copy_triangles(const OpenSubdiv::Far::TopologyLevel& level, std::vector<Triangle>& out) {
  const size_t nf = size_t(level.GetNumFaces());
  resize_huge(out, nf);
  if (nf == 0) return;
  // OpenSubdiv keeps a level's face-vertex indices in one array, face after face: a level of
  // triangles is the triangle array as it is (int and uint32_t alike for indices >= 0).
  const auto first = level.GetFaceVertices(0), end = level.GetFaceVertices(int(nf - 1));
  static_assert(sizeof(Triangle) == 3 * sizeof(OpenSubdiv::Far::Index));
  if (first.size() == 3 && end.size() == 3 && &end[0] == &first[0] + 3 * (nf - 1)) {
    const OpenSubdiv::Far::Index* src = &first[0];
    parallel_blocks(nf, 65536, [&](size_t b, size_t e) {
      std::memcpy(static_cast<void*>(out.data() + b), src + 3 * b, (e - b) * sizeof(Triangle));
    });
    return;
  }
  parallel_blocks(nf, 8192, [&](size_t b, size_t e) {
    for (size_t f = b; f < e; ++f) {
      const auto fv = level.GetFaceVertices(int(f));
      out[f] = {uint32_t(fv[0]), uint32_t(fv[1]), uint32_t(fv[2])};
    }
  });
}

std::unique_ptr<TopologyRefiner> loop_refiner(const ControlMesh& control, const SmoothOptions& options,
                                              const std::vector<std::pair<uint32_t, uint32_t>>& crease_pairs,
                                              const std::vector<float>& crease_sharpness, bool full_last_level) {
  const size_t nv = control.positions.size(), nf = control.triangles.size();
  // Through OpenSubdiv's raw-array descriptor.
  std::vector<int> verts_per_face(nf, 3);
  std::vector<int> face_verts(3 * nf);
  parallel_blocks(nf, 8192, [&](size_t b, size_t e) {
    for (size_t f = b; f < e; ++f)
      for (int c = 0; c < 3; ++c) face_verts[3 * f + size_t(c)] = int(control.triangles[f][size_t(c)]);
  });
  std::vector<int> crease_verts(2 * crease_pairs.size());
  for (size_t i = 0; i < crease_pairs.size(); ++i) {
    crease_verts[2 * i] = int(crease_pairs[i].first);
    crease_verts[2 * i + 1] = int(crease_pairs[i].second);
  }
  TopologyDescriptor desc;
  desc.numVertices = int(nv);
  desc.numFaces = int(nf);
  desc.numVertsPerFace = verts_per_face.data();
  desc.vertIndicesPerFace = face_verts.data();
  desc.numCreases = int(crease_pairs.size());
  desc.creaseVertexIndexPairs = crease_verts.data();
  desc.creaseWeights = crease_sharpness.data();

  Sdc::Options sdc;
  sdc.SetVtxBoundaryInterpolation(to_sdc(options.boundary));
  sdc.SetCreasingMethod(options.crease_method == CreaseMethod::Chaikin ? Sdc::Options::CREASE_CHAIKIN
                                                                       : Sdc::Options::CREASE_UNIFORM);
  std::unique_ptr<TopologyRefiner> r(RefinerFactory::Create(desc, RefinerFactory::Options(Sdc::SCHEME_LOOP, sdc)));
  if (!r)  // the control mesh was checked, so this is our bug, not the caller's input
    throw Error(Status::Internal, "OpenSubdiv refused the checked control mesh");
  if (options.levels > 0) {
    TopologyRefiner::UniformOptions uniform(options.levels);
    uniform.fullTopologyInLastLevel = full_last_level;
    r->RefineUniform(uniform);
  }
  return r;
}

void loop_subdivide(const ControlMesh& control, const SmoothOptions& options,
                    const std::vector<std::pair<uint32_t, uint32_t>>& crease_pairs,
                    const std::vector<float>& crease_sharpness, ProgressTracker& progress,
                    SmoothResult& out) {
  const int levels = options.levels;
  const size_t nv = control.positions.size();
  SmoothStats& st = out.stats;
  auto t0 = Clock::now();

  // 1. The topology, refined by OpenSubdiv. On a closed surface without creases the limit is
  // taken here, in parallel, with the rings read from the level before the last
  // (loop_limit.h); otherwise by OpenSubdiv, which needs the last level's full topology.
  progress.stage("refining topology (OpenSubdiv)", 0.05, 0.25);
  const bool own_limit = own_loop_limit(control, options, crease_pairs.size());
  auto refine = [&](bool full_last_level) {
    return loop_refiner(control, options, crease_pairs, crease_sharpness, full_last_level);
  };
  std::unique_ptr<TopologyRefiner> refiner = refine(options.limit && !own_limit);
  progress.check();

  // 2. Interpolate level by level (ping-pong buffers): positions and all attribute channels
  //    in parallel, each through the same refiner (PrimvarRefiner only reads it).
  int channels = 0;
  std::vector<double> attr = interleave_channels(control.attributes, nv, &channels), attr_next;
  std::vector<Vec3> pos = control.positions, pos_next;
  const PrimvarRefiner primvar(*refiner);
  double total_work = 0, done_work = 0;
  for (int l = 1; l <= levels; ++l) total_work += double(refiner->GetLevel(l).GetNumVertices());
  for (int l = 1; l <= levels; ++l) {
    const size_t n = size_t(refiner->GetLevel(l).GetNumVertices());
    const double w = double(n);
    progress.stage("interpolating level " + std::to_string(l) + " of " + std::to_string(levels), 
                   0.25 + 0.5 * done_work / total_work, 0.25 + 0.5 * (done_work + w) / total_work);
    done_work += w;
    pos_next.resize(n);
    attr_next.resize(n * size_t(channels));
    tbb::parallel_invoke(
        [&] {
          const PointBuffer src{pos.data()};
          PointBuffer dst{pos_next.data()};
          primvar.Interpolate(l, src, dst);
        },
        [&] {
          if (channels == 0) return;
          const ChannelBuffer src{attr.data(), channels};
          ChannelBuffer dst{attr_next.data(), channels};
          primvar.Interpolate(l, src, dst);
        },
        [&] {
          // Beside the last level's interpolation (one thread each): the output triangles,
          // and the limit's fresh output arrays (their page faults off the critical path).
          if (l != levels) return;
          copy_triangles(refiner->GetLevel(levels), out.mesh.triangles);
          if (own_limit) {
            resize_huge(out.mesh.positions, n);
            resize_huge(out.mesh.normals, n);
          }
        });
    pos.swap(pos_next);
    attr.swap(attr_next);
    progress.check();
  }
  pos_next = {};
  attr_next = {};
  st.seconds_refine = seconds_since(t0);

  // 3. The limit: exact positions, tangents (-> normals) and attributes.
  const size_t n_out = pos.size();
  auto t1 = Clock::now();
  const auto last = refiner->GetLevel(levels);
  if (levels == 0) copy_triangles(last, out.mesh.triangles);
  std::vector<Vec3>& positions = out.mesh.positions;
  bool limit_done = false;
  if (own_limit) {
    progress.stage("limit positions and normals", 0.75, 0.85);
    std::vector<double> attr_lim(n_out * size_t(channels));
    if (levels > 0) {
      // The rings from the level before the last (its full topology).
      limit_done = loop_limit_refined(refiner->GetLevel(levels - 1), last, pos, attr.data(), channels, positions,
                                      out.mesh.normals, attr_lim.data());
    } else {
      LoopRings rings;
      if (build_loop_rings(out.mesh.triangles, n_out, &rings)) {
        const LoopLimitMasks masks(rings.max_valence);
        tbb::parallel_invoke([&] { loop_limit_positions(rings, masks, pos, positions, out.mesh.normals); },
                             [&] {
                               if (channels > 0) loop_limit_channels(rings, masks, attr.data(), channels, attr_lim.data());
                             });
        limit_done = true;
      }
    }
    if (limit_done) {
      attr.swap(attr_lim);
      st.limit = true;
      progress.check();
    }
  }
  if (!limit_done) {
    positions = std::move(pos);
    out.mesh.normals.clear();
    if (options.limit) {
      if (own_limit) {
        // Not one closed fan at every vertex after all (cannot happen on a checked closed
        // 2-manifold): OpenSubdiv's limit, on a refinement with the full last level.
        refiner = refine(true);
      }
      progress.stage("limit positions and normals", 0.75, 0.85);
      opensubdiv_limit(*refiner, positions, attr, channels, out.mesh.normals);
      st.limit = true;
      progress.check();
    }
  }
  pos = {};
  st.seconds_limit = seconds_since(t1);

  // 4. Output arrays.
  auto t2 = Clock::now();
  progress.stage("output", 0.85, 0.95);
  out.mesh.attributes = split_channels(control.attributes, attr, channels, n_out);
  st.seconds_output = seconds_since(t2);
}

std::vector<double> interleave_channels(const std::vector<VertexAttribute>& attributes, size_t vertex_count,
                                        int* channels) {
  int k = 0;
  for (const auto& a : attributes) k += a.components;
  *channels = k;
  std::vector<double> values(vertex_count * size_t(k));
  size_t offset = 0;
  for (const auto& a : attributes) {
    const size_t c = size_t(a.components);
    for (size_t i = 0; i < vertex_count; ++i)
      for (size_t j = 0; j < c; ++j) values[i * size_t(k) + offset + j] = double(a.values[i * c + j]);
    offset += c;
  }
  return values;
}

std::vector<VertexAttribute> split_channels(const std::vector<VertexAttribute>& like, const std::vector<double>& values,
                                            int channels, size_t vertex_count) {
  std::vector<VertexAttribute> out;
  out.reserve(like.size());
  size_t offset = 0;
  for (const auto& a : like) {
    const size_t c = size_t(a.components);
    VertexAttribute o{a.name, a.components, std::vector<float>(vertex_count * c)};
    parallel_blocks(vertex_count, 8192, [&](size_t b, size_t e) {
      for (size_t i = b; i < e; ++i)
        for (size_t j = 0; j < c; ++j) o.values[i * c + j] = float(values[i * size_t(channels) + offset + j]);
    });
    offset += c;
    out.push_back(std::move(o));
  }
  return out;
}

void opensubdiv_limit(const TopologyRefiner& refiner, std::vector<Vec3>& positions, std::vector<double>& values,
                      int channels, std::vector<Vec3>& normals) {
  const PrimvarRefiner primvar(refiner);
  const size_t n = positions.size();
  std::vector<Point3> src(n), lim(n), tan1(n), tan2(n);
  std::memcpy(static_cast<void*>(src.data()), positions.data(), n * sizeof(Vec3));
  std::vector<double> values_lim(n * size_t(channels));
  tbb::parallel_invoke(
      [&] {
        const Point3* s = src.data();
        Point3 *p = lim.data(), *t1p = tan1.data(), *t2p = tan2.data();
        primvar.Limit(s, p, t1p, t2p);
      },
      [&] {
        if (channels == 0) return;
        const ChannelBuffer s{values.data(), channels};
        ChannelBuffer d{values_lim.data(), channels};
        primvar.Limit(s, d);
      });
  std::memcpy(static_cast<void*>(positions.data()), lim.data(), n * sizeof(Vec3));
  values.swap(values_lim);
  normals.resize(n);
  parallel_blocks(n, 8192, [&](size_t b, size_t e) {
    for (size_t i = b; i < e; ++i) {
      const Vec3 a{tan1[i].p[0], tan1[i].p[1], tan1[i].p[2]}, c{tan2[i].p[0], tan2[i].p[1], tan2[i].p[2]};
      const Vec3 nn = cross(a, c);
      normals[i] = squared_norm(nn) > 1e-24 * squared_norm(a) * squared_norm(c) ? normalized(nn) : Vec3{};
    }
  });
}

}  // namespace particlemesh::detail
