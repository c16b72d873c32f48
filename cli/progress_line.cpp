#include "progress_line.h"

#include <atomic>
#include <csignal>
#include <cstdio>
#include <unistd.h>

#include "particlemesh/core/error.h"
#include "particlemesh/io/output_file.h"

namespace particlemesh::cli {

namespace {
volatile std::sig_atomic_t g_interrupted = 0;
volatile std::sig_atomic_t g_phase = 0;  // Phase::Reading
std::atomic<bool> g_phase_held{false};

extern "C" void on_signal(int sig) {
  const bool cancel = sig == SIGINT || sig == SIGTERM;
  if (g_phase == int(Phase::Done)) {  // the outputs are in place: end as the signal ends a process
    std::signal(sig, SIG_DFL);
    raise(sig);
    return;
  }
  if (cancel && g_phase == int(Phase::Computing) && !g_interrupted) {
    g_interrupted = 1;  // the progress callback cancels the library's work
    return;
  }
  // Reading (nothing written), writing (temporaries only), a second Ctrl-C, or a hang-up,
  // quit or broken pipe: no output may be left half-made.
  particlemesh::remove_unfinished_outputs();
  if (cancel) {
    static const char msg[] = "particlemesh: cancelled (interrupted)\n";
    (void)!write(STDERR_FILENO, msg, sizeof msg - 1);
    _exit(130);
  }
  std::signal(sig, SIG_DFL);
  raise(sig);
}
}  // namespace

void set_phase(Phase phase) {
  if (g_phase_held.load()) return;
  g_phase = int(phase);
  if (phase == Phase::Reading && g_interrupted) _exit(130);
}

void hold_phase(bool held) {
  if (held) {
    g_phase = int(Phase::Computing);
    g_phase_held = true;
  } else {
    g_phase_held = false;
    g_phase = int(Phase::Done);
  }
}

void install_signal_handlers() {
  struct sigaction sa {};
  sa.sa_handler = on_signal;
  sigemptyset(&sa.sa_mask);
  sa.sa_flags = SA_RESTART;
  for (int sig : {SIGINT, SIGTERM, SIGHUP, SIGQUIT, SIGPIPE}) sigaction(sig, &sa, nullptr);
  std::signal(SIGXFSZ, SIG_IGN);  // a file size limit: EFBIG, a clear error, no killed process
}

bool interrupted() { return g_interrupted != 0; }

void throw_if_interrupted() {
  if (interrupted()) throw Error(Status::Cancelled, "cancelled (interrupted)");
}

ProgressCallback ProgressLine::callback() {
  tty_ = isatty(STDERR_FILENO) != 0;
  return [this](std::string_view stage, double fraction) {
    if (interrupted()) return false;
    if (quiet_) return true;
    const auto now = Clock::now();
    if (now - start_ < std::chrono::seconds(1)) return true;
    if (tty_) {
      if (now - last_ < std::chrono::milliseconds(100)) return true;
      std::fprintf(stderr, "\r%-28.*s %3d%%", int(stage.size()), stage.data(), int(fraction * 100 + 0.5));
      std::fflush(stderr);
      shown_ = true;
    } else if (stage != last_stage_ || now - last_ > std::chrono::seconds(5)) {
      // Logs (CI, render farms): one line per stage, and every 5 s within a long one.
      std::fprintf(stderr, "%.*s %d%%\n", int(stage.size()), stage.data(), int(fraction * 100 + 0.5));
      last_stage_ = std::string(stage);
    } else {
      return true;
    }
    last_ = now;
    return true;
  };
}

void ProgressLine::clear() {
  if (shown_ && tty_) {
    std::fprintf(stderr, "\r%40s\r", "");
    std::fflush(stderr);
  }
  shown_ = false;
}

}  // namespace particlemesh::cli
