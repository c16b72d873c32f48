// The options polygonize and render share: anisotropic kernels (Yu and Turk 2013).
#pragma once

#include <cmath>
#include <cstdio>
#include <cstddef>
#include <string>

#include <CLI/CLI.hpp>

#include "commands.h"
#include "particlemesh/volume/anisotropy.h"
#include "particlemesh/volume/field.h"

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
      ->check(in_range(1e-9, 10.0))
      ->check(finite_number());
  app.add_option("--aniso-max-stretch", a.max_stretch,
                 "With --anisotropic: largest ratio of an ellipsoid's longest to shortest axis, k_r (1..100; "
                 "default 4)")
      ->check(in_range(1.0, 100.0))
      ->check(finite_number());
  app.add_option("--aniso-min-neighbors", a.min_neighbors,
                 "With --anisotropic: particles with fewer neighbours than this in the PCA neighbourhood keep a "
                 "sphere, N_eps (default 25)")
      ->check(in_range(0, 100000));
  app.add_option("--aniso-smoothing", a.smoothing,
                 "With --anisotropic: how far each kernel centre moves toward its neighbours' weighted mean, "
                 "lambda (0..1; default 0: off; Yu and Turk's 0.9 pulls a face's outer layer in by about a "
                 "spacing)")
      ->check(in_range(0.0, 1.0))
      ->check(finite_number());
}

/// What the summary says of a default radius R for particles of median spacing s: 2 x s, or the
/// larger radius their packing asked for (FieldParams::radius).
inline std::string default_radius_note(double radius, double spacing) {
  const double x = spacing > 0 ? radius / spacing : 0;
  if (!(std::abs(x - kDefaultRadiusFactor) > 1e-9 * kDefaultRadiusFactor)) return "default: 2 x spacing";
  char w[160];
  std::snprintf(w, sizeof w, "default: %.3g x spacing, from how densely the particles are packed", x);
  return w;
}

/// The help text of --radius for polygonize and render.
inline constexpr const char* kRadiusHelp =
    "Particle radius R (the field's support), world units (default: 2 x the median particle spacing; when that "
    "leaves over a tenth of the particles outside the surface, as in an SPH frame in motion, up to twice as much: "
    "the radius at which the field at the particles reaches a packed lattice's)";

/// --radius-channel NAME and --radius-scale F (after --radius, which the channel excludes).
inline void add_radius_channel_options(CLI::App& app, std::string& channel, double& scale) {
  app.add_option("--radius-channel", channel,
                 "Per-particle radius: R_i = F x the input's one-component channel NAME (Houdini's pscale, a radius "
                 "or size channel), F from --radius-scale; instead of --radius")
      ->excludes(app.get_option("--radius"));
  app.add_option("--radius-scale", scale,
                 "With --radius-channel: the factor F (default 4: a pscale of half the particle spacing gives the "
                 "default R of two spacings). The default threshold is then half the field inside touching "
                 "particles of their size at R = F x size, as in the Blender add-on's Particle Size mode")
      ->check(positive_number())
      ->check(finite_number());
}

/// The default threshold with radii from a channel of sizes (--radius-channel, spherical
/// kernels): the size says the spacing (touching particles of size s lie 2 s apart), so it is
/// half the field inside such a packing at R = F s, as the Blender add-on's Particle Size mode
/// sets it (at F = 4 it is the library's own default).
inline double sized_threshold(Kernel kernel, double scale) { return 0.5 * lattice_field(kernel, scale, 2.0); }

