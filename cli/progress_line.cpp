#include "progress_line.h"

#include <tbb/task_group.h>

#include <atomic>
#include <csignal>
#include <cstdio>
#include <unistd.h>

#include "particlemesh/core/error.h"

namespace particlemesh::cli {

namespace {
volatile std::sig_atomic_t g_interrupted = 0;
volatile std::sig_atomic_t g_phase = 0;  // Phase::Reading

extern "C" void on_sigint(int) {
  g_interrupted = 1;
  if (g_phase == int(Phase::Reading)) {
    static const char msg[] = "particlemesh: cancelled (interrupted)\n";
    (void)!write(STDERR_FILENO, msg, sizeof msg - 1);
    _exit(130);  // async-signal-safe; nothing has been written yet
  }
  std::signal(SIGINT, SIG_DFL);  // a second Ctrl-C terminates at once
  std::signal(SIGTERM, SIG_DFL);
}
}  // namespace

void set_phase(Phase phase) {
  g_phase = int(phase);
  if (phase == Phase::Reading && g_interrupted) _exit(130);
}

void install_interrupt_handler() {
  struct sigaction sa {};
  sa.sa_handler = on_sigint;
  sigemptyset(&sa.sa_mask);
  sigaction(SIGINT, &sa, nullptr);
  sigaction(SIGTERM, &sa, nullptr);
}

bool interrupted() { return g_interrupted != 0; }

double write_outputs(const std::function<void()>& write, std::initializer_list<std::string> paths) {
  const auto t0 = std::chrono::steady_clock::now();
  set_phase(Phase::Writing);
  write();
  if (interrupted()) {  // Ctrl-C while writing: the run is cancelled, so no output either
    for (const std::string& p : paths)
      if (!p.empty()) std::remove(p.c_str());
    throw Error(Status::Cancelled, "interrupted");
  }
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

double write_outputs(const std::function<void()>& write, std::initializer_list<std::string> paths,
                     const std::function<void()>& beside) {
  tbb::task_group group;
  group.run(beside);
  double seconds = 0;
  try {
    seconds = write_outputs(write, paths);
  } catch (...) {
    group.wait();
    throw;
  }
  group.wait();
  return seconds;
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
