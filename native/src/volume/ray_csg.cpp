#include "particlemesh/volume/ray_csg.h"

#include <string>

#include "particlemesh/core/error.h"

namespace PM_NAMESPACE {

namespace {

bool combine(CsgOp op, bool a, bool b) {
  switch (op) {
    case CsgOp::Union: return a || b;
    case CsgOp::Intersection: return a && b;
    case CsgOp::Difference: return a && !b;
  }
  return false;
}

void validate(CsgOp op) {
  if (op != CsgOp::Union && op != CsgOp::Intersection && op != CsgOp::Difference)
    throw Error(Status::InvalidArgument,
                "CSG operation is " + std::to_string(int32_t(op)) + " (must be 0 union, 1 intersection or 2 difference)");
}

void check_sorted(const RayHits& h, const char* name) {
  for (size_t i = 1; i < h.hits.size(); ++i)
    if (!(h.hits[i - 1].t <= h.hits[i].t))
      throw Error(Status::InvalidArgument, std::string(name) + ".hits[" + std::to_string(i) + "] is out of order");
}

}  // namespace

const char* csg_op_name(CsgOp op) {
  switch (op) {
    case CsgOp::Union: return "union";
    case CsgOp::Intersection: return "intersection";
    case CsgOp::Difference: return "difference";
  }
  return "unknown";
}

RayHits csg_hits(const RayHits& a, const RayHits& b, CsgOp op) {
  validate(op);
  check_sorted(a, "a");
  check_sorted(b, "b");
  bool in_a = a.starts_inside, in_b = b.starts_inside;
  RayHits r;
  r.starts_inside = combine(op, in_a, in_b);
  bool state = r.starts_inside;
  size_t i = 0, j = 0;
  while (i < a.hits.size() || j < b.hits.size()) {
    const double ta = i < a.hits.size() ? a.hits[i].t : std::numeric_limits<double>::infinity();
    const double tb = j < b.hits.size() ? b.hits[j].t : std::numeric_limits<double>::infinity();
    const double t = std::min(ta, tb);
    const RayHit* from_a = nullptr;
    const RayHit* from_b = nullptr;
    if (ta == t) {
      from_a = &a.hits[i++];
      in_a = !in_a;
    }
    if (tb == t) {
      from_b = &b.hits[j++];
      in_b = !in_b;
    }
    const bool next = combine(op, in_a, in_b);
    if (next == state) continue;
    state = next;
    RayHit h;
    // The surface that changed the result: A's if A crossed here and that alone changes
    // the result (or both crossed), else B's.
    const bool use_a = from_a && (from_b == nullptr || combine(op, in_a, !in_b) == next);
    if (use_a) {
      h = *from_a;
    } else {
      h = *from_b;
      if (op == CsgOp::Difference) h.normal = -h.normal;
    }
    h.entering = next;
    r.hits.push_back(h);
  }
  return r;
}

RayHits csg_all_hits(const RayCaster& a, const RayCaster& b, CsgOp op, const Vec3& origin, const Vec3& direction,
                     double t_min, double t_max) {
  validate(op);
  return csg_hits(a.all_hits(origin, direction, t_min, t_max), b.all_hits(origin, direction, t_min, t_max), op);
}

std::optional<RayHit> csg_first_hit(const RayCaster& a, const RayCaster& b, CsgOp op, const Vec3& origin,
                                    const Vec3& direction, double t_min, double t_max) {
  const RayHits r = csg_all_hits(a, b, op, origin, direction, t_min, t_max);
  if (r.hits.empty()) return std::nullopt;
  return r.hits.front();
}

}  // namespace particlemesh
