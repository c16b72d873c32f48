// Cancellation through every long call of the C++ API (issue 9): a host asks to stop from
// another thread at several points of a run (a flag its progress callback returns); the call
// must throw Error(Cancelled) within a bounded time of the request, whatever stage it is in.
// The sanitizer build checks that nothing leaks on the way out (LeakSanitizer at exit).
//
// Each test first runs the call to the end to learn its duration and the longest time it
// goes without calling the callback (printed), then cancels at 15 %, 50 % and 85 % of that
// duration.
#include <gtest/gtest.h>

#include <cstdio>

#include "hostile_support.h"
#include "particlemesh/sample/shapes.h"
#include "particlemesh/smooth/subdivide.h"
#include "particlemesh/surface/normals.h"
#include "particlemesh/surface/reconstruct.h"
#include "particlemesh/surface/spacing.h"
#include "particlemesh/surface/triangulate.h"

using namespace particlemesh;
using namespace particlemesh::test;

namespace {

// Seconds from the request to the return. Between two checks our own code does at most a few
// milliseconds of work (an idle machine returns in < 0.1 s); the rest of the bound is room
// for a loaded 2-core CI machine, 3x more under ASan.
constexpr double kLatency = kSanitized ? 6.0 : 2.0;
// One refinement level inside OpenSubdiv (topology) or OpenMesh (butterfly) is a single
// third-party call that cannot be interrupted: the bound there is that level's duration
// (about 1 s for the 80k-triangle level 2 below on an idle machine).
constexpr double kThirdPartyLatency = kSanitized ? 12.0 : 4.0;

void expect_prompt_cancellation(const char* what, const std::function<void(const ProgressCallback&)>& call,
                                double bound = kLatency) {
  const ProgressTrace full = trace_progress(call);
  std::printf("%s: %.2f s, %zu stages, longest gap between callbacks %.3f s (%s)\n", what, full.seconds,
              full.stages.size(), full.longest_gap, full.gap_stage.c_str());
  // The callback is the only way a host can ask to stop: between two calls it cannot.
  EXPECT_LT(full.longest_gap, bound) << what << ": no callback for " << full.longest_gap << " s in "
                                     << full.gap_stage;
  for (double at : {0.15, 0.5, 0.85}) {
    Status status = Status::Ok;
    std::string stage;
    const double latency = cancel_after(at * full.seconds, call, &status, &stage);
    if (latency < 0) continue;  // finished first (a faster rerun): nothing to cancel
    std::printf("  cancelled at %2.0f %% (%s): returned after %.3f s\n", at * 100, stage.c_str(), latency);
    EXPECT_EQ(status, Status::Cancelled) << what << " at " << at;
    EXPECT_LT(latency, bound) << what << " cancelled at " << at * 100 << " % in stage " << stage;
  }
}

size_t million() { return kSanitized ? 200000 : 1000000; }  // ASan: 3x slower, same code paths

}  // namespace

TEST(Cancellation, TriangulateRawMillionPoints) {
  const PointCloud c = fibonacci_sphere(million());
  expect_prompt_cancellation("triangulate_raw", [&](const ProgressCallback& p) {
    TriangulateOptions o;
    o.progress = p;
    triangulate_raw(c, o);
  });
}

TEST(Cancellation, ReconstructSurfaceMillionPoints) {
  const PointCloud c = fibonacci_sphere(million());
  expect_prompt_cancellation("reconstruct_surface", [&](const ProgressCallback& p) {
    SurfaceOptions o;
    o.progress = p;
    reconstruct_surface(c, o);
  });
}

TEST(Cancellation, SpacingAndNormals) {
  PointCloud c = fibonacci_sphere(million());
  expect_prompt_cancellation("estimate_spacing", [&](const ProgressCallback& p) {
    estimate_spacing(c.positions.data(), c.size(), 0, p);
  });
  expect_prompt_cancellation("estimate_normals", [&](const ProgressCallback& p) {
    NormalOptions o;
    o.progress = p;
    estimate_normals(c, o);
  });
}

TEST(Cancellation, SmoothLoopAndButterfly) {
  const TriMesh m = icosphere_mesh(kSanitized ? 5 : 6);  // 20480 / 81920 triangles
  for (SmoothScheme scheme : {SmoothScheme::Loop, SmoothScheme::Butterfly}) {
    expect_prompt_cancellation(scheme == SmoothScheme::Loop ? "smooth loop x2" : "smooth butterfly x2",
                               [&](const ProgressCallback& p) {
                                 SmoothOptions o;
                                 o.scheme = scheme;
                                 o.levels = 2;
                                 o.progress = p;
                                 smooth_mesh(m, o);
                               },
                               kThirdPartyLatency);
  }
}

// Once a callback has asked to stop it is not called again, and the call throws.
TEST(Cancellation, CallbackNotCalledAfterItCancels) {
  const PointCloud c = fibonacci_sphere(100000);
  for (int at = 1; at <= 12; ++at) {
    int calls = 0;
    SurfaceOptions o;
    o.progress = [&](std::string_view, double) { return ++calls < at; };
    const Status s = status_of([&] { reconstruct_surface(c, o); });
    if (s == Status::Ok) {
      EXPECT_LT(calls, at);
      break;
    }
    EXPECT_EQ(s, Status::Cancelled);
    EXPECT_EQ(calls, at) << "called again after it asked to cancel";
  }
}
