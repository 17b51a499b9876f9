#!/usr/bin/env bash
# How well --budget holds (docs/production.md): renders the built-in demo (1920x1080, EXR + PNG, with --denoise:
# the raw images, then the denoised ones if they fit) under each budget, timing each run from outside the process,
# and prints each run's wall time, its margin, the spp it reached and whether the denoised images were written,
# then the worst margin.
#   bench/budget_adherence.sh [--load] [--kozu PATH] [BUDGET...]
# --load: another kozu render (the demo at 2 threads, endless) competes for the cores during every run, as on a
#         shared machine.
# Defaults: build/kozu; 20 budgets from 2 to 123 s (camp 6's limit): 2 3 4 5 6 8 10 12 15 20 25 30 40 50 60 75 90 100
#           110 123 (about 14 minutes).
set -euo pipefail
cd "$(dirname "$0")/.."
kozu=build/kozu
load=0
budgets=()
while [ $# -gt 0 ]; do
  case "$1" in
    --load) load=1 ;;
    --kozu) kozu=$2; shift ;;
    *) budgets+=("$1") ;;
  esac
  shift
done
[ ${#budgets[@]} -gt 0 ] || budgets=(2 3 4 5 6 8 10 12 15 20 25 30 40 50 60 75 90 100 110 123)
out=$(mktemp -d)
competitor=
cleanup() {
  [ -n "$competitor" ] && kill "$competitor" 2>/dev/null || true
  rm -rf "$out"
}
trap cleanup EXIT
if [ "$load" = 1 ]; then
  mkdir -p "$out/load"
  "$kozu" render --demo --threads 2 --spp 0 --time-limit 1e6 -q -o "$out/load/l.exr" >/dev/null 2>&1 &
  competitor=$!
  sleep 3  # let it load and start sampling
  echo "load: kozu render --demo --threads 2 (pid $competitor) competing"
fi
# The demo's generated textures are made once into the output folder's cache (as on a user's second run).
"$kozu" render --demo --spp 1 --resolution 64x36 -q -o "$out/d.png"
rm -f "$out"/d.*
worst=1e9
refused=0
for b in "${budgets[@]}"; do
  start=$(date +%s.%N)
  status=0
  "$kozu" render --demo --budget "$b" --denoise -q -o "$out/d.exr" -o "$out/d.png" --stats "$out/d.json" \
    2>"$out/err.txt" || status=$?
  end=$(date +%s.%N)
  if [ "$status" != 0 ]; then
    # A budget that cannot hold the writes after loading is refused at once, nothing rendered (docs/production.md).
    if grep -q "nothing rendered" "$out/err.txt"; then
      awk -v b="$b" -v s="$start" -v e="$end" 'BEGIN { printf "budget %5.1f s: refused after %.3f s (cannot hold the writes after loading)\n", b, e - s }'
      refused=$((refused + 1))
      continue
    fi
    echo "budget $b: exit status $status" >&2
    cat "$out/err.txt" >&2
    exit 1
  fi
  [ -s "$out/d.exr" ] && [ -s "$out/d.png" ] || { echo "budget $b: an image is missing" >&2; exit 1; }
  denoised=no
  [ -s "$out/d.denoised.png" ] && denoised=yes
  spp=$(sed -n 's/^ *"spp": \([0-9.e+-]*\),*/\1/p' "$out/d.json" | head -1)
  line=$(awk -v b="$b" -v s="$start" -v e="$end" -v spp="$spp" -v dn="$denoised" 'BEGIN {
    w = e - s; printf "budget %5.1f s: wall %7.3f s, margin %6.3f s, %5.1f spp, denoised %s\n", b, w, b - w, spp, dn }')
  echo "$line"
  m=$(echo "$line" | sed -n 's/.*margin *\([-0-9.]*\) s.*/\1/p')
  worst=$(awk -v a="$worst" -v m="$m" 'BEGIN { print (m < a ? m : a) }')
  rm -f "$out"/d.*
done
echo "worst margin over $((${#budgets[@]} - refused)) runs$([ "$load" = 1 ] && echo " (loaded)"): $worst s (negative: the budget was overrun); $refused refused"
