#!/usr/bin/env bash
# A contact sheet of an animation's frames: every STEP-th PNG of DIR, shrunk to WIDTH pixels wide, in a grid of
# COLUMNS (OpenImageIO's oiiotool, which kozu's install brings).
#   scripts/contact-sheet.sh DIR OUT.png [STEP=5] [COLUMNS=4] [WIDTH=320]
set -euo pipefail
dir=${1:?usage: contact-sheet.sh DIR OUT.png [STEP] [COLUMNS] [WIDTH]}
out=${2:?usage: contact-sheet.sh DIR OUT.png [STEP] [COLUMNS] [WIDTH]}
step=${3:-5}
columns=${4:-4}
width=${5:-320}
mapfile -t frames < <(find "$dir" -maxdepth 1 -name '*.png' | sort)
[ ${#frames[@]} -gt 0 ] || { echo "contact-sheet.sh: no PNG files in $dir" >&2; exit 1; }
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
picked=()
for ((i = 0; i < ${#frames[@]}; i += step)); do
  oiiotool "${frames[$i]}" --resize "${width}x0" -o "$tmp/$(printf %05d "$i").png"
  picked+=("$tmp/$(printf %05d "$i").png")
done
rows=$(((${#picked[@]} + columns - 1) / columns))
oiiotool "${picked[@]}" --mosaic:pad=4 "${columns}x${rows}" -o "$out"
echo "$out: ${#picked[@]} frames (every ${step}th of ${#frames[@]}), ${columns}x${rows}"
