// A progress line on stderr for work that takes more than a second, and Ctrl-C handling:
// SIGINT sets a flag that the library's progress callback turns into a prompt cancel.
#pragma once

#include <chrono>
#include <functional>
#include <initializer_list>
#include <string>
#include <string_view>

#include "particlemesh/core/progress.h"

namespace particlemesh::cli {

/// Install the SIGINT/SIGTERM handler. While the command computes, the first Ctrl-C sets a
/// flag that the progress callback turns into the library's cancellation; while it only reads
/// input (nothing to cancel, nothing written yet) the process exits at once with status 130.
/// A second Ctrl-C always exits at once.
void install_interrupt_handler();
bool interrupted();

enum class Phase { Reading, Computing, Writing };
/// Tell the handler what the command is doing now.
void set_phase(Phase phase);

/// The writing phase shared by the commands: runs `write` (whose writers are atomic), and if a
/// Ctrl-C arrived meanwhile the run counts as cancelled, so the files it finished (`paths`;
/// empty names are skipped) are removed and Error(Cancelled) is thrown. Returns the seconds taken.
double write_outputs(const std::function<void()>& write, std::initializer_list<std::string> paths);
/// The same, with `beside` (the topology report of what is written) computed meanwhile on the
/// other cores; both are done when it returns or throws.
double write_outputs(const std::function<void()>& write, std::initializer_list<std::string> paths,
                     const std::function<void()>& beside);

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
