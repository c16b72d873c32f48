// The particles' attributes at given points as polygonize gives them at its vertices: the same
// field (built from the same options) and the same sums (AttributeSums, polygonize's own).
#include "particlemesh/volume/polygonize_attributes.h"

#include <cmath>
#include <string>
#include <utility>

#include "core/parallel.h"
#include "core/progress_tracker.h"
#include "particlemesh/core/error.h"
#include "volume/field_impl.h"
#include "volume/polygonize_finish.h"

namespace PM_NAMESPACE {

namespace {

void check_points(const Vec3* points, size_t count) {
  if (count > 0 && points == nullptr) throw Error(Status::InvalidArgument, "points is NULL");
  for (size_t i = 0; i < count; ++i)
    for (int a = 0; a < 3; ++a)
      if (!std::isfinite(points[i][a]))
        throw Error(Status::InvalidInput, "points[" + std::to_string(i) + "]." + "xyz"[a] + " is " +
                                              (std::isnan(points[i][a]) ? "NaN" : "infinite"));
}

// The sums of polygonize (AttributeSums) at every point, in parallel: each point's values
// come from its own query in the field's fixed order, so the thread count changes nothing.
std::vector<VertexAttribute> interpolate(const ParticleField& field, const std::vector<VertexAttribute>& attributes,
                                         const Vec3* points, size_t count, detail::ProgressTracker& tracker,
                                         double begin) {
  std::vector<VertexAttribute> values;
  detail::AttributeSums sums(values, count, field, attributes);
  if (!sums.any()) return {};
  tracker.stage("interpolating attributes", begin, 1.0, count);
  detail::parallel_blocks(count, 1024, [&](size_t bb, size_t be) {
    if (tracker.cancelled()) return;
    detail::AttributeSums local(sums);  // its own running sums
    for (size_t v = bb; v < be; ++v) local.interpolate(v, field, points[v]);
    tracker.tick(be - bb);
  });
  tracker.check();
  return values;
}

}  // namespace

std::vector<VertexAttribute> polygonize_attributes(const PointCloud& cloud, const PolygonizeOptions& options,
                                                   const Vec3* points, size_t count) {
  detail::ProgressTracker tracker(options.progress);
  check_points(points, count);
  std::vector<VertexAttribute> out = detail::with_threads(options.threads, [&] {
    // The field polygonize(cloud, options) builds, from the same options.
    const double field_end = options.anisotropy.enabled ? 0.6 : 0.2;
    const ParticleField field = detail::polygonize_field_of(cloud, options, tracker, 0.0, field_end);
    return interpolate(field, cloud.attributes, points, count, tracker, field_end);
  });
  tracker.finish();
  return out;
}

std::vector<VertexAttribute> polygonize_attributes(const ParticleField& field,
                                                   const std::vector<VertexAttribute>& attributes,
                                                   const Vec3* points, size_t count, int threads,
                                                   const ProgressCallback& progress) {
  detail::ProgressTracker tracker(progress);
  check_points(points, count);
  std::vector<VertexAttribute> out =
      detail::with_threads(threads, [&] { return interpolate(field, attributes, points, count, tracker, 0.0); });
  tracker.finish();
  return out;
}

}  // namespace particlemesh
