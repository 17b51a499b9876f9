#!/usr/bin/env bash
# A hostile round against kozu's outputs: every output flag of every command is given a FIFO, a character device
# (a copy of /dev/null made here with mknod, when allowed), symbolic links to /dev/null, /dev/full and to a FIFO, a
# folder, a name under /proc, a name too long for the file system, a name ending in '/', an empty name and (for the
# tools, which do not create folders) a missing folder. Each must give exactly one line, starting "error: ", and
# exit status 1, and leave the node as it was, with no temporary file beside it. System devices are only ever named
# through links (a rename replaces the link, not the device), so a regression cannot replace /dev/null itself.
#   scripts/hostile-outputs.sh [KOZU]   (default build/kozu; prints one line per failure and a summary)
set -uo pipefail
cd "$(dirname "$0")/.."
kozu=$(realpath "${1:-build/kozu}")
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
in=$work/in
out=$work/out
mkdir -p "$in" "$out"

# Inputs: a scene, two parts of one render (merge), an image (maketx), a mesh (voxelize).
cat >"$in/s.json" <<'EOF'
{"camera": {"position": [0, 0, 4], "look_at": [0, 0, 0], "fov": 35, "resolution": [16, 12]},
 "render": {"spp": 1}, "materials": {"m": {"type": "diffuse", "albedo": 1}},
 "shapes": [{"type": "sphere", "center": [0, 0, 0], "radius": 1, "material": "m"}],
 "lights": [{"type": "environment", "radiance": 1}]}
EOF
"$kozu" render "$in/s.json" -q --sample-range 0:1 -o "$in/a.exr" >/dev/null 2>&1 || { echo "cannot render the inputs"; exit 2; }
"$kozu" render "$in/s.json" -q --sample-range 1:2 -o "$in/b.exr" >/dev/null 2>&1
printf 'v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n' >"$in/m.obj"
printf 'x,value\n0,1\n0.5,2\n1,3\n2,5\n' >"$in/t.csv"
"$kozu" render "$in/s.json" -q -o "$in/n.png" >/dev/null 2>&1

# name | extension | command line with OUT for the output (DIR for a folder for the command's other outputs)
flags=(
  "render -o|.exr|render $in/s.json -q -o OUT"
  "render --stats|.json|render $in/s.json -q -o DIR/r.exr --stats OUT"
  "render --checkpoint|.ckpt|render $in/s.json -q -o DIR/r.exr --checkpoint OUT"
  "merge -o|.exr|merge $in/a.exr $in/b.exr -o OUT"
  "maketx -o|.tx|maketx $in/a.exr -o OUT"
  "fit-ltc -o|.json|fit-ltc --size 2 --threads 1 -o OUT"
  "precompute -o|.inc|precompute microfacet-albedo --grid 4 -o OUT"
  "procedural -o|.kvox|procedural smoke --resolution 8 -o OUT"
  "voxelize -o|.kvox|voxelize $in/m.obj --resolution 4 -o OUT"
  "sss-reference -o|.csv|sss-reference --albedo 0.5 --photons 10 -o OUT"
  "sss-reference --json|.json|sss-reference --table --photons 1 --json OUT"
  "texture height -o|.exr|texture height $in/a.exr -o OUT"
  "texture height --mesh|.ply|texture height $in/a.exr -o DIR/r.exr --mesh OUT"
  "texture occlusion -o|.exr|texture occlusion $in/a.exr -o OUT --radius 2"
  "texture occlusion --cone|.exr|texture occlusion $in/a.exr -o DIR/r.exr --cone OUT --radius 2"
  "texture filter-normals -o|.exr|texture filter-normals $in/n.png -o OUT DIR/g.exr"
  "texture filter-normals gloss|.exr|texture filter-normals $in/n.png -o DIR/n.exr OUT"
  "fit-rational --json|.json|fit-rational $in/t.csv --num 1 --den 0 --json OUT"
)

# What a path is, without following a link (a link is shown with its target).
kind() { if [ -L "$1" ]; then echo "link to $(readlink "$1")"; elif [ -e "$1" ]; then stat -c %F "$1"; else echo missing; fi; }

failures=0
cases=0
long=$(printf 'x%.0s' $(seq 1 300))
for entry in "${flags[@]}"; do
  IFS='|' read -r name ext cmdline <<<"$entry"
  dir=$out/$(echo "$name" | tr ' -' '__')
  mkdir -p "$dir"
  targets=()
  mkfifo "$dir/fifo$ext" && targets+=("$dir/fifo$ext")
  mknod "$dir/null$ext" c 1 3 2>/dev/null && targets+=("$dir/null$ext")
  ln -s /dev/null "$dir/devnull$ext" && targets+=("$dir/devnull$ext")
  ln -s /dev/full "$dir/devfull$ext" && targets+=("$dir/devfull$ext")
  ln -s "fifo$ext" "$dir/fifolink$ext" && targets+=("$dir/fifolink$ext")
  mkdir "$dir/folder$ext" && targets+=("$dir/folder$ext")
  targets+=("/proc/kozu-hostile$ext" "$dir/$long$ext" "$dir/folder$ext/")
  # An empty name: render's optional outputs take it as "none" (as if the flag were not given).
  case $name in "render --stats" | "render --checkpoint") ;; *) targets+=("") ;; esac
  # The tools write into a folder that exists; render, merge and maketx create theirs (out/).
  case $name in render* | merge* | maketx*) ;; *) targets+=("$dir/no/such/folder/t$ext") ;; esac
  for target in "${targets[@]}"; do
    cases=$((cases + 1))
    before=$(kind "$target")
    line=${cmdline//OUT/"'$target'"}
    line=${line//DIR/"'$dir'"}
    output=$(eval "timeout 60 '$kozu' $line" 2>&1)
    code=$?
    after=$(kind "$target")
    temps=$(find "$dir" -maxdepth 1 -name '*.tmp*' | wc -l)
    problems=()
    [ "$code" = 1 ] || problems+=("exit $code")
    [ "$(printf '%s\n' "$output" | wc -l)" = 1 ] || problems+=("$(printf '%s\n' "$output" | wc -l) lines")
    [[ $output == error:* ]] || problems+=("no 'error:'")
    [ "$before" = "$after" ] || problems+=("replaced: $before -> $after")
    [ "$temps" = 0 ] || problems+=("$temps temporary files left")
    [ -e "$dir/r.exr" ] && problems+=("wrote its other output") && rm -f "$dir/r.exr"
    if [ ${#problems[@]} -gt 0 ]; then
      failures=$((failures + 1))
      echo "FAIL $name '${target:0:80}': ${problems[*]}: $(printf '%s' "$output" | head -c 300)"
    fi
  done
done
echo "$cases cases, $failures failures"
[ "$failures" = 0 ]
