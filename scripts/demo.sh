#!/usr/bin/env bash
# Quick start (a): install what is missing, build kozu (Release), and render the built-in demo
# scene (1920x1080 within the camp's 123-second budget, denoised) into out/demo.exr (linear float RGB),
# out/demo.png (tone-mapped sRGB) and out/demo.denoised.exr/.png; the Python module is built too
# (build/python/kozu, docs/python.md).
set -euo pipefail
cd "$(dirname "$0")/.."
./scripts/install-deps.sh
cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=Release -DKOZU_PYTHON=ON
cmake --build build --target kozu kozu_python -j "$(nproc)"
./build/kozu render --demo -o out/demo.exr -o out/demo.png --stats out/demo.stats.json
# Only kozu is built above; the same build folder is configured with the tests and the benchmarks.
echo "demo.sh: tests and benchmarks: cmake --build build, then ctest --test-dir build (or build/bench/bench_render)"
echo "demo.sh: from Python: PYTHONPATH=build/python python3 -c 'import kozu; print(kozu.render(kozu.demo(), spp=4, resolution=(480, 270)).shape)'"
