#!/usr/bin/env bash
# Set-up shared by the README's two commands: install the Debian packages that are missing,
# then configure and build everything but the benchmarks into build/. Safe to run again: it
# only does what is not done yet. Needs root (or sudo) only when a package is missing.
set -euo pipefail

ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
BUILD="${PM_BUILD_DIR:-$ROOT/build}"

# Every package the build, the tests and the demo need, from Debian 12.
PACKAGES=(
  build-essential cmake ninja-build pkg-config
  libtbb-dev libopenmesh-dev libosd-dev libeigen3-dev
  libcli11-dev nlohmann-json3-dev
  libpng-dev
  liblz4-dev liblzma-dev  # VTK XML arrays compressed with LZ4 or LZMA (zlib comes with libpng-dev)
  libblosc-dev  # Houdini's .bgeo.sc (Blosc-compressed blocks)
  libgtest-dev libgmock-dev
  python3 python3-numpy python3-pytest
  python3-blosc  # the CLI tests write .bgeo.sc files as Houdini does
  python3-vtk9  # tests/python/test_vtk_files.py: files written by VTK's own writers
  patchelf  # RUNPATH $ORIGIN on the libraries the Python package and the add-on zip carry
  debootstrap  # scripts/test_addon_portable.sh: the add-on zip in a bare Debian 12
  python3-pip python3-setuptools python3-wheel  # `pip install build/python` (offline) and its test
  blender
  libpcl-dev
  clang llvm libclang-rt-14-dev  # the sanitizer build and libFuzzer (scripts/sanitize.sh, fuzz.sh)
  python3-distributed python3-scipy  # particlemesh.distributed (Dask; SciPy: connected components) and its tests
)
# The benchmarks (bench/) are built only when asked: PM_BUILD_BENCH=ON ./scripts/setup.sh.
# Once asked, the build folder remembers it (and its peers' packages stay in the list);
# PM_BUILD_BENCH=OFF turns them off again.
BENCH_OPTION=()
bench="${PM_BUILD_BENCH:-}"
if [ -n "$bench" ]; then
  BENCH_OPTION=(-DPM_BUILD_BENCH="$bench")
elif grep -qs '^PM_BUILD_BENCH:BOOL=ON$' "$BUILD/CMakeCache.txt"; then
  bench=ON
fi
case "$bench" in
  ON|on|1|TRUE|true|YES|yes)
    PACKAGES+=(
      libbenchmark-dev  # Google Benchmark: the benchmarks' timing loops
      libopenvdb-dev  # the polygonize benchmark's peer
      libcgal-dev     # the scan benchmark's advancing-front peer
      libembree-dev   # the ray-casting benchmark's peer, with OpenVDB's mesh
    ) ;;
esac

missing=()
for p in "${PACKAGES[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done
if [ ${#missing[@]} -gt 0 ]; then
  echo "setup: installing ${missing[*]}"
  SUDO=""
  if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
  $SUDO apt-get update -q
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -q --no-install-recommends "${missing[@]}"
fi

cmake -S "$ROOT" -B "$BUILD" -G Ninja -DCMAKE_BUILD_TYPE=Release "${BENCH_OPTION[@]}" \
  -DPM_SHARED_DATA_DIR="${PM_SHARED_DATA_DIR:-$ROOT/../shared/data}" >/dev/null
cmake --build "$BUILD" -j "$(nproc)"
