#!/usr/bin/env bash
# Memory of instancing (docs/scene-format.md#objects-and-instances): peak resident memory of `kozu render` for a
# field of N bushes (scenes/meshes/bush.ply, 4,880 triangles), placed as instances of one object and as copies of
# the mesh. Usage: bench/instancing_memory.sh [KOZU] (default build/kozu). Prints one line per scene. Needs
# /usr/bin/time (Debian package `time`) and python3.
set -euo pipefail
cd "$(dirname "$0")/.."
kozu=$(realpath "${1:-build/kozu}")
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
cp scenes/meshes/bush.ply "$work/"
cd "$work"
cat > gen.py <<'PY'
import json, math, random, sys
n, mode = int(sys.argv[1]), sys.argv[2]
random.seed(1)
side = max(1, int(math.ceil(math.sqrt(n))))
scene = {"camera": {"position": [0, 40, -side * 1.2], "look_at": [0, 0, side * 0.6], "fov": 50, "resolution": [64, 36]},
         "materials": {"leaf": {"type": "diffuse", "albedo": [0.2, 0.5, 0.1]}, "ground": {"type": "diffuse", "albedo": 0.4}},
         "shapes": [{"type": "quad", "material": "ground",
                     "vertices": [[-1e4, 0, 1e4], [1e4, 0, 1e4], [1e4, 0, -1e4], [-1e4, 0, -1e4]]}],
         "lights": [{"type": "environment", "radiance": 1}]}
if mode == "instance":
    scene["objects"] = {"bush": [{"type": "mesh", "file": "bush.ply", "material": "leaf"}]}
for i in range(n):
    xf = {"rotate": [0, 1, 0, random.uniform(0, 360)], "scale": random.uniform(0.8, 1.2),
          "translate": [(i % side - side / 2) * 2.0, 0, (i // side) * 2.0]}
    if mode == "instance":
        scene["shapes"].append({"type": "instance", "object": "bush", "transform": xf})
    else:
        scene["shapes"].append({"type": "mesh", "file": "bush.ply", "material": "leaf", "transform": xf})
json.dump(scene, open(f"{mode}_{n}.json", "w"))
PY
for run in "instance 1" "instance 1000" "instance 100000" "copy 1" "copy 100" "copy 1000"; do
  set -- $run
  python3 gen.py "$2" "$1"
  /usr/bin/time -f "$1 x $2: peak RSS %M KiB, %e s (scene file $(stat -c %s "$1_$2.json") bytes)" \
    "$kozu" render "$1_$2.json" -o out.png --spp 4 --quiet 2>&1 | tail -1
done
