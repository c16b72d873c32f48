// `--smooth loop|butterfly --levels K` for commands that produce a mesh (triangulate): the
// option definitions and the one post-processing step, kept here so those commands change by
// a few lines only. The full set of smoothing options is on `particlemesh smooth`.
#pragma once

#include <string>

#include <CLI/CLI.hpp>

#include "particlemesh/mesh/tri_mesh.h"
#include "progress_line.h"

namespace particlemesh::cli {

struct SmoothChainArgs {
  std::string scheme;  ///< "" = no smoothing, "loop" or "butterfly"
  int levels = 1;
};

/// Add --smooth and --levels to `app`.
void add_smooth_chain_options(CLI::App* app, SmoothChainArgs& args);

/// Replace `mesh` by its smoothed version when --smooth was given (Loop at the limit, or
/// butterfly; `threads` as for the command). Errors name the smoothing step.
void apply_smooth_chain(TriMesh& mesh, const SmoothChainArgs& args, int threads, ProgressLine& progress);

}  // namespace particlemesh::cli
