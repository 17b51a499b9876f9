#!/usr/bin/env bash
# Regenerates tests/data/cornell_ref.exr, the reference of the Cornell-box regression test
# (tests/integrators/test_path_regression.cpp): scenes/cornell.json at 64x64, 65536 spp, seed 0.
# Run from the repository root after building (build/kozu). Takes a few minutes on 2 cores.
set -euo pipefail
kozu=${KOZU:-build/kozu}
"$kozu" render scenes/cornell.json --resolution 64x64 --spp 65536 --seed 0 \
  -o tests/data/cornell_ref.exr --stats tests/data/cornell_ref.stats.json
