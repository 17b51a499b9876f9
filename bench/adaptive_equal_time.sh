#!/usr/bin/env bash
# Adaptive sampling at equal time (docs/production.md): uniform sampling and render.noise_threshold (min_spp 64)
# each given the same --time-limit, three seeds each, on the demo (320x180) and the Cornell box (256x256); error:
# the RMS difference (idiff -a) of the linear EXR from a 1024-spp reference of another seed. Usage:
# bench/adaptive_equal_time.sh [KOZU] [SECONDS] (defaults build/kozu, 8). Needs OpenImageIO's idiff and python3.
set -euo pipefail
cd "$(dirname "$0")/.."
kozu=$(realpath "${1:-build/kozu}")
limit=${2:-8}
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
rms() { { idiff -a "$1" "$2" || true; } 2>&1 | grep -o "RMS error = [0-9.e+-]*" | awk '{print $4}'; }
for scene in demo cornell; do
  if [ $scene = cornell ]; then src=(scenes/cornell.json --resolution 256x256); else src=(--demo --resolution 320x180); fi
  "$kozu" render "${src[@]}" --spp 1024 --seed 1000 --quiet -o "$out/ref.exr"
  for cfg in uniform 0.05 0.02; do
    errors=() spps=()
    for seed in 1 2 3; do
      extra=(--spp 0)
      [ $cfg != uniform ] && extra+=(-D /render/noise_threshold=$cfg -D /render/min_spp=64)
      "$kozu" render "${src[@]}" "${extra[@]}" --time-limit "$limit" --seed $seed --quiet -o "$out/r.exr" \
        --stats "$out/r.json"
      errors+=("$(rms "$out/r.exr" "$out/ref.exr")")
      spps+=("$(python3 -c "import json; print(round(json.load(open('$out/r.json'))['spp'], 1))")")
    done
    echo "$scene $cfg: RMS ${errors[*]}; mean spp ${spps[*]}"
  done
done
