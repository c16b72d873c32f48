// Helpers for the hostile-input suite: statuses of throwing calls, a byte hash of
// meshes (determinism), and a cancellation probe that measures how long a call takes to
// return after cancellation is requested from another thread.
#pragma once

#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <functional>
#include <string>
#include <thread>
#include <vector>

#include "particlemesh/core/error.h"
#include "particlemesh/core/progress.h"
#include "particlemesh/mesh/tri_mesh.h"
#include "support/test_support.h"

namespace particlemesh::test {

/// Status of a call (Ok if it returns); the message into *message.

#define PM_EXPECT_ERROR(call, status, text)                                                   \
  do {                                                                                        \
    std::string pm_msg_;                                                                      \
    EXPECT_EQ(::particlemesh::test::status_of([&] { (void)(call); }, &pm_msg_), (status)) << pm_msg_; \
    EXPECT_NE(pm_msg_.find(text), std::string::npos) << "message: " << pm_msg_;               \
  } while (0)

/// FNV-1a over the bytes of every array of a mesh: equal hashes = byte-identical meshes.
inline uint64_t mesh_hash(const TriMesh& m) {
  uint64_t h = 1469598103934665603ull;
  auto add = [&](const void* p, size_t n) {
    const auto* b = static_cast<const unsigned char*>(p);
    for (size_t i = 0; i < n; ++i) h = (h ^ b[i]) * 1099511628211ull;
  };
  add(m.positions.data(), m.positions.size() * sizeof(Vec3));
  add(m.normals.data(), m.normals.size() * sizeof(Vec3));
  add(m.triangles.data(), m.triangles.size() * sizeof(Triangle));
  for (const auto& a : m.attributes) {
    add(a.name.data(), a.name.size());
    add(a.values.data(), a.values.size() * sizeof(float));
  }
  return h;
}

using Clock = std::chrono::steady_clock;
inline double seconds(Clock::duration d) { return std::chrono::duration<double>(d).count(); }

/// The process's CPU time so far (all its threads), seconds. The bounds on progress gaps and
/// cancellation latency are in CPU time: on a loaded machine the wall time between two
/// progress calls stretches with the load, the work done between them does not.
inline double cpu_seconds() {
  timespec ts{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return double(ts.tv_sec) + 1e-9 * double(ts.tv_nsec);
}
/// A call that stops computing without returning (a deadlock) would pass a CPU bound: its wall
/// time gets a bound this many times looser.
inline constexpr double kWallSlack = 10.0;

/// What a full run's progress callbacks looked like.
struct ProgressTrace {
  double seconds = 0;         ///< the whole call (wall)
  double cpu = 0;             ///< the whole call (CPU, all threads)
  double longest_gap = 0;     ///< longest CPU time without a callback (incl. before the first / after the last)
  double longest_wall_gap = 0;
  std::string gap_stage;      ///< the stage in which it happened
  std::vector<std::string> stages;
};

/// Run `call(progress)` to the end, recording the callbacks.
inline ProgressTrace trace_progress(const std::function<void(const ProgressCallback&)>& call) {
  ProgressTrace t;
  const auto start = Clock::now();
  auto last = start;
  const double start_cpu = cpu_seconds();
  double last_cpu = start_cpu;
  std::string current = "(before the first callback)";
  auto gap = [&](const std::string& stage) {
    const auto now = Clock::now();
    const double cpu = cpu_seconds();
    if (cpu - last_cpu > t.longest_gap) {
      t.longest_gap = cpu - last_cpu;
      t.gap_stage = stage;
    }
    t.longest_wall_gap = std::max(t.longest_wall_gap, seconds(now - last));
    last = now;
    last_cpu = cpu;
  };
  call([&](std::string_view stage, double) {
    gap(current);
    current = std::string(stage);
    if (t.stages.empty() || t.stages.back() != stage) t.stages.emplace_back(stage);
    return true;
  });
  gap(current + " (after the last callback)");
  t.seconds = seconds(last - start);
  t.cpu = last_cpu - start_cpu;
  return t;
}

/// Cancel `call` from another thread `delay` seconds after it starts, as a host does (a flag
/// the progress callback returns). Returns the CPU seconds (cpu_seconds) from the request to
/// the call's return, negative if the call finished before the request or without calling the
/// callback after it (the request came too late to be seen), and its status into *status.
/// The wall time from the request to the return is checked against kWallSlack x `cpu_bound`.
inline double cancel_after(double delay, const std::function<void(const ProgressCallback&)>& call, Status* status,
                           std::string* stage_at_cancel = nullptr, double cpu_bound = 3.0) {
  std::atomic<bool> requested{false};
  std::atomic<int64_t> requested_at{0};
  std::atomic<double> requested_cpu{0};
  std::string stage_seen;
  std::thread timer([&] {
    std::this_thread::sleep_for(std::chrono::duration<double>(delay));
    requested_at = Clock::now().time_since_epoch().count();
    requested_cpu = cpu_seconds();
    requested = true;
  });
  bool seen = false;
  *status = status_of([&] {
    call([&](std::string_view stage, double) {
      stage_seen = std::string(stage);
      seen = requested.load();
      return !seen;
    });
  });
  const auto returned = Clock::now();
  const double returned_cpu = cpu_seconds();
  timer.join();
  if (stage_at_cancel) *stage_at_cancel = stage_seen;
  if (!seen && *status == Status::Ok) return -1;
  const double wall = seconds(returned - Clock::time_point(Clock::duration(requested_at.load())));
  EXPECT_LT(wall, kWallSlack * cpu_bound) << "the call went on for " << wall << " s after the request";
  return returned_cpu - requested_cpu.load();
}

/// The "1M" of the long-call tests: 100k under ASan (3x slower; the same code paths, and the
/// sanitizer build's run has to fit in CI's time beside the Release one).
inline size_t million() { return kSanitized ? 100000 : 1000000; }

// CPU seconds from the request to the return. Between two checks our own code does at most a
// few milliseconds of work (an idle machine returns in < 0.1 s); the rest of the bound is room
// for every thread's share of it on many cores, 3x more under ASan.
inline constexpr double kLatency = kSanitized ? 9.0 : 3.0;
// One refinement level inside OpenSubdiv (topology) or OpenMesh (butterfly) is a single
// third-party call that cannot be interrupted: the bound there is that level's duration
// (about 1 s for the 80k-triangle level 2 below on an idle machine).
inline constexpr double kThirdPartyLatency = kSanitized ? 12.0 : 4.0;

inline ProgressTrace expect_prompt_cancellation(const char* what,
                                               const std::function<void(const ProgressCallback&)>& call,
                                               double bound = kLatency) {
  const ProgressTrace full = trace_progress(call);
  std::printf("%s: %.2f s, %zu stages, longest gap between callbacks %.3f s of CPU (%s), %.3f s of wall time\n",
              what, full.seconds, full.stages.size(), full.longest_gap, full.gap_stage.c_str(), full.longest_wall_gap);
  // The callback is the only way a host can ask to stop: between two calls it cannot.
  EXPECT_LT(full.longest_gap, bound) << what << ": no callback for " << full.longest_gap << " s of CPU in "
                                     << full.gap_stage;
  EXPECT_LT(full.longest_wall_gap, kWallSlack * bound) << what;
  for (double at : {0.15, 0.5, 0.85}) {
    Status status = Status::Ok;
    std::string stage;
    const double latency = cancel_after(at * full.seconds, call, &status, &stage, bound);
    if (latency < 0) continue;  // finished first (a faster rerun): nothing to cancel
    std::printf("  cancelled at %2.0f %% (%s): returned after %.3f s of CPU\n", at * 100, stage.c_str(), latency);
    EXPECT_EQ(status, Status::Cancelled) << what << " at " << at;
    EXPECT_LT(latency, bound) << what << " cancelled at " << at * 100 << " % in stage " << stage;
  }
  return full;
}

}  // namespace particlemesh::test
