#!/usr/bin/env bash
# Thread scaling of `kozu render` (docs/performance.md, "The machine's limit"): each scene rendered RUNS times on 1
# thread and on 2, alternating, at RES x RES and SPP samples per pixel; prints the median samples/s of each and
# their ratio (2 threads over 1; 2 is perfect scaling), and the peak resident memory of the 2-thread runs.
#   bench/thread_scaling.sh [KOZU] [RES] [SPP] [RUNS] SCENE.json...
# Defaults: build/kozu, 512, 16, 3; without scenes, the built-in demo and scenes/cornell.json. The Cycles
# comparison's scenes are written by `python3 bench/cycles/compare.py` into /tmp/kozu-cycles/NAME.json.
set -euo pipefail
cd "$(dirname "$0")/.."
kozu=${1:-build/kozu}
res=${2:-512}
spp=${3:-16}
runs=${4:-3}
shift $(($# < 4 ? $# : 4))
scenes=("$@")
[ ${#scenes[@]} -gt 0 ] || scenes=(demo scenes/cornell.json)
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT

median() { sort -g | awk '{a[NR] = $1} END {print a[int((NR + 1) / 2)]}'; }

echo "| scene | samples/s, 1 thread | samples/s, 2 threads | 2 threads / 1 | peak MiB (2 threads) |"
echo "| --- | ---: | ---: | ---: | ---: |"
for scene in "${scenes[@]}"; do
  name=$(basename "$scene" .json)
  declare -A rate=()
  peak=0
  for t in 1 2; do rate[$t]=""; done
  for ((i = 0; i < runs; ++i)); do
    for t in 1 2; do
      if [ "$scene" = demo ]; then src=(render --demo); else src=(render "$scene"); fi
      /usr/bin/time -f '%M' -o "$out/mem" "$kozu" "${src[@]}" --resolution "${res}x${res}" --spp "$spp" \
        --threads "$t" -q --stats "$out/stats.json" -o "$out/image.exr" > /dev/null
      r=$(sed -n 's/^ *"samples_per_second": \([0-9.e+-]*\),*/\1/p' "$out/stats.json" | head -1)
      rate[$t]+="$r "
      if [ "$t" = 2 ]; then peak=$(awk -v a="$peak" -v b="$(tail -1 "$out/mem")" 'BEGIN {print (b > a ? b : a)}'); fi
    done
  done
  one=$(printf '%s\n' ${rate[1]} | median)
  two=$(printf '%s\n' ${rate[2]} | median)
  awk -v n="$name" -v a="$one" -v b="$two" -v m="$peak" \
    'BEGIN {printf "| %s | %.0f | %.0f | %.2f | %.0f |\n", n, a, b, b / a, m / 1024}'
  unset rate
done
