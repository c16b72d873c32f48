#include "peer_embree.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstring>
#include <string>

#include <tbb/global_control.h>
#include <tbb/parallel_for.h>

#ifdef PM_BENCH_WITH_EMBREE
#include <embree3/rtcore.h>
#endif

namespace peer {

#ifdef PM_BENCH_WITH_EMBREE

bool embree_available() { return true; }

EmbreeResult embree_primary_rays(const std::vector<float>& points, const std::vector<uint32_t>& triangles,
                                 const particlemesh::Vec3& eye, const particlemesh::Vec3& forward,
                                 const particlemesh::Vec3& right, const particlemesh::Vec3& up, double tv, double th,
                                 int width, int height, int threads) {
  using Clock = std::chrono::steady_clock;
  EmbreeResult out;
  const std::string config = "threads=" + std::to_string(threads);
  RTCDevice device = rtcNewDevice(config.c_str());
  const auto t0 = Clock::now();
  RTCScene scene = rtcNewScene(device);
  RTCGeometry geom = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
  const size_t nv = points.size() / 3, nt = triangles.size() / 3;
  float* v = static_cast<float*>(
      rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 3 * sizeof(float), nv));
  std::memcpy(v, points.data(), points.size() * sizeof(float));
  unsigned* ix = static_cast<unsigned*>(
      rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 3 * sizeof(unsigned), nt));
  std::memcpy(ix, triangles.data(), triangles.size() * sizeof(uint32_t));
  rtcCommitGeometry(geom);
  rtcAttachGeometry(scene, geom);
  rtcReleaseGeometry(geom);
  rtcCommitScene(scene);
  out.build_seconds = std::chrono::duration<double>(Clock::now() - t0).count();

  const auto t1 = Clock::now();
  out.hit.assign(size_t(width) * size_t(height), 0);
  std::atomic<uint64_t> hits{0};
  const particlemesh::Vec3 light = normalized(forward * -1.0 + up * 0.7 - right * 0.5);
  std::vector<float> shade(size_t(width) * size_t(height), 0.0f);
  {
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, size_t(threads));
    tbb::parallel_for(0, height, [&](int y) {
      RTCIntersectContext context;
      rtcInitIntersectContext(&context);
      uint64_t row_hits = 0;
      const double py = 1.0 - 2.0 * (double(y) + 0.5) / double(height);
      for (int x = 0; x < width; ++x) {
        const double px = 2.0 * (double(x) + 0.5) / double(width) - 1.0;
        const particlemesh::Vec3 d = forward + right * (px * th) + up * (py * tv);
        RTCRayHit rh{};
        rh.ray.org_x = float(eye.x);
        rh.ray.org_y = float(eye.y);
        rh.ray.org_z = float(eye.z);
        rh.ray.dir_x = float(d.x);
        rh.ray.dir_y = float(d.y);
        rh.ray.dir_z = float(d.z);
        rh.ray.tnear = 0.0f;
        rh.ray.tfar = std::numeric_limits<float>::infinity();
        rh.ray.mask = ~0u;
        rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
        rtcIntersect1(scene, &context, &rh);
        if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) continue;
        ++row_hits;
        out.hit[size_t(y) * size_t(width) + size_t(x)] = 1;
        // A Lambert shade of the geometric normal, as a renderer would.
        particlemesh::Vec3 n{rh.hit.Ng_x, rh.hit.Ng_y, rh.hit.Ng_z};
        n = normalized(n);
        if (dot(n, d) > 0) n = -n;
        shade[size_t(y) * size_t(width) + size_t(x)] = float(std::max(0.0, dot(n, light)));
      }
      hits += row_hits;
    });
  }
  out.trace_seconds = std::chrono::duration<double>(Clock::now() - t1).count();
  out.hits = hits;
  rtcReleaseScene(scene);
  rtcReleaseDevice(device);
  return out;
}

#else

bool embree_available() { return false; }
EmbreeResult embree_primary_rays(const std::vector<float>&, const std::vector<uint32_t>&, const particlemesh::Vec3&,
                                 const particlemesh::Vec3&, const particlemesh::Vec3&, const particlemesh::Vec3&, double,
                                 double, int, int, int) {
  return {};
}

#endif

}  // namespace peer