/// R_i = scale x the cloud's one-component channel `name`. @throws Error(InvalidArgument)
/// naming the channels the particles carry when it is not one of them or has several
/// components, Error(InvalidInput) naming the particle whose radius is not positive.
inline std::vector<double> radii_from_channel(const PointCloud& cloud, const std::string& name, double scale,
                                       const std::string& path) {
  std::string names;
  for (const VertexAttribute& x : cloud.attributes) {
    if (x.name != name) {
      names += (names.empty() ? "" : ", ") + x.name;
      continue;
    }
    if (x.components != 1)
      throw Error(Status::InvalidArgument, "--radius-channel " + name + ": the channel has " +
                                               std::to_string(x.components) + " components (one is needed)");
    std::vector<double> radii(x.values.size());
    for (size_t i = 0; i < radii.size(); ++i) {
      radii[i] = scale * double(x.values[i]);
      if (!(radii[i] > 0) || !std::isfinite(radii[i])) {
        char value[32];
        std::snprintf(value, sizeof value, "%g", double(x.values[i]));
        throw Error(Status::InvalidInput, "'" + path + "': particle " + std::to_string(i) + "'s " + name + " is " +
                                              value + " (a radius must be positive)");
      }
    }
    return radii;
  }
  throw Error(Status::InvalidArgument, "--radius-channel " + name + ": '" + path + "' has no such channel (" +
                                           (names.empty() ? std::string("it has none") : "it has " + names) + ")");
}

/// Below this share of the particles inside the surface, polygonize and render warn.
constexpr double kFewEnclosed = 0.5;
/// A radius more than this many times what the particles' packing asks for (over 6 spacings
/// of a lattice as dense: each particle's support holds about 900 of them) is said too.
constexpr double kLargeRadius = 3.0;

/// The warning when the radius does not fit how the particles are packed (field_at_particles):
/// most of them end up outside the surface, which shows only their densest clumps (a radius
/// given small, or a threshold high), said with the radius their packing suggests and
/// (`surface_method`) the command for particles that sample a surface rather than fill a
/// volume; or the radius is over kLargeRadius x what the packing asks for. Empty otherwise.
inline std::string radius_warning(double enclosed_fraction, double density_radius, double radius, double threshold,
                                     bool surface_method = false) {
  char w[500];
  if (!(enclosed_fraction < kFewEnclosed)) {
    // The other way round: a radius so large that every detail of the particles smaller than
    // it melts into one smooth blob (density_radius reads at most kMaxCalibrationRatio
    // spacings: then it is R x 2 / 8, and the radius to try may be smaller still).
    if (!(density_radius > 0 && density_radius * kLargeRadius < radius)) return {};
    const bool at_most = density_radius * (kMaxCalibrationRatio / kDefaultRadiusFactor) <= radius * (1.0 + 1e-6);
    std::snprintf(w, sizeof w,
                  "the radius R = %g is large for how densely the particles are packed (their packing suggests "
                  "--radius %.3g%s): every detail smaller than about R melts into one smooth blob",
                  radius, density_radius, at_most ? " or less" : "");
    return w;
  }
  int n = std::snprintf(w, sizeof w,
                        "the surface encloses only %.0f%% of the particles: the radius R = %g is small for how sparsely "
                        "they are packed, or the threshold T = %g high",
                        100.0 * enclosed_fraction, radius, threshold);
  if (density_radius > radius && n > 0 && size_t(n) < sizeof w)
    n += std::snprintf(w + n, sizeof w - size_t(n), "; their packing suggests --radius %.3g", density_radius);
  if (surface_method && n > 0 && size_t(n) < sizeof w)
    std::snprintf(w + n, sizeof w - size_t(n), " (particles that sample a surface rather than fill a volume: "
                                               "`particlemesh triangulate`)");
  return w;
}

/// More pieces than one for every this many particles (and at least kManyPiecesMin) make
/// polygonize say that the particles may sample a surface rather than fill a volume.
constexpr size_t kParticlesPerPiece = 10;
constexpr size_t kManyPiecesMin = 100;

/// The warning when the surface fell into about as many pieces as there are particles: one
/// layer of particles (the samples of a surface, not a fluid's volume) gives a blob around
/// each particle or each few, since the default threshold is half the field inside a packed
/// volume. Empty otherwise.
inline std::string pieces_warning(size_t pieces, size_t particles) {
  if (pieces < kManyPiecesMin || pieces * kParticlesPerPiece <= particles) return {};
  char w[400];
  std::snprintf(w, sizeof w,
                "the surface fell into %zu pieces, one for every %.1f particles: particles that sample a surface "
                "(one layer) rather than fill a volume give a blob around each few; `particlemesh triangulate` meshes "
                "such particles (or raise --radius, or lower --threshold, to join the blobs)",
                pieces, double(particles) / double(pieces));
  return w;
}

}  // namespace particlemesh::cli
