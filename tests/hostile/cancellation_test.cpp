// Cancellation through every long call of the C++ API: a host asks to stop from
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
#include "particlemesh/spatial/spacing.h"
#include "particlemesh/surface/triangulate.h"

using namespace particlemesh;
using namespace particlemesh::test;

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
  const TriMesh m = icosphere_mesh(kSanitized ? 4 : 6);  // 5120 / 81920 triangles
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
