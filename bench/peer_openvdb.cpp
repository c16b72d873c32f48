#include "peer_openvdb.h"

#include <chrono>

#ifdef PM_BENCH_WITH_OPENVDB
#include <openvdb/openvdb.h>
#include <openvdb/tools/ParticlesToLevelSet.h>
#include <openvdb/tools/VolumeToMesh.h>
#endif

namespace peer {

#ifdef PM_BENCH_WITH_OPENVDB

namespace {
// The particle list interface ParticlesToLevelSet expects.
struct ParticleList {
  using PosType = openvdb::Vec3R;
  std::vector<openvdb::Vec3R> p;
  openvdb::Real r = 0;
  size_t size() const { return p.size(); }
  void getPos(size_t n, openvdb::Vec3R& xyz) const { xyz = p[n]; }
  void getPosRad(size_t n, openvdb::Vec3R& xyz, openvdb::Real& rad) const {
    xyz = p[n];
    rad = r;
  }
};
}  // namespace

bool openvdb_available() { return true; }

VdbResult openvdb_particles_to_mesh(const std::vector<particlemesh::Vec3>& positions, double sphere_radius,
                                    double voxel) {
  openvdb::initialize();
  ParticleList list;
  list.r = sphere_radius;
  list.p.reserve(positions.size());
  for (const auto& q : positions) list.p.emplace_back(q.x, q.y, q.z);
  VdbResult out;
  const auto t0 = std::chrono::steady_clock::now();
  openvdb::FloatGrid::Ptr ls = openvdb::createLevelSet<openvdb::FloatGrid>(voxel, 3.0);
  openvdb::tools::ParticlesToLevelSet<openvdb::FloatGrid> raster(*ls);
  raster.rasterizeSpheres(list);
  raster.finalize(/*prune=*/true);
  std::vector<openvdb::Vec3s> points;
  std::vector<openvdb::Vec3I> triangles;
  std::vector<openvdb::Vec4I> quads;
  openvdb::tools::volumeToMesh(*ls, points, triangles, quads, /*isovalue=*/0.0, /*adaptivity=*/0.0);
  out.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  out.vertices = points.size();
  out.triangles = triangles.size() + 2 * quads.size();
  return out;
}

VdbMesh openvdb_particles_mesh(const std::vector<particlemesh::Vec3>& positions, double sphere_radius, double voxel) {
  openvdb::initialize();
  ParticleList list;
  list.r = sphere_radius;
  list.p.reserve(positions.size());
  for (const auto& q : positions) list.p.emplace_back(q.x, q.y, q.z);
  VdbMesh out;
  const auto t0 = std::chrono::steady_clock::now();
  openvdb::FloatGrid::Ptr ls = openvdb::createLevelSet<openvdb::FloatGrid>(voxel, 3.0);
  openvdb::tools::ParticlesToLevelSet<openvdb::FloatGrid> raster(*ls);
  raster.rasterizeSpheres(list);
  raster.finalize(/*prune=*/true);
  std::vector<openvdb::Vec3s> points;
  std::vector<openvdb::Vec3I> triangles;
  std::vector<openvdb::Vec4I> quads;
  openvdb::tools::volumeToMesh(*ls, points, triangles, quads, /*isovalue=*/0.0, /*adaptivity=*/0.0);
  out.points.resize(3 * points.size());
  for (size_t i = 0; i < points.size(); ++i)
    for (int a = 0; a < 3; ++a) out.points[3 * i + size_t(a)] = points[i][a];
  out.triangles.reserve(3 * (triangles.size() + 2 * quads.size()));
  for (const auto& t : triangles) out.triangles.insert(out.triangles.end(), {t[0], t[1], t[2]});
  for (const auto& q : quads) out.triangles.insert(out.triangles.end(), {q[0], q[1], q[2], q[0], q[2], q[3]});
  out.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return out;
}

#else

bool openvdb_available() { return false; }
VdbMesh openvdb_particles_mesh(const std::vector<particlemesh::Vec3>&, double, double) { return {}; }
VdbResult openvdb_particles_to_mesh(const std::vector<particlemesh::Vec3>&, double, double) { return {}; }

#endif

}  // namespace peer
