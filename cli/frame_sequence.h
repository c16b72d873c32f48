// Sequences of frames: an input path with a frame field ({} or {:04d}) names one file per
// frame, or a collection (.pvd, .series) lists them, and every output path (-o, --report) must
// hold a field too. What a frame pattern is,
// how frames are found, picked (--frames), skipped when up to date (--force), run several at
// once (--jobs) and reported (one progress line, a summary, exit 1 when a frame failed) lives
// here; each command only meshes one file (its run function, given a FrameContext).
//
// A frame pattern holds exactly one field and no other brace:
//   {}       the frame number in decimal, no leading zeros ("fluid_{}.vtk": fluid_7.vtk)
//   {:d}     the same
//   {:0Nd}   zero-padded to N characters, N = 1..18 ("fluid_{:04d}.vtk": fluid_0007.vtk; the
//            sign counts, -007; wider numbers keep every digit)
// A file is frame n when the pattern written for n gives its name exactly (fluid_07.vtk is not
// a frame of fluid_{}.vtk). These are Python's str.format rules for one integer, which
// particlemesh.distributed.map_frames follows too.
//
// A frame is up to date (and left alone unless --force) when every output exists, is newer
// than the frame's input, and its sidecar (sidecar_path) holds the same options text: the
// command, the version, the input path and every option that shapes the output. The sidecar
// is committed with the outputs, so the outputs' own bytes are exactly those of meshing the
// file alone.
#pragma once

#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <CLI/CLI.hpp>

#include "particlemesh/io/frame_collection.h"
#include "particlemesh/mesh/point_cloud.h"
#include "run_outputs.h"

namespace particlemesh::cli {

struct FramePattern {
  std::string prefix, suffix;
  int width = 0;  ///< 0: no padding
  std::string text;  ///< as given
};

/// Whether `path` holds a '{' or '}' (and so must be a frame pattern).
bool has_frame_field(const std::string& path);

/// Whether `path` is a frame collection (.pvd, .series) and no pattern: frame n is the file it
/// lists n-th by time.
bool is_sequence_collection(const std::string& path);

/// Whether `path` names a sequence: a frame pattern or a collection.
bool is_sequence_input(const std::string& path);

/// The pattern in `path`. @throws UsageError naming `option` when it has no field, more than
/// one, an unsupported one, or a stray brace.
FramePattern parse_frame_pattern(const std::string& path, const std::string& option);

/// The file of frame `frame`.
std::string frame_path(const FramePattern& p, int64_t frame);

/// The frames whose files exist, ascending.
std::vector<int64_t> find_frames(const FramePattern& p);

/// --frames, --force, --jobs, --dry-run.
struct SequenceArgs {
  std::string frames;
  bool force = false;
  int jobs = 1;
  bool dry_run = false;
};
void add_sequence_options(CLI::App& app, SequenceArgs& args);

/// For a single file: @throws UsageError when a sequence option or an output pattern was
/// given (they need a frame pattern input).
void check_single_file(const CLI::App& app, const std::vector<OutputSpec>& outputs);

/// Options that do not change an output's bytes (paths, threads, verbosity, the sequence's
/// own): left out of the options text that decides whether a frame is up to date.
inline const std::vector<std::string> kSequenceIgnored = {"input",  "--output", "--report", "--pcl-mesh",
                                                          "--threads", "--quiet", "--jobs", "--force",
                                                          "--dry-run", "--frames"};

/// What a frame's run gets from the sequence (null for a single file).
struct FrameContext {
  std::string label;  ///< "frame 12"
  /// Outputs the run writes besides its own, committed with them: the options sidecar.
  std::vector<OutputSpec> extra_outputs;
  std::vector<std::string> extra_contents;
  /// Call once the particles are read (after --attributes): records their attributes in the
  /// sidecar, and throws Error when they differ from the sequence's first frame's (that
  /// frame's sidecar when it is up to date; else it is meshed first, alone).
  std::function<void(const std::vector<VertexAttribute>&)> check_attributes;
  /// A warning about this frame (printed with its label, under the progress line).
  std::function<void(const std::string&)> warn;
};

/// A run's outputs: `specs` and, for a frame (non-null), its extra outputs too.
std::vector<OutputSpec> with_frame_outputs(std::vector<OutputSpec> specs, const FrameContext* frame);

/// --attributes (`spec`) applied to the particles read; for a frame, they are then checked
/// against the sequence's (FrameContext::check_attributes).
void settle_attributes(PointCloud& cloud, const std::string& spec, FrameContext* frame);

/// Writes a frame's extra outputs (for a non-null `frame`) and commits every output together.
void commit_outputs(RunOutputs& outputs, const FrameContext* frame);

struct SequenceSpec {
  std::string command;               ///< "polygonize"
  std::string input;                 ///< the input pattern
  std::vector<OutputSpec> outputs;   ///< -o, --report ... (patterns; empty path = not asked)
  SequenceArgs sequence;
  int threads = 0;                   ///< --threads (0 = all cores), shared by the --jobs frames
  bool quiet = false;
  std::string options_text;          ///< the options that shape the output (options_text())
  /// Mesh one frame: read `input`, write `outputs` (and the context's extras) with `threads`.
  std::function<void(const std::string& input, const std::vector<OutputSpec>& outputs, int threads, FrameContext& frame)>
      run_frame;
};

/// Run the sequence; returns the exit status (0; 1 when a frame failed or none was found;
/// 130 when interrupted). @throws UsageError (exit 2) for bad patterns, --frames or outputs,
/// all checked before any frame is read.
int run_sequence(const SequenceSpec& spec);

/// A command's action: mesh its input file or, when the input is a frame pattern, every frame
/// of the sequence. `Args` holds input, threads, quiet and sequence (SequenceArgs);
/// `outputs(args)` lists the output paths (patterns for a sequence), `for_frame(args, outs)`
/// sets a copy's output paths to one frame's, and `run(args, frame)` meshes one file (frame
/// null: a single file) and returns the exit status.
template <class Args, class Outputs, class ForFrame, class Run>
int run_file_or_sequence(const std::string& command, const CLI::App& app, const Args& args, Outputs outputs,
                         ForFrame for_frame, Run run);

/// "name=value" lines of the options given on `app`'s command line, in the order CLI11 lists
/// them, leaving out `ignored` (paths, threads, output verbosity: what does not change the
/// output's bytes). The options digest is made from it.
std::string options_text(const CLI::App& app, const std::vector<std::string>& ignored);

/// The sidecar that records how an output of a sequence was made: ".NAME.particlemesh" in
/// its folder.
std::string sidecar_path(const std::string& output);

template <class Args, class Outputs, class ForFrame, class Run>
int run_file_or_sequence(const std::string& command, const CLI::App& app, const Args& args, Outputs outputs,
                         ForFrame for_frame, Run run) {
  if (!is_sequence_input(args.input)) {
    check_single_file(app, outputs(args));
    return run(args, nullptr);
  }
  SequenceSpec spec;
  spec.command = command;
  spec.input = args.input;
  spec.outputs = outputs(args);
  spec.sequence = args.sequence;
  spec.threads = args.threads;
  spec.quiet = args.quiet;
  spec.options_text = options_text(app, kSequenceIgnored);
  spec.run_frame = [&args, for_frame, run](const std::string& in, const std::vector<OutputSpec>& outs, int threads,
                                           FrameContext& frame) {
    Args a = args;
    a.input = in;
    for_frame(a, outs);
    a.threads = threads;
    a.quiet = true;
    run(a, &frame);
  };
  return run_sequence(spec);
}

}  // namespace particlemesh::cli
