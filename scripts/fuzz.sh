#!/usr/bin/env bash
# Runs kozu's libFuzzer targets (tests/fuzz, built with KOZU_FUZZ=ON) from their corpora in tests/data/fuzz/:
# first every corpus input once (the regression cases: every input that ever crashed is kept there), then a
# fixed number of mutations per target from a fixed seed, so a run is reproducible. About 60 s in all on 2 cores.
# A crash, sanitizer report, timeout (5 s per input) or memory blow-up (2 GiB) fails the run and leaves the
# input in $OUT (default build-fuzz-findings/); add it to tests/data/fuzz/<target>/ once fixed.
#   scripts/fuzz.sh BUILD_DIR [SCALE]   (SCALE multiplies the mutation counts; default 1)
set -euo pipefail
cd "$(dirname "$0")/.."
build=${1:?usage: scripts/fuzz.sh BUILD_DIR [SCALE]}
scale=${2:-1}
out=${OUT:-build-fuzz-findings}
mkdir -p "$out"
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
export UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1
# kozu's own guard told the fuzzer's limit (below its 2 GiB, which counts the sanitizers' memory too): what the
# readers refuse before allocating is then tested against it (an EXR whose decoding blocks would not fit is refused
# before OpenEXR opens it).
export KOZU_MEMORY_LIMIT=1536M

# target  mutations  max input length  leak checks
# OpenImageIO keeps per-thread error strings and caches alive between inputs: with leak checks libFuzzer would
# scan the heap after every input (3 inputs/s) and report OpenImageIO's own allocations, so fuzz_image and
# fuzz_exr_part run without them; the other targets keep them.
targets=(
  "fuzz_scene 25000 8192 1"
  "fuzz_obj 80000 4096 1"
  "fuzz_ply 80000 4096 1"
  "fuzz_kvox 80000 4096 1"
  "fuzz_image 4000 4096 0"
  "fuzz_ies 80000 4096 1"
  "fuzz_checkpoint 40000 4096 1"
  "fuzz_exr_part 4000 4096 0"
  "fuzz_gltf 20000 8192 1"
)
status=0
for entry in "${targets[@]}"; do
  read -r target runs max_len leaks <<< "$entry"
  bin="$build/tests/fuzz/$target"
  [ -x "$bin" ] || { echo "fuzz.sh: $bin not built (configure with -DKOZU_FUZZ=ON)" >&2; exit 2; }
  corpus=tests/data/fuzz/$target
  dict=()
  [ -f "tests/fuzz/${target#fuzz_}.dict" ] && dict=(-dict="tests/fuzz/${target#fuzz_}.dict")
  mkdir -p "$work/$target"
  start=$(date +%s%N)
  # New inputs go to the scratch corpus (first folder); the checked-in corpus is read only.
  if ! ASAN_OPTIONS=detect_leaks=$leaks:abort_on_error=1 "$bin" "$work/$target" "$corpus" "${dict[@]}" -seed=1 -runs=$((runs * scale)) -max_len="$max_len" \
      -detect_leaks="$leaks" -timeout=5 -rss_limit_mb=2048 -max_total_time=$((15 * scale)) -artifact_prefix="$out/$target-" \
      -print_final_stats=1 > "$work/$target.log" 2>&1; then
    echo "== $target: FAILED"
    tail -60 "$work/$target.log"
    status=1
    continue
  fi
  execs=$(grep -o 'stat::number_of_executed_units: *[0-9]*' "$work/$target.log" | grep -o '[0-9]*$' || echo '?')
  ms=$((($(date +%s%N) - start) / 1000000))
  printf '== %s: %s inputs in %d.%03d s, no finding\n' "$target" "$execs" $((ms / 1000)) $((ms % 1000))
done
exit $status
