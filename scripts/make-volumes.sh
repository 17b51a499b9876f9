#!/bin/sh
# Generates the voxel volume the bush showcase scenes read from scenes/volumes/ (git-ignored): the voxelized bush
# (bush_volume*.json). The smoke, yarn and fabric scenes need no file: they generate their voxels at load
# ("procedural"); `kozu procedural smoke|yarn|fabric -o FILE.kvox` writes the same voxels as files.
# Usage (from the repository root, after a build): scripts/make-volumes.sh [path/to/kozu]   (about 3 s)
set -eu
KOZU=${1:-build/kozu}
mkdir -p scenes/volumes
"$KOZU" voxelize scenes/meshes/bush.ply --resolution 128 -o scenes/volumes/bush.kvox
