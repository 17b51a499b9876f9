#!/bin/sh
# The Figure 18 idea of Heitz et al. 2015, "The SGGX Microflake Distribution" (ACM TOG 34(4), §6), on the voxelized bush: the mesh and
# its SGGX volume with automatic level of detail, rendered ever smaller (a pixel covering 1, 2, 4, 8, 16 times
# more of the bush, as if seen from farther away). kozu picks the MIP level from the pixel footprint
# (docs/volumes.md), so each halving of the image size moves one level down the chain. Writes
# docs/images/bush_lod_distance.png (rows: 320x240 … 20x15, nearest-neighbour enlarged; left mesh, right volume)
# and prints, per size, the level used (its memory: `kozu voxelize`'s table), samples/s and each image's mean.
#
# Usage (from the repository root, after a build and `kozu voxelize` of the bush, docs/volumes.md):
#   tools/make_lod_figure.sh            KOZU=build/kozu by default
set -eu
KOZU=${KOZU:-build/kozu}
out=${OUT:-out/lod}
mkdir -p "$out"
test -f scenes/volumes/bush.kvox || "$KOZU" voxelize scenes/meshes/bush.ply --resolution 128 -o scenes/volumes/bush.kvox
tiles=""
printf '%-8s %-6s %5s %14s %14s %26s %26s\n' size spp level mesh_samples/s vol_samples/s mesh_mean vol_mean
for w in 320 160 80 40 20; do
  h=$((w * 3 / 4))
  spp=$((32 * (320 / w) * (320 / w)))
  for s in mesh volume; do
    "$KOZU" render "scenes/bush_$s.json" --resolution "${w}x$h" --spp "$spp" --seed 1 -q \
      -o "$out/${s}_$w.exr" -o "$out/${s}_$w.png" --stats "$out/${s}_$w.json"
    oiiotool "$out/${s}_$w.png" --resample:interp=0 320x240 -o "$out/${s}_${w}_big.png"
  done
  tiles="$tiles $out/mesh_${w}_big.png $out/volume_${w}_big.png"
  python3 - "$out" "$w" "$spp" <<'EOF'
import json, subprocess, sys
out, w, spp = sys.argv[1], sys.argv[2], sys.argv[3]
m = json.load(open(f"{out}/mesh_{w}.json"))
v = json.load(open(f"{out}/volume_{w}.json"))
def mean(f):
    s = subprocess.run(["oiiotool", "--stats", f], capture_output=True, text=True).stdout
    line = next(l for l in s.splitlines() if "Stats Avg" in l)
    return " ".join(f"{float(x):.4f}" for x in line.split(":")[1].split()[:3])
b = v["media"]["bush"]
print(f"{w}x{int(w)*3//4:<5} {spp:<6} {b['lod']:5d} "
      f"{m['samples_per_second']:14.0f} {v['samples_per_second']:14.0f} "
      f"{mean(f'{out}/mesh_{w}.exr'):>26} {mean(f'{out}/volume_{w}.exr'):>26}")
EOF
done
# shellcheck disable=SC2086
oiiotool $tiles --mosaic:pad=4 2x5 -o docs/images/bush_lod_distance.png
echo "wrote docs/images/bush_lod_distance.png"
