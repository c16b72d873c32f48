// Internal: turns a ProgressCallback into a cheap, thread-safe progress/cancel object.
//
// Workers on any thread call tick()/cancelled(); only the thread that created the tracker
// ever calls the user's callback (hosts such as Blender and ctypes need that), and at most
// every 50 ms, so callbacks never cost measurable time.
#pragma once

#include "particlemesh/core/config.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdint>
#include <string>
#include <thread>

#include "particlemesh/core/error.h"
#include "particlemesh/core/progress.h"

namespace PM_NAMESPACE::detail {

class ProgressTracker {
 public:
  explicit ProgressTracker(const ProgressCallback& callback)
      : callback_(callback), owner_(std::this_thread::get_id()), last_(Clock::now()) {}

  /// Start a stage covering [begin, end) of the overall fraction with `total` work units.
  void stage(std::string name, double begin, double end, uint64_t total = 1) {
    check();
    name_ = std::move(name);
    begin_ = begin;
    end_ = end;
    total_ = total > 0 ? total : 1;
    done_.store(0, std::memory_order_relaxed);
    report(begin_, /*force=*/true);
  }

  /// Record `units` of finished work. Cheap; safe from any thread.
  void tick(uint64_t units = 1) {
    const uint64_t done = done_.fetch_add(units, std::memory_order_relaxed) + units;
    if (callback_ && std::this_thread::get_id() == owner_) {
      const double f = begin_ + (end_ - begin_) * (double(done < total_ ? done : total_) / double(total_));
      report(f, /*force=*/false);
    }
  }

  bool cancelled() const { return cancelled_.load(std::memory_order_relaxed); }

  /// The overall fraction at the start of the current stage.
  double position() const { return begin_; }

  /// Throw Error(Cancelled) if cancellation was requested. On the owner thread it also asks
  /// the callback (at most every 50 ms), so long steps without ticks still notice a request.
  void check() {
    if (callback_ && !cancelled() && std::this_thread::get_id() == owner_) {
      const uint64_t done = done_.load(std::memory_order_relaxed);
      report(begin_ + (end_ - begin_) * (double(done < total_ ? done : total_) / double(total_)), false);
    }
    if (cancelled()) throw Error(Status::Cancelled, "cancelled by the progress callback");
  }

  /// Final report (fraction 1) at the end of a successful call.
  void finish() { report(1.0, true); check(); }

 private:
  using Clock = std::chrono::steady_clock;

  void report(double fraction, bool force) {
    // Once the callback has asked to cancel it is not called again (the call is unwinding).
    if (!callback_ || cancelled() || std::this_thread::get_id() != owner_) return;
    const auto now = Clock::now();
    if (!force && now - last_ < std::chrono::milliseconds(50)) return;
    last_ = now;
    // Never back: a stage run again (the surface built a second time) holds the bar.
    fraction = std::max(fraction, reported_);
    reported_ = fraction;
    bool keep_going = true;
    try {
      keep_going = callback_(name_, fraction);
    } catch (...) {
      keep_going = false;  // a throwing callback cancels rather than unwinding through TBB
    }
    if (!keep_going) cancelled_.store(true, std::memory_order_relaxed);
  }

  const ProgressCallback& callback_;
  std::thread::id owner_;
  Clock::time_point last_;
  std::string name_;
  double begin_ = 0, end_ = 1;
  double reported_ = 0;  // the largest fraction reported
  uint64_t total_ = 1;
  std::atomic<uint64_t> done_{0};
  std::atomic<bool> cancelled_{false};
};

}  // namespace particlemesh::detail
