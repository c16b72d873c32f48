#!/usr/bin/env bash
# The README's test command: the same set-up as the demo, then every test suite (C++,
# C ABI, CLI, CMake package) through CTest; then the sanitizer build (ASan + UBSan + LSan:
# the C++ and C ABI suites, the fuzz regressions) and a short fuzz run of every target
# (scripts/sanitize.sh; PM_SANITIZE=0 skips it, PM_FUZZ_SECONDS sets the seconds per
# target). CI (.ci/run) runs exactly this.
set -euo pipefail

ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
"$ROOT/scripts/setup.sh"
BUILD="${PM_BUILD_DIR:-$ROOT/build}"
ctest --test-dir "$BUILD" --output-on-failure -j "$(nproc)"
if [ "${PM_SANITIZE:-1}" != 0 ]; then
  "$ROOT/scripts/sanitize.sh"
fi
