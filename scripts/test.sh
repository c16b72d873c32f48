#!/usr/bin/env bash
# The README's test command: the same set-up as the demo, then every test suite (C++,
# C ABI, CLI, CMake package, Python package, Blender add-on) through CTest; the add-on zip in a
# bare Debian 12 (scripts/test_addon_portable.sh); then the sanitizer build (ASan + UBSan + LSan:
# the C++ and C ABI suites, the fuzz regressions) and a short fuzz run of every target
# (scripts/sanitize.sh; PM_SANITIZE=0 skips it, PM_FUZZ_SECONDS sets the seconds per
# target). CI (.ci/run) runs exactly this.
set -euo pipefail

ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
"$ROOT/scripts/setup.sh"
BUILD="${PM_BUILD_DIR:-$ROOT/build}"
ctest --test-dir "$BUILD" --output-on-failure -j "$(nproc)"
# The add-on zip in a bare Debian 12 root with only Debian's blender (about 2 minutes, needs
# root and Debian's mirror; PM_PORTABLE=0 skips it).
if [ "${PM_PORTABLE:-1}" != 0 ]; then
  if [ "$(id -u)" -eq 0 ]; then
    "$ROOT/scripts/test_addon_portable.sh"
  else
    echo "test.sh: scripts/test_addon_portable.sh SKIPPED: it needs root (debootstrap, chroot)"
  fi
fi
if [ "${PM_SANITIZE:-1}" != 0 ]; then
  "$ROOT/scripts/sanitize.sh"
fi
