#!/usr/bin/env bash
# The sanitizer build, run by scripts/test.sh after the normal suites:
#
#  1. configures build-asan/ with clang, AddressSanitizer + UndefinedBehaviorSanitizer (every
#     report is fatal) and libFuzzer's coverage instrumentation, and builds the library, the
#     PCL bridge, the C++ suites (native, hostile, bridge), the C ABI suites and the fuzz
#     targets. No CLI, no benchmarks, no pytest/Blender/CMake-package tests: they only drive the same
#     library code through a process boundary (an uninstrumented python would need the ASan
#     runtime preloaded), and the CLI's own code is covered by the Release suites;
#  2. runs them through CTest (LeakSanitizer checks every test process at exit);
#  3. fuzzes every target for PM_FUZZ_SECONDS seconds (default 10, a smoke run: longer
#     campaigns are scripts/fuzz.sh's; 0 = skip), two at a time.
#
# Usage: scripts/sanitize.sh   (env: PM_ASAN_BUILD_DIR, PM_FUZZ_SECONDS, PM_JOBS, PM_WITH_PCL=OFF)
set -euo pipefail

ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
BUILD="${PM_ASAN_BUILD_DIR:-$ROOT/build-asan}"
JOBS="${PM_JOBS:-$(nproc)}"

# The C ABI's plain-C tests link with clang (C): -fsanitize-link-c++-runtime and libstdc++
# give them the C++ parts of the UBSan runtime that the C++ library needs.
# -O1: fast enough to run the suites (1M-point cancellation runs use 100k under ASan), quicker
# to compile than -O2. fuzzer-no-link: coverage for libFuzzer in the library the fuzz
# targets link (the targets themselves add -fsanitize=fuzzer). The test programs' own sources
# (set-up and assertions) get -O0 and no coverage (they are not fuzzed): 2.4 times quicker to
# compile, the suites 10-20 % slower to run: about 1.5 minutes less in all on two cores
# (tests/CMakeLists.txt, PM_TEST_SOURCES_OPTIONS; bench/RESULTS.md, "The test command's time").
SAN="-fsanitize=address,undefined -fno-sanitize-recover=all -fno-omit-frame-pointer"
cmake -S "$ROOT" -B "$BUILD" -G Ninja \
  -DCMAKE_C_COMPILER=clang -DCMAKE_CXX_COMPILER=clang++ \
  -DCMAKE_BUILD_TYPE=RelWithDebInfo \
  -DCMAKE_C_FLAGS_RELWITHDEBINFO="-O1 -gline-tables-only" \
  -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O1 -gline-tables-only" \
  -DCMAKE_C_FLAGS="$SAN" \
  -DCMAKE_CXX_FLAGS="$SAN -fsanitize=fuzzer-no-link -Wno-unknown-warning-option" \
  -DCMAKE_EXE_LINKER_FLAGS="-fsanitize=address,undefined" \
  -DCMAKE_C_STANDARD_LIBRARIES="-fsanitize-link-c++-runtime -lstdc++" \
  -DCMAKE_SHARED_LINKER_FLAGS="-fsanitize=address,undefined" \
  -DPM_BUILD_CLI=OFF -DPM_BUILD_BENCH=OFF -DPM_PACKAGE_TESTS=OFF -DPM_PYTHON_TESTS=OFF \
  -DPM_BUILD_BLENDER_ADDON=OFF -DPM_BUILD_PYTHON=OFF -DPM_BUILD_FUZZERS=ON \
  -DPM_TEST_SOURCES_OPTIONS="-O0;-fno-sanitize=fuzzer-no-link" \
  -DPM_WITH_PCL="${PM_WITH_PCL:-ON}" \
  -DPM_SHARED_DATA_DIR="${PM_SHARED_DATA_DIR:-$ROOT/../shared/data}" >/dev/null
cmake --build "$BUILD" -j "$JOBS"

