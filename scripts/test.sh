#!/usr/bin/env bash
# Quick start (b): install what is missing, build kozu with its tests and benchmarks, and run the
# whole test suite twice: in the Release build, and in an AddressSanitizer + UBSan build.
# Extra arguments are passed to both ctest runs (e.g. -L unit, or -R Cornell).
set -euo pipefail
cd "$(dirname "$0")/.."
./scripts/install-deps.sh
jobs=$(nproc)

echo "== Release build and tests"
cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=Release -DKOZU_BUILD_TESTS=ON -DKOZU_BUILD_BENCH=ON
cmake --build build -j "$jobs"
ctest --test-dir build --output-on-failure --no-tests=error -j "$jobs" "$@"

echo "== AddressSanitizer + UndefinedBehaviorSanitizer build and tests"
cmake -S . -B build-asan -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo -DKOZU_SANITIZE=ON -DKOZU_BUILD_TESTS=ON -DKOZU_BUILD_BENCH=OFF
cmake --build build-asan -j "$jobs"
ASAN_OPTIONS=detect_leaks=1:abort_on_error=1 UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 \
  ctest --test-dir build-asan --output-on-failure --no-tests=error -j "$jobs" "$@"
