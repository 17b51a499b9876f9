#!/usr/bin/env bash
# How well --budget holds (docs/production.md): renders the demo (1280x720, EXR + PNG) under budgets from 2 to 20 s,
# timing each run from outside the process, and prints each run's wall time, its margin and the spp it reached, then
# the worst margin.
#   bench/budget_adherence.sh [KOZU] [BUDGET...]
# Defaults: build/kozu, budgets 2 3 4 ... 20 minus a few (20 runs: 2..20 and 2 again).
set -euo pipefail
cd "$(dirname "$0")/.."
kozu=${1:-build/kozu}
shift $(($# < 1 ? $# : 1))
budgets=("$@")
[ ${#budgets[@]} -gt 0 ] || budgets=(2 3 4 5 6 7 8 9 10 11 12 13 14 15 16 17 18 19 20 2)
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
worst=1e9
for b in "${budgets[@]}"; do
  start=$(date +%s.%N)
  "$kozu" render --demo --budget "$b" -q -o "$out/d.exr" -o "$out/d.png" --stats "$out/d.json" 2>/dev/null
  end=$(date +%s.%N)
  [ -s "$out/d.exr" ] && [ -s "$out/d.png" ] || { echo "budget $b: an image is missing" >&2; exit 1; }
  spp=$(sed -n 's/^ *"spp": \([0-9.e+-]*\),*/\1/p' "$out/d.json" | head -1)
  line=$(awk -v b="$b" -v s="$start" -v e="$end" -v spp="$spp" 'BEGIN {
    w = e - s; printf "budget %5.1f s: wall %6.3f s, margin %6.3f s, %.1f spp\n", b, w, b - w, spp }')
  echo "$line"
  m=$(echo "$line" | sed -n 's/.*margin *\([-0-9.]*\) s.*/\1/p')
  worst=$(awk -v a="$worst" -v m="$m" 'BEGIN { print (m < a ? m : a) }')
  rm -f "$out"/d.*
done
echo "worst margin over ${#budgets[@]} runs: $worst s (negative: the budget was overrun)"
