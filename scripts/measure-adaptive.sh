#!/bin/bash
# Adaptive sampling (render.noise_threshold) against uniform sampling at equal samples (docs/production.md): each
# adaptive run is capped at 256 spp, then a uniform run takes its mean spp; RMS error (idiff -a) of the linear EXR
# and the ACES PNG against a 2048 spp reference of another seed. Usage: scripts/measure-adaptive.sh [BUILD_DIR]
set -euo pipefail
cd "$(dirname "$0")/.."
kozu="${1:-build}/kozu"
out=$(mktemp -d)
for scene in cornell demo; do
  if [ $scene = cornell ]; then src=(scenes/cornell.json --resolution 128x128); else src=(--demo --resolution 160x90); fi
  ref=$out/${scene}_ref
  "$kozu" render "${src[@]}" --spp 2048 --seed 1000 -q -o $ref.exr -o $ref.png
  for cfg in "0.02 16" "0.05 64" "0.1 64"; do
    set -- $cfg
    a=$out/${scene}_$1_$2
    "$kozu" render "${src[@]}" --spp 256 --seed 1 --threads 2 -q -o $a.exr -o $a.png --stats $a.json \
      -D /render/noise_threshold=$1 -D /render/min_spp=$2
    mean=$(python3 -c "import json; print(round(json.load(open('$a.json'))['spp']))")
    u=$out/${scene}_uniform_$mean
    "$kozu" render "${src[@]}" --spp $mean --seed 1 --threads 2 -q -o $u.exr -o $u.png --stats $u.json
    for f in $a $u; do
      linear=$(idiff -a $f.exr $ref.exr 2>&1 | grep -o "RMS error = [0-9.e+-]*" | awk '{print $4}' || true)
      png=$(idiff -a $f.png $ref.png 2>&1 | grep -o "RMS error = [0-9.e+-]*" | awk '{print $4}' || true)
      spp=$(python3 -c "import json; j = json.load(open('$f.json')); print(round(j['spp'], 1), j['spp_min'], j['spp_max'])")
      echo "$(basename $f): RMS linear $linear, PNG $png; spp mean min max: $spp"
    done
  done
done
rm -rf "$out"
