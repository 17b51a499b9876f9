#!/usr/bin/env bash
# Render time of two (binary, scene) pairs, alternating, on one thread: the medians of `render_seconds` and their ratio.
#   bench/ab_render.sh BIN_A SCENE_A BIN_B SCENE_B RUNS RESOLUTION SPP [extra kozu render arguments...]
# e.g. a build against another on one scene, or one build on a scene with and without a feature:
#   bench/ab_render.sh build/kozu /tmp/suite_np/interior.json build/kozu /tmp/suite/interior.json 5 256x256 16
# One thread and alternation keep the comparison fair on a shared, noisy machine (docs/performance.md).
set -euo pipefail
if [ $# -lt 7 ]; then
  sed -n '2,5p' "$0" >&2
  exit 2
fi
bin_a=$1 scene_a=$2 bin_b=$3 scene_b=$4 runs=$5 res=$6 spp=$7
shift 7
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
times_a=() times_b=()
for _ in $(seq "$runs"); do
  for which in a b; do
    if [ "$which" = a ]; then bin=$bin_a scene=$scene_a; else bin=$bin_b scene=$scene_b; fi
    "$bin" render "$scene" --resolution "$res" --spp "$spp" --threads 1 -q -o "$tmp/$which.exr" \
      --stats "$tmp/$which.json" "$@" >/dev/null
    t=$(python3 -c "import json, sys; print(json.load(open(sys.argv[1]))['render_seconds'])" "$tmp/$which.json")
    if [ "$which" = a ]; then times_a+=("$t"); else times_b+=("$t"); fi
  done
done
python3 - "${times_a[*]}" "${times_b[*]}" <<'PY'
import statistics, sys
a = [float(x) for x in sys.argv[1].split()]
b = [float(x) for x in sys.argv[2].split()]
print("A", " ".join(f"{x:.3f}" for x in a), f"median {statistics.median(a):.3f} s")
print("B", " ".join(f"{x:.3f}" for x in b), f"median {statistics.median(b):.3f} s")
print(f"B / A {statistics.median(b) / statistics.median(a):.3f}")
PY