# Every report fails the run: ASan and UBSan stop the process (-fno-sanitize-recover, and
# halt_on_error for what is built without it), LeakSanitizer makes the exit status non-zero.
export ASAN_OPTIONS="detect_leaks=1:abort_on_error=0:strict_string_checks=1:detect_stack_use_after_return=1:check_initialization_order=1${ASAN_OPTIONS:+:$ASAN_OPTIONS}"
export UBSAN_OPTIONS="halt_on_error=1:print_stacktrace=1${UBSAN_OPTIONS:+:$UBSAN_OPTIONS}"
# Suppressions, if ever needed, go in tests/lsan.supp (none at present).
export LSAN_OPTIONS="suppressions=$ROOT/tests/lsan.supp${LSAN_OPTIONS:+:$LSAN_OPTIONS}"
# Left to the Release build, because they check results, not memory safety, and the
# sanitizers see the same code in the other tests (each run here costs 5-10 times the
# Release run):
#  - the determinism suite (whole runs repeated 6 times);
#  - the tests that compare whole outputs across thread counts;
#  - the million-point sphere (a size);
#  - how promptly a cancel returns (a time; the cancellation paths run here in
#    hostile.Cancellation.* and CApiHostile.*);
#  - the same stages repeated on more shapes, densities and jitters, or checked for
#    accuracy (the last block).
# Together they took a third of this suite's time (bench/RESULTS.md, "The test command's time").
RESULTS_ONLY=(
  'hostile\.Determinism\..*'
  'ReconstructSurface\.GrowthBlocksGiveTheSameSurfaceForAnyThreadCount'
  'ReconstructSurface\.NormalsDecidedByNeighbourVotesAreTheSameForAnyThreadCount'
  'ReconstructSurface\.SameOutputForAnyThreadCount'
  'Polygonize\.OutputDoesNotDependOnTheThreadCount'
  'PolygonizeAttributes\.TheValuesPolygonizeGivesItsVertices'
  'AnisotropicPolygonize\.SameMeshForAnyThreadCountAndVerticesOnTheSurface'
  'ReconstructSurface\.MillionPointSphere'
  'ReconstructSurface\.CancelsPromptly'
  # The same stages again on more shapes, densities and jitters, or checking an answer's
  # accuracy: every stage they run is run here by smaller tests of its own (and by the real
  # scans and SPH frames, which stay).
  'ReconstructSurface\.SpheresOfEveryDensityAreClosedOutwardGenusZero'
  'ReconstructSurface\.TorusTrefoilAndDoubleTorusKeepTheirGenus'
  'ReconstructSurface\.JitteredSamplingsStayManifoldAndOriented'
  'ReconstructSurface\.JitteredResampledModelsClose'
  'Polygonize\.GatheredAndDirectEvaluationsGiveTheSameMesh'
  'RayCaster\.FirstCrossingsOfSmallBlobsAndThinSheetsInFrontOfABlock'
  'Polygonize\.VerticesOnTheFieldAndAttributesAsItsWeights'
  # The same three scans as pcl_bridge.ParticleTriangulation.SharedScansReconstruct (which
  # stays), filtered by PCL first: the meshes' quality.
  'pcl_bridge\.Scans\.PreparedAsAPclUserWouldTheyMeshWhole'
)
if [ -z "${PM_SKIP_SUITES:-}" ]; then
  ctest --test-dir "$BUILD" --output-on-failure -j "$JOBS" -E "^($(IFS='|'; echo "${RESULTS_ONLY[*]}"))\$"
fi

SECONDS_PER_TARGET="${PM_FUZZ_SECONDS:-10}"
if [ "$SECONDS_PER_TARGET" -gt 0 ]; then
  # A fixed seed: the same commit explores the same inputs (see scripts/fuzz.sh).
  PM_FUZZ_SEED="${PM_FUZZ_SEED:-1}" PM_ASAN_BUILD_DIR="$BUILD" "$ROOT/scripts/fuzz.sh" all "$SECONDS_PER_TARGET"
fi
