// The options polygonize and render share: anisotropic kernels (Yu and Turk 2013).
#pragma once

#include <CLI/CLI.hpp>

#include "commands.h"
#include "particlemesh/volume/anisotropy.h"

namespace particlemesh::cli {

/// --anisotropic and its four parameters, written into `a` (a.enabled by the flag).
inline void add_anisotropy_options(CLI::App& app, AnisotropyOptions& a) {
  app.add_flag("--anisotropic", a.enabled,
               "Anisotropic kernels (Yu and Turk 2013): each particle's kernel becomes an ellipsoid of its "
               "sphere's volume, stretched along the surface and squeezed across it by a PCA of its neighbours: "
               "flat faces without bumps, thin sheets that stay whole. The default threshold is then calibrated "
               "on the particles so that a packed face lies half a spacing out (the volume is kept)");
  app.add_option("--aniso-radius", a.neighbor_radius,
                 "With --anisotropic: radius of the neighbourhood each kernel's PCA looks at, as a multiple of R "
                 "(0 < F <= 10; default 2)")
      ->check(CLI::Range(1e-9, 10.0))
      ->check(finite_number());
  app.add_option("--aniso-max-stretch", a.max_stretch,
                 "With --anisotropic: largest ratio of an ellipsoid's longest to shortest axis, k_r (1..100; "
                 "default 4)")
      ->check(CLI::Range(1.0, 100.0))
      ->check(finite_number());
  app.add_option("--aniso-min-neighbors", a.min_neighbors,
                 "With --anisotropic: particles with fewer neighbours than this in the PCA neighbourhood keep a "
                 "sphere, N_eps (default 25)")
      ->check(CLI::Range(0, 100000));
  app.add_option("--aniso-smoothing", a.smoothing,
                 "With --anisotropic: how far each kernel centre moves toward its neighbours' weighted mean, "
                 "lambda (0..1; default 0: off; Yu and Turk's 0.9 pulls a face's outer layer in by about a "
                 "spacing)")
      ->check(CLI::Range(0.0, 1.0))
      ->check(finite_number());
}

}  // namespace particlemesh::cli
