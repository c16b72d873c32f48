// A progress line on stderr for work that takes more than a second, and Ctrl-C handling:
// SIGINT sets a flag that the library's progress callback turns into a prompt cancel.
#pragma once

#include <chrono>
#include <string>
#include <string_view>

#include "particlemesh/core/progress.h"

namespace particlemesh::cli {

/// Install the SIGINT handler (the first Ctrl-C cancels; a second one kills).
void install_interrupt_handler();
bool interrupted();

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
