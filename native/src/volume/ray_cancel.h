// Internal: cancellation inside one ray. With a radius that covers thousands of particles a
// single ray sums all of them on each of thousands of intervals (seconds from inside a big
// blob), so the batch calls (cast_first_hits, cast_all_hits, render) publish their tracker to
// the rays they cast on a thread, and the ray's march checks it every few dozen intervals. A
// cancelled ray ends early; its (partial) result is discarded with the rest of the call.
#pragma once

#include "particlemesh/core/config.h"

#include "core/progress_tracker.h"

namespace PM_NAMESPACE::detail {

/// The tracker of the batch whose rays this thread is casting (nullptr: a single ray cast by
/// the user, which is not cancellable).
ProgressTracker*& ray_tracker();

/// Publishes `tracker` to the rays cast on this thread for the scope.
class RayCancelScope {
 public:
  explicit RayCancelScope(ProgressTracker* tracker) : previous_(ray_tracker()) { ray_tracker() = tracker; }
  ~RayCancelScope() { ray_tracker() = previous_; }
  RayCancelScope(const RayCancelScope&) = delete;
  RayCancelScope& operator=(const RayCancelScope&) = delete;

 private:
  ProgressTracker* previous_;
};

/// Whether the batch casting this ray was cancelled; on the calling thread this also gives
/// the callback its chance to ask (at most every 50 ms, as always).
inline bool ray_cancelled() {
  ProgressTracker* t = ray_tracker();
  if (t == nullptr) return false;
  t->tick(0);
  return t->cancelled();
}

}  // namespace particlemesh::detail
