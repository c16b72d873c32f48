#!/usr/bin/env bash
# The README's test command: the same set-up as the demo, then every test suite (C++,
# C ABI, CLI, CMake package) through CTest. CI (.ci/run) runs exactly this.
set -euo pipefail

ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
"$ROOT/scripts/setup.sh"
BUILD="${PM_BUILD_DIR:-$ROOT/build}"
ctest --test-dir "$BUILD" --output-on-failure -j "$(nproc)"
