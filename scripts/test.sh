#!/usr/bin/env bash
# The README's test command: the same set-up as the demo, then every test suite (C++,
# C ABI, CLI, CMake package, Python package, Blender add-on) through CTest; the add-on zip in
# a bare Debian 12 (scripts/test_addon_portable.sh, beside the rest); then the sanitizer
# build (ASan + UBSan + LSan: the C++ and C ABI suites, the fuzz regressions) and a short
# fuzz run of every target (scripts/sanitize.sh; PM_SANITIZE=0 skips it, PM_FUZZ_SECONDS
# sets the seconds per target). CI (.ci/run) runs exactly this.
set -euo pipefail

ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
"$ROOT/scripts/setup.sh"
BUILD="${PM_BUILD_DIR:-$ROOT/build}"

# The add-on zip in a bare Debian 12 root with only Debian's blender (needs root and Debian's
# mirror; PM_PORTABLE=0 skips it). Most of its 2 minutes are downloads and unpacking, so it
# runs beside the suites below, its output kept in a log and shown when it ends; the script
# waits for it whatever happens, so no root is left half made or mounted.
portable_pid=""
portable_log="$BUILD/test_addon_portable.log"
finish_portable() {
  [ -n "$portable_pid" ] || return 0
  local rc=0
  wait "$portable_pid" || rc=$?
  portable_pid=""
  cat "$portable_log"
  return $rc
}
trap 'finish_portable >/dev/null 2>&1 || true' EXIT
if [ "${PM_PORTABLE:-1}" != 0 ]; then
  if [ "$(id -u)" -eq 0 ]; then
    "$ROOT/scripts/test_addon_portable.sh" >"$portable_log" 2>&1 &
    portable_pid=$!
  else
    echo "test.sh: scripts/test_addon_portable.sh SKIPPED: it needs root (debootstrap, chroot)"
  fi
fi

ctest --test-dir "$BUILD" --output-on-failure -j "$(nproc)"
if [ "${PM_SANITIZE:-1}" != 0 ]; then
  "$ROOT/scripts/sanitize.sh"
fi
if ! finish_portable; then
  echo "test.sh: the add-on in a bare Debian 12 FAILED (scripts/test_addon_portable.sh, log above)" >&2
  exit 1
fi
