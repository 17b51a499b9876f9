#!/usr/bin/env bash
# Quick start (b): install what is missing, build kozu with its tests and benchmarks, and run the
# whole test suite twice: in the Release build (GCC; then checking its dependencies against the install list), and
# in an AddressSanitizer + UBSan build (clang); then that build's fuzz targets, for about a minute, and 24 renders
# of mutated scenes (scripts/fuzz-scenes.py).
# Extra arguments are passed to both ctest runs (e.g. -L unit, or -R test_io: ctest runs each test binary as one
# test; configure with -DKOZU_TEST_PER_BINARY=OFF for one ctest entry per GoogleTest test).
set -euo pipefail
cd "$(dirname "$0")/.."
# Each step says when it starts, so a slow one shows (CI must stay under 30 minutes on 2 cores).
step() { echo "== $1 (at $((SECONDS / 60))m$((SECONDS % 60))s)"; }
# With the optional test set: Blender, for the add-on's comparisons with Cycles (tests/blender).
./scripts/install-deps.sh --tests
jobs=$(nproc)

step "Release build"
cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=Release -DKOZU_BUILD_TESTS=ON -DKOZU_BUILD_BENCH=ON -DKOZU_MPI=ON \
  -DKOZU_PYTHON=ON
cmake --build build -j "$jobs"
# A fresh machine is the truth: every system header and library the build read must come from a package that
# install-deps.sh installs (or one they depend on), or the build only works here by accident.
step "Build dependencies against scripts/install-deps.sh --list"
check=../shared/tools/check-debian-deps
if [ -x "$check" ]; then
  # shellcheck disable=SC2046
  "$check" build $(./scripts/install-deps.sh --list)
elif [ "${KOZU_REQUIRE_DEPS_CHECK:-0}" = 1 ]; then
  echo "test.sh: $check not found (KOZU_REQUIRE_DEPS_CHECK=1, as in .ci/run)" >&2
  exit 1
else
  echo "test.sh: $check not found beside this checkout; dependency check skipped"
fi

step "Release tests"
ctest --test-dir build --output-on-failure --no-tests=error -j "$jobs" "$@"

step "AddressSanitizer + UndefinedBehaviorSanitizer build (clang, with the fuzz targets) and tests"
# One clang build serves the sanitizer tests and the libFuzzer targets (which need clang): kozu_core is compiled
# once for both, and clang compiles it about twice as fast as GCC (CI: 2 cores, 30 minutes).
# MPI is left out of this build (the MPI tests run in the Release build): the sanitizers would check OpenMPI's
# runtime, not kozu. So is the Python module: an instrumented extension needs the sanitizer runtime preloaded into
# the interpreter, which would then check Python and numpy; the code it binds is kozu_core's, tested here.
cmake -S . -B build-asan -G Ninja -DCMAKE_CXX_COMPILER=clang++ -DCMAKE_BUILD_TYPE=RelWithDebInfo -DKOZU_SANITIZE=ON \
  -DKOZU_FUZZ=ON -DKOZU_BUILD_TESTS=ON -DKOZU_BUILD_BENCH=OFF -DKOZU_MPI=OFF
cmake --build build-asan -j "$jobs"
# The three longest statistical binaries (5.4 CPU-minutes under the sanitizers: chi-square and furnace tests of
# millions of samples of the rough materials, the standard material and SGGX) run in the Release build only; the
# sanitizers still see that code through the other tests (furnace scenes, volume renders, the command's tests).
# With them CI took 30m10s on 2 cores; KOZU_ASAN_ALL=1 runs them too.
# The Blender comparisons (label blender) run in the Release pass only: under the sanitizers they would test the
# same kozu code on the same scenes, for about two more minutes.
asan_skip=()
[ "${KOZU_ASAN_ALL:-0}" = 1 ] || asan_skip=(-E '^(test_rough_materials_stat|test_standard_stat|test_sggx_stat)$' -LE blender)
ASAN_OPTIONS=detect_leaks=1:abort_on_error=1 UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 \
  ctest --test-dir build-asan --output-on-failure --no-tests=error -j "$jobs" "${asan_skip[@]}" "$@"

step "Fuzzing (libFuzzer, sanitizers on; scripts/fuzz.sh: the corpora, then fixed-seed mutations)"
./scripts/fuzz.sh build-asan
# Whole renders of mutated scenes under the sanitizers (libFuzzer's scene target only loads): a fixed set of 24.
step "Fuzzing whole renders (scripts/fuzz-scenes.py: 24 mutated scenes, sanitizer build)"
ASAN_OPTIONS=detect_leaks=1:abort_on_error=1 UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 \
  python3 scripts/fuzz-scenes.py --kozu build-asan/kozu --cases 24 --seed 1
step "done"
