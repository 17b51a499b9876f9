#!/usr/bin/env bash
# Adaptive sampling at equal time (docs/production.md): uniform sampling and render.noise_threshold (min_spp 64)
# each given the same --time-limit (an adaptive render may end sooner, when every pixel has converged), three seeds
# each, on the demo (320x180) and the Cornell box (256x256); error: the RMS difference (idiff -a) from a reference of
# another seed, of the linear EXR and of the display-referred image (RGB clamped to [0, 1], sRGB-encoded). Prints
# per configuration the three errors and mean spp, and the render seconds. Usage:
#   bench/adaptive_equal_time.sh [KOZU] [SECONDS] [REF_SPP] (defaults build/kozu, 8, 4096)
# Needs OpenImageIO's idiff and oiiotool, and python3.
set -euo pipefail
cd "$(dirname "$0")/.."
kozu=$(realpath "${1:-build/kozu}")
limit=${2:-8}
ref_spp=${3:-4096}
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
rms() { { idiff -a "$1" "$2" || true; } 2>&1 | grep -o "RMS error = [0-9.e+-]*" | awk '{print $4}'; }
display() { oiiotool "$1" --ch R,G,B --clamp:min=0:max=1 --colorconvert linear sRGB -d float -o "$2"; }
stat() { python3 -c "import json; d=json.load(open('$1')); print(round(d['$2'], ${3:-1}))"; }
for scene in demo cornell; do
  if [ $scene = cornell ]; then src=(scenes/cornell.json --resolution 256x256); else src=(--demo --resolution 320x180); fi
  "$kozu" render "${src[@]}" --spp "$ref_spp" --seed 1000 --quiet -o "$out/ref.exr"
  display "$out/ref.exr" "$out/ref.d.exr"
  for cfg in uniform 0.05 0.02 0.01; do
    lin=() disp=() spps=() secs=()
    for seed in 1 2 3; do
      extra=(--spp 0)
      [ $cfg != uniform ] && extra+=(-D /render/noise_threshold=$cfg -D /render/min_spp=64)
      "$kozu" render "${src[@]}" "${extra[@]}" --time-limit "$limit" --seed $seed --quiet -o "$out/r.exr" \
        --stats "$out/r.json"
      display "$out/r.exr" "$out/r.d.exr"
      lin+=("$(rms "$out/r.exr" "$out/ref.exr")")
      disp+=("$(rms "$out/r.d.exr" "$out/ref.d.exr")")
      spps+=("$(stat "$out/r.json" spp)")
      secs+=("$(stat "$out/r.json" render_seconds 2)")
    done
    echo "$scene $cfg: RMS linear ${lin[*]}; display ${disp[*]}; mean spp ${spps[*]}; seconds ${secs[*]}"
  done
done
