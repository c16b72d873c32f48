// Shared helpers for the fuzz targets (tests/fuzz/fuzz_*.cpp).
//
// Every target defines LLVMFuzzerTestOneInput. Built with clang and PM_BUILD_FUZZERS=ON it
// links libFuzzer (-fsanitize=fuzzer); otherwise it links replay_main.cpp and replays the
// files it is given (the regression inputs under tests/data/fuzz_regressions/), so every
// crash ever found stays a test in the normal build too.
//
// A finding is: a crash or sanitizer report, an exception other than particlemesh::Error
// escaping the C++ API, PM_STATUS_INTERNAL from the C ABI, a broken promise of the API
// (checked with PM_FUZZ_CHECK), a time-out or an allocation beyond libFuzzer's
// -malloc_limit_mb (a size taken from the input before checking it).
#pragma once

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <string>
#include <type_traits>
#include <unistd.h>

#include "particlemesh/particlemesh.h"

/// A broken API promise: report it and abort, so libFuzzer (or the replay) records it.
#define PM_FUZZ_CHECK(cond)                                                                   \
  do {                                                                                        \
    if (!(cond)) {                                                                            \
      std::fprintf(stderr, "fuzz check failed: %s (%s:%d)\n", #cond, __FILE__, __LINE__);     \
      std::abort();                                                                           \
    }                                                                                         \
  } while (0)

namespace particlemesh::fuzz {

/// Write the input to a file with the given extension (the readers pick the format by it)
/// and return its path. One file per process and extension, rewritten for every input, in
/// /dev/shm when it exists (no disk traffic).
inline const std::string& temp_file(const char* extension, const uint8_t* data, size_t size) {
  static std::string path;
  namespace fs = std::filesystem;
  std::error_code ec;
  fs::path dir = fs::exists("/dev/shm", ec) ? fs::path("/dev/shm") : fs::temp_directory_path();
  path = (dir / ("pm_fuzz_" + std::to_string(::getpid()) + extension)).string();
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(reinterpret_cast<const char*>(data), std::streamsize(size));
  out.close();
  if (!out) {
    std::fprintf(stderr, "cannot write the fuzz input to %s\n", path.c_str());
    std::abort();
  }
  return path;
}

/// Remove the per-process temporary files at exit.
struct TempFileCleanup {
  const char* extension;
  ~TempFileCleanup() {
    std::error_code ec;
    std::filesystem::remove("/dev/shm/pm_fuzz_" + std::to_string(::getpid()) + extension, ec);
    std::filesystem::remove(std::filesystem::temp_directory_path() /
                                ("pm_fuzz_" + std::to_string(::getpid()) + extension),
                            ec);
  }
};

/// Checks every C ABI status: a known code, a message on failure, never INTERNAL (a bug),
/// never OUT_OF_MEMORY for the small inputs a fuzzer makes (a size taken on trust).
inline void check_status(pm_status s) {
  PM_FUZZ_CHECK(int(s) >= 0 && int(s) <= int(PM_STATUS_INTERNAL));
  if (s != PM_OK) PM_FUZZ_CHECK(pm_last_error_message()[0] != '\0');
  if (s == PM_STATUS_INTERNAL || s == PM_STATUS_OUT_OF_MEMORY)
    std::fprintf(stderr, "unexpected status %s: %s\n", pm_status_string(s), pm_last_error_message());
  PM_FUZZ_CHECK(s != PM_STATUS_INTERNAL);
  PM_FUZZ_CHECK(s != PM_STATUS_OUT_OF_MEMORY);
}

/// Takes values from the front of the fuzz input; zeros once it is exhausted. (libFuzzer's
/// FuzzedDataProvider would do, but the replay build must not depend on clang's headers.)
class Input {
 public:
  Input(const uint8_t* data, size_t size) : p_(data), end_(data + size) {}

  size_t remaining() const { return size_t(end_ - p_); }

  template <class T>
  T take() {
    static_assert(std::is_trivially_copyable_v<T>);
    T v{};
    const size_t n = std::min(sizeof(T), remaining());
    std::memcpy(&v, p_, n);
    p_ += n;
    return v;
  }

  /// An integer in [lo, hi].
  uint64_t range(uint64_t lo, uint64_t hi) {
    const uint64_t span = hi - lo + 1;
    const uint64_t v = span <= 0x100 ? take<uint8_t>() : span <= 0x10000 ? take<uint16_t>() : take<uint64_t>();
    return span == 0 ? v : lo + v % span;
  }

  bool flag() { return take<uint8_t>() & 1; }

  /// A double that is usually meaningful: a small integer, a scaled grid value, one of the
  /// special values (0, -0, NaN, +-Inf, denormal, huge) or raw bits.
  double number(double scale = 1.0) {
    const uint8_t mode = take<uint8_t>();
    switch (mode % 8) {
      case 0: return double(int8_t(take<uint8_t>())) * scale;
      case 1: return double(int16_t(take<uint16_t>())) * (scale / 256.0);
      case 2: {
        static const double special[] = {0.0,
                                         -0.0,
                                         std::numeric_limits<double>::quiet_NaN(),
                                         std::numeric_limits<double>::infinity(),
                                         -std::numeric_limits<double>::infinity(),
                                         std::numeric_limits<double>::denorm_min(),
                                         std::numeric_limits<double>::max(),
                                         -std::numeric_limits<double>::max(),
                                         1e-300,
                                         1e300,
                                         std::numeric_limits<double>::epsilon(),
                                         1.0};
        return special[take<uint8_t>() % (sizeof(special) / sizeof(special[0]))];
      }
      case 3: return take<double>();
      case 4: return double(take<float>());
      default: return double(int8_t(take<uint8_t>())) * scale * 0.25 + double(take<uint8_t>()) * scale / 1024.0;
    }
  }

 private:
  const uint8_t* p_;
  const uint8_t* end_;
};

}  // namespace particlemesh::fuzz
