#!/usr/bin/env bash
# Equal-time error of direct lighting from a polygon light, "direct": "ltc" and "ltc-ratio" against "sample"
# (docs/lights.md); "sample-light" is "sample" with "light_sampling": "light" (no lobe-shaped light samples).
# For each scene: a reference with light sampling at REF_SPP, then RUNS renders of each mode with the same
# --time-limit; prints each run's RMS error against the reference (idiff, all channels, linear EXR), and the
# ratios of the median MSEs (sample / mode: above 1, the mode is better at equal time).
# With SECONDS given as a sample count, e.g. "32spp", each mode renders that many samples a pixel instead and the
# ratios are of the medians of MSE × render seconds (--stats render_seconds): the efficiency of the other benchmarks
# (docs/performance.md). Under a time limit the film has no sample count to plan for, so the emitters' edges are not
# supersampled (render.emission_supersampling) and the light's silhouette, seen by the camera, weighs on the error of
# the mode that takes fewer samples; at a sample count every mode gets it.
#   bench/ltc_equal_time.sh [KOZU] [SECONDS|Nspp] [RUNS] [REF_SPP] [SCENE...]
# Defaults: build/kozu, 2 s, 5 runs, 4096 spp, and docs/lights.md's six scenes: scenes/ltc_glossy.json and
# ltc_rough.json, each also without its sphere ("open"), the rough one with a plastic floor, and
# scenes/stained_glass.json at 320 x 180 with direct light only (written to a temporary folder).
set -euo pipefail
cd "$(dirname "$0")/.."
kozu=${1:-build/kozu}
seconds=${2:-2}
runs=${3:-5}
ref_spp=${4:-4096}
fixed_spp=
[[ "$seconds" == *spp ]] && fixed_spp=${seconds%spp}
measure="median MSE at $seconds s"
[ -n "$fixed_spp" ] && measure="median MSE x seconds at $fixed_spp spp"
shift $(($# < 4 ? $# : 4))
scenes=("$@")
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
if [ ${#scenes[@]} -eq 0 ]; then
  cp scenes/ltc_glossy.json scenes/ltc_rough.json "$out/"
  grep -v '"sphere"' scenes/ltc_glossy.json > "$out/ltc_glossy_open.json"
  grep -v '"sphere"' scenes/ltc_rough.json > "$out/ltc_rough_open.json"
  sed 's/"floor": *{[^}]*}/"floor": { "type": "plastic", "albedo": [0.35, 0.3, 0.25], "roughness": 0.3 }/' \
    scenes/ltc_rough.json > "$out/ltc_plastic.json"
  sed -e 's/"resolution": \[[0-9]*, [0-9]*\]/"resolution": [320, 180]/' -e 's/"max_depth": [0-9]*/"max_depth": 1/' \
    -e "s#\"textures/#\"$PWD/scenes/textures/#g" scenes/stained_glass.json > "$out/stained_glass_direct.json"
  scenes=("$out"/ltc_glossy.json "$out"/ltc_rough.json "$out"/ltc_glossy_open.json "$out"/ltc_rough_open.json
          "$out"/ltc_plastic.json "$out"/stained_glass_direct.json)
fi

rms() { idiff -v -a -fail 1e9 -warn 1e9 "$1" "$2" 2>&1 | sed -n 's/.*RMS error = \([0-9.e+-]*\).*/\1/p' | head -1; }
median() { sort -g | awk '{a[NR] = $1} END {print a[int((NR + 1) / 2)]}'; }

for scene in "${scenes[@]}"; do
  name=$(basename "$scene" .json)
  "$kozu" render "$scene" --spp "$ref_spp" -q -o "$out/$name.ref.exr"
  declare -A mse=()
  for mode in sample sample-light ltc ltc-ratio; do
    list=()
    for ((i = 0; i < runs; ++i)); do
      args=(--direct "$mode")
      [ "$mode" = sample-light ] && args=(--direct sample -D /render/light_sampling=light)
      budget=(--time-limit "$seconds")
      [ -n "$fixed_spp" ] && budget=(--spp "$fixed_spp")
      "$kozu" render "$scene" "${args[@]}" "${budget[@]}" --seed "$((i + 1))" -q \
        --stats "$out/$name.$mode.$i.json" -o "$out/$name.$mode.$i.exr"
      e=$(rms "$out/$name.$mode.$i.exr" "$out/$name.ref.exr")
      spp=$(sed -n 's/^ *"spp": \([0-9.e+-]*\),*/\1/p' "$out/$name.$mode.$i.json" | head -1)
      t=$(sed -n 's/^ *"render_seconds": \([0-9.e+-]*\),*/\1/p' "$out/$name.$mode.$i.json" | head -1)
      echo "$name $mode run $i: RMS error $e at $spp spp in $t s"
      if [ -n "$fixed_spp" ]; then
        list+=("$(awk -v e="$e" -v t="$t" 'BEGIN {printf "%.6e", e * e * t}')")
      else
        list+=("$(awk -v e="$e" 'BEGIN {printf "%.6e", e * e}')")
      fi
    done
    mse[$mode]=$(printf '%s\n' "${list[@]}" | median)
  done
  awk -v n="$name" -v s="${mse[sample]}" -v g="${mse[sample-light]}" -v l="${mse[ltc]}" -v r="${mse[ltc-ratio]}" \
    -v m="$measure" \
    'BEGIN {printf "%s: %s: sample %.4e, sample-light %.4e (%.2fx lower), ltc %.4e (%.2fx lower), ltc-ratio %.4e (%.2fx lower)\n", n, m, s, g, s / g, l, s / l, r, s / r}'
  unset mse
done
