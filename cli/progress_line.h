// A progress line on stderr for work that takes more than a second, and signal handling:
// SIGINT / SIGTERM while computing set a flag that the library's progress callback turns into
// a prompt cancel; any other time, and SIGHUP, SIGQUIT, SIGPIPE at any time, end the process
// at once after removing the unfinished output files' temporaries. SIGXFSZ (a file size
// limit) is ignored, so that a write past the limit fails with "File too large" and the run
// ends with that error instead of being killed half-way.
#pragma once

#include <chrono>
#include <string>
#include <string_view>

#include "particlemesh/core/progress.h"

namespace particlemesh::cli {

/// Install the handlers. While the command computes, the first SIGINT or SIGTERM sets a flag
/// that the progress callback turns into the library's cancellation (exit status 130); while
/// it reads input or writes its outputs, the process removes the outputs' temporaries and
/// exits with status 130 at once. A second SIGINT / SIGTERM always exits at once. SIGHUP,
/// SIGQUIT and SIGPIPE remove the temporaries, then end the process as they would have.
void install_signal_handlers();
bool interrupted();
/// @throws Error(Cancelled) once a SIGINT / SIGTERM has been received (interrupted()).
void throw_if_interrupted();

enum class Phase { Reading, Computing, Writing, Done };
/// Tell the handler what the command is doing now.
void set_phase(Phase phase);
/// A sequence of frames (frame_sequence.h) holds the phase at Computing while its frames
/// run, several at once: a Ctrl-C then only sets the flag that cancels every frame in flight
/// (each removes its temporaries); the frames' own set_phase calls change nothing. Releasing
/// sets Done.
void hold_phase(bool held);

class ProgressLine {
 public:
  explicit ProgressLine(bool quiet) : quiet_(quiet), start_(Clock::now()) {}
  ~ProgressLine() { clear(); }
  /// A callback for the library: draws the line once a second has passed; cancels on Ctrl-C.
  ProgressCallback callback();
  void clear();

 private:
  using Clock = std::chrono::steady_clock;
  bool quiet_;
  bool tty_ = false;
  bool shown_ = false;
  Clock::time_point start_;
  Clock::time_point last_{};
  std::string last_stage_;
};

}  // namespace particlemesh::cli
