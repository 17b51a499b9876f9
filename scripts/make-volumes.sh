#!/bin/sh
# Generates the voxel volumes the showcase scenes read from scenes/volumes/ (git-ignored): the voxelized bush
# (bush_volume*.json), the smoke plume, the ball of yarn and the woven fabric (smoke/yarn/fabric.json).
# Usage (from the repository root, after a build): scripts/make-volumes.sh [path/to/kozu]   (about 3 s)
set -eu
KOZU=${1:-build/kozu}
mkdir -p scenes/volumes
"$KOZU" voxelize scenes/meshes/bush.ply --resolution 128 -o scenes/volumes/bush.kvox
for kind in smoke yarn fabric; do
  "$KOZU" procedural "$kind" -o "scenes/volumes/$kind.kvox"
done
