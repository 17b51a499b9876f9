#!/usr/bin/env bash
# Regenerates the pictures of README.md and docs/*.md (docs/images/*), each the way its caption says.
#
#   scripts/make-docs-images.sh [--kozu PATH] [NAME...]   regenerate these images (all of them, in order, if none)
#   scripts/make-docs-images.sh --list [NAME...]          name, estimated seconds, command(s); runs nothing
#   scripts/make-docs-images.sh --dry-run [NAME...]       print the commands instead of running them
#   scripts/make-docs-images.sh --check                   Markdown references against docs/images and this list
#
# NAME is the file name without its extension (`demo fabric`; docs/images/fabric.png works too). The kozu binary
# is --kozu PATH, else a first argument that is an executable file (as scripts/make-volumes.sh takes it), else $KOZU,
# else build/kozu. Run it from anywhere after a build; it works in the repository root.
#
# Each image renders into a scratch folder and only a finished file is copied (atomically) to docs/images, so a
# failed or interrupted render never leaves a broken image. A failing image does not stop the others; the run
# ends with a summary and exits 1 if any failed. Images whose tool is missing (blender, Python's matplotlib) are
# skipped with a message. Estimated seconds are the captions' own (--time-limit, --budget, "N s") where they give
# them, on the 2-core machine the captions were measured on; a guess is marked "~".
#
# Adding an image: write a function img_NAME (a '-' in NAME becomes '_') with `secs`, its `step`s and a `keep`,
# and add NAME to IMAGES. The helpers (below the images): secs ESTIMATE; step CMD... (printed, or run);
# ensure FILE CMD... (run CMD if FILE is missing); requires TOOL (skip the image without it);
# keep FILE [NAME.EXT] (copy a finished file to docs/images); no_command (the caption gives no command).
#
# NO_COMMAND: images whose caption gives no command and that no script in the repository makes. Listed in --list as
# "(no command: caption needs one)" and skipped; their captions need a command (or a script) first.
#   python-materials.png  docs/python.md "Comparing two materials": the code above it renders each material at
#                         320x240 (the caption says seed=0, spp=256) and the caption says the two were joined with
#                         np.concatenate and saved with kozu.write_image, but the image (644x240) has a 4-pixel light
#                         grey gap between them that the caption does not describe; no script writes it.

set -euo pipefail
cd "$(dirname "$0")/.."

# The order of a full run (README.md first, then docs/*.md).
IMAGES=(
  demo blender camp_animation showcase-gltf stained_glass wwii_showcase
  microfacet microfacet_none furnace_compensated furnace_none subsurface subsurface_lambert
  fabric yarn smoke bush_lod bush_lod_distance cornell
  cookbook_product cookbook_interior cookbook_volume stained_glass_preview lobe_light_sampling python-materials
  sss_fit_searchlight sss_fit_diffuse sss_fit_dmfp sss_dmfp_check sss_rmax_scan
)

# --- The images -------------------------------------------------------------------------------------------------
# In each function $KOZU is the kozu binary, $tmp the image's own scratch folder (empty at the start).

# README.md (top). The built-in demo's defaults: 1920x1080 within --budget 123, denoised; it writes demo.png and
# demo.denoised.png, and the README shows the denoised one.
img_demo() {
  secs 123
  step "$KOZU" render --demo -o "$tmp/demo.png"
  keep "$tmp/demo.denoised.png" demo.png
}

# README.md "In Blender", docs/blender.md: Cycles above, kozu through the add-on below (showcase.py stacks them
# with oiiotool). Written here to the scratch folder: the caption's command writes docs/images/blender.png and
# leaves blender.cycles.png and blender.kozu.png beside it.
img_blender() {
  secs '~600'
  requires blender
  step env KOZU="$(kozu_abs)" blender -b --factory-startup --python blender/examples/showcase.py -- \
    "$tmp/blender.png" 960 256 --compare
  keep "$tmp/blender.png"
}

# README.md (a camp-style animation), docs/production.md "Showcase: 60 frames inside a camp budget".
img_camp_animation() {
  secs 480
  step "$KOZU" render scenes/camp_animation.json --budget 480 -o "$tmp/camp/%04d.png"
  step scripts/contact-sheet.sh "$tmp/camp" "$tmp/camp_animation.jpg" 5 4 320
  keep "$tmp/camp_animation.jpg"
}

# README.md "glTF showcase": 960x540, 256 spp (the scene's), 99 s on 2 shared cores.
img_showcase_gltf() {
  secs 99
  ensure scenes/showcase.glb python3 scripts/make-showcase-gltf.py
  step "$KOZU" render scenes/showcase/showcase.json -o "$tmp/showcase-gltf.png"
  keep "$tmp/showcase-gltf.png"
}

# README.md, docs/lights.md ("direct": "sample", the scene's).
img_stained_glass() {
  secs '~60'
  step "$KOZU" render scenes/stained_glass.json --resolution 960x540 --spp 256 --denoise -o "$tmp/stained_glass.png"
  keep "$tmp/stained_glass.denoised.png" stained_glass.png
}

# README.md, docs/wwii.md "Showcase: a wet cobblestone street" (9 minutes on 2 cores). The script's own
# wwii-showcase.png puts the four panels in a row; the picture is them 2 x 2 (plain, filtered / occluded, reference).
img_wwii_showcase() {
  secs 540
  step python3 scripts/wwii-showcase.py "$KOZU" "$tmp/wwii" --width 640 --spp 64
  step oiiotool "$tmp/wwii/plain.png" "$tmp/wwii/filtered.png" "$tmp/wwii/occluded.png" "$tmp/wwii/reference.png" \
    --mosaic 2x2 -o "$tmp/wwii_showcase.png"
  keep "$tmp/wwii_showcase.png"
}

# README.md "Rough metals, glass and plastic": 1920x1080, --time-limit 240.
img_microfacet() {
  secs 240
  step "$KOZU" render scenes/microfacet.json --resolution 1920x1080 --time-limit 240 -o "$tmp/microfacet.png"
  keep "$tmp/microfacet.png"
}

# README.md: "the same scene with multiscatter none (194 spp in 240 s)".
img_microfacet_none() {
  secs 240
  step "$KOZU" render scenes/microfacet_none.json --resolution 1920x1080 --time-limit 240 -o "$tmp/microfacet_none.png"
  keep "$tmp/microfacet_none.png"
}

# README.md "White furnace" (the paragraph above the two images): the scenes' 960x160, 64 spp, --tonemap clamp.
img_furnace_compensated() {
  secs '~10'
  step "$KOZU" render scenes/furnace_compensated.json --tonemap clamp -o "$tmp/furnace_compensated.png"
  keep "$tmp/furnace_compensated.png"
}

img_furnace_none() {
  secs '~10'
  step "$KOZU" render scenes/furnace_none.json --tonemap clamp -o "$tmp/furnace_none.png"
  keep "$tmp/furnace_none.png"
}

# README.md "Subsurface scattering", docs/subsurface.md: 1280x720, --time-limit 180.
img_subsurface() {
  secs 200
  step "$KOZU" render scenes/subsurface.json --resolution 1280x720 --time-limit 180 --denoise -o "$tmp/subsurface.png"
  keep "$tmp/subsurface.denoised.png" subsurface.png
}

# README.md: "316 spp in 180 s".
img_subsurface_lambert() {
  secs 180
  step "$KOZU" render scenes/subsurface_lambert.json --resolution 1280x720 --time-limit 180 \
    -o "$tmp/subsurface_lambert.png"
  keep "$tmp/subsurface_lambert.png"
}

# README.md "Participating media and SGGX volumes", docs/volumes.md: 640x480, --time-limit 120 (voxels made at load).
img_fabric() {
  secs 120
  step "$KOZU" render scenes/fabric.json --resolution 640x480 --time-limit 120 -o "$tmp/fabric.png"
  keep "$tmp/fabric.png"
}

# README.md, docs/volumes.md: 480x480, "145 spp in 120 s".
img_yarn() {
  secs 120
  step "$KOZU" render scenes/yarn.json --resolution 480x480 --time-limit 120 -o "$tmp/yarn.png"
  keep "$tmp/yarn.png"
}

# README.md, docs/volumes.md: 480x480, "128 spp in 26 s" (128 spp: the scene's own count).
img_smoke() {
  secs 26
  step "$KOZU" render scenes/smoke.json --resolution 480x480 --spp 128 -o "$tmp/smoke.png"
  keep "$tmp/smoke.png"
}

# README.md, docs/volumes.md: mesh, SGGX volume at the automatic level, level 2, level 4; 320x240, 48 spp each, in a
# row 4 pixels apart (the picture's 1292 x 240, as tools/make_lod_figure.sh pads its figure). The estimate is the
# caption's samples/s: 3.7 M samples at 1.47, 0.20, 0.43 and 0.41 M/s.
img_bush_lod() {
  secs '~40'
  ensure scenes/volumes/bush.kvox scripts/make-volumes.sh "$KOZU"
  local s
  for s in mesh volume volume_lod2 volume_lod4; do
    step "$KOZU" render "scenes/bush_$s.json" --resolution 320x240 --spp 48 -o "$tmp/$s.png"
  done
  step oiiotool "$tmp/mesh.png" "$tmp/volume.png" "$tmp/volume_lod2.png" "$tmp/volume_lod4.png" \
    --mosaic:pad=4 4x1 -o "$tmp/bush_lod.png"
  keep "$tmp/bush_lod.png"
}

# docs/volumes.md "From a distance", README.md (a link): tools/make_lod_figure.sh, which writes
# docs/images/bush_lod_distance.png itself, so it runs in a scratch root whose scenes/ is the repository's.
img_bush_lod_distance() {
  secs '~65'
  ensure scenes/volumes/bush.kvox scripts/make-volumes.sh "$KOZU"
  step mkdir -p "$tmp/root/docs/images"
  step ln -s "$PWD/scenes" "$tmp/root/scenes"
  step env -C "$tmp/root" KOZU="$(kozu_abs)" OUT="$tmp/lod" "$PWD/tools/make_lod_figure.sh"
  keep "$tmp/root/docs/images/bush_lod_distance.png"
}

# README.md (end of "Performance"): "scenes/cornell.json, 512 spp, --exposure 1.6" (the scene's 512x512).
img_cornell() {
  secs '~75'
  step "$KOZU" render scenes/cornell.json --spp 512 --exposure 1.6 -o "$tmp/cornell.png"
  keep "$tmp/cornell.png"
}

# docs/cookbook.md: the command under each picture, at the scenes' own size (1280x720) and spp; a PNG added
# where the command writes only an EXR.
img_cookbook_product() {
  secs '~150'
  step "$KOZU" render scenes/cookbook/product.json -o "$tmp/product.exr" -o "$tmp/product.png"
  keep "$tmp/product.png" cookbook_product.png
}

img_cookbook_interior() {
  secs '~300'
  step "$KOZU" render scenes/cookbook/interior.json -o "$tmp/interior.exr" -o "$tmp/interior.png" --denoise
  keep "$tmp/interior.denoised.png" cookbook_interior.png
}

img_cookbook_volume() {
  secs '~200'
  step "$KOZU" render scenes/cookbook/volume.json -o "$tmp/volume.exr" -o "$tmp/volume.png"
  keep "$tmp/volume.png" cookbook_volume.png
}

# docs/lights.md: "the same with --direct ltc-preview".
img_stained_glass_preview() {
  secs '~15'
  step "$KOZU" render scenes/stained_glass.json --resolution 960x540 --spp 64 --direct ltc-preview \
    -o "$tmp/stained_glass_preview.png"
  keep "$tmp/stained_glass_preview.png"
}

# docs/lights.md "Light samples shaped by a glossy lobe": the glossy floor at 16 spp, light sampling alone (left)
# and with lobe-shaped light samples (right, the default).
img_lobe_light_sampling() {
  secs '~3'
  local m
  for m in light lobe; do
    step "$KOZU" render scenes/ltc_glossy.json --spp 16 --seed 1 -D /render/light_sampling=$m -o "$tmp/$m.png"
  done
  step oiiotool "$tmp/light.png" "$tmp/lobe.png" --mosaic:pad=4 2x1 -o "$tmp/lobe_light_sampling.png"
  keep "$tmp/lobe_light_sampling.png"
}

# docs/python.md: see NO_COMMAND above.
img_python_materials() {
  secs '?'
  no_command
}

# docs/subsurface.md: the five plots of tools/plot_sss_table.py, from the checked-in tables (the command under
# "The table"; Debian's matplotlib). One run makes all five; a full run plots once.
img_sss_fit_searchlight() { secs '~10'; sss_plots; keep "$tmp/sss_fit_searchlight.png"; }
img_sss_fit_diffuse() { secs '~10'; sss_plots; keep "$tmp/sss_fit_diffuse.png"; }
img_sss_fit_dmfp() { secs '~10'; sss_plots; keep "$tmp/sss_fit_dmfp.png"; }
img_sss_dmfp_check() { secs '~10'; sss_plots; keep "$tmp/sss_dmfp_check.png"; }
img_sss_rmax_scan() { secs '~10'; sss_plots; keep "$tmp/sss_rmax_scan.png"; }

sss_plots() {
  if [[ $mode == run && -d $work/sss ]]; then  # plotted earlier in this run
    cp "$work"/sss/*.png "$tmp/"
    return 0
  fi
  local py=/usr/bin/python3 p
  for p in /usr/bin/python3 python3; do
    if "$p" -c 'import matplotlib' 2>/dev/null; then py=$p; break; fi
  done
  requires_python_module "$py" matplotlib "Debian: apt-get install python3-matplotlib"
  step "$py" tools/plot_sss_table.py docs/data/sss_table.json docs/data/sss_table_1.6M.json \
    docs/data/sss_table_40k.json --out "$tmp"
  if [[ $mode == run ]]; then
    mkdir -p "$work/sss.partial"
    cp "$tmp"/sss_*.png "$work/sss.partial/"
    mv "$work/sss.partial" "$work/sss"
  fi
}

# --- Helpers ----------------------------------------------------------------------------------------------------
# mode: run, dry (--dry-run), list (--list) or check (--check). In list mode the helpers collect each image's
# estimate and commands instead of printing or running them.

die() { echo "make-docs-images.sh: $*" >&2; exit 2; }

# A command line as it would be typed (arguments with odd characters in single quotes).
show() {
  local a safe='^[A-Za-z0-9_./:=%,+@$-]+$' out=()
  for a in "$@"; do
    if [[ $a =~ $safe ]]; then out+=("$a"); else out+=("'${a//\'/\'\\\'\'}'"); fi
  done
  printf '%s' "${out[*]}"
}

# secs ESTIMATE: the image's seconds (a guess starts with ~; ? unknown); a run prints it as the image's header.
secs() {
  est=$1
  if [[ $mode != run ]]; then return 0; fi
  if [[ $1 == '?' ]]; then echo "== $name"; else echo "== $name (about ${1#\~} s)"; fi
}

# step CMD...: one command of the image: collected (--list), printed (--dry-run) or printed and run.
step() {
  case $mode in
    list) cmds+=("$(show "$@")") ;;
    dry) echo "  $(show "$@")" ;;
    run) echo "+ $(show "$@")"; "$@" ;;
  esac
}

# ensure FILE CMD...: make a generated input the scene reads, if it is missing.
ensure() {
  local file=$1
  shift
  case $mode in
    list) cmds+=("[ -f $file ] || $(show "$@")") ;;
    dry) echo "  [ -f $file ] || $(show "$@")" ;;
    run) if [[ ! -f $file ]]; then step "$@"; fi ;;
  esac
}

# requires TOOL: skip the image (exit status 3 of its subshell) when TOOL is not on PATH.
requires() {
  if command -v "$1" >/dev/null; then return 0; fi
  case $mode in
    dry) echo "  # $1 not found: $name would be skipped" ;;
    run) echo "skip $name: $1 is not on PATH" >&2; exit 3 ;;
  esac
}

requires_python_module() {  # PYTHON MODULE HINT
  if "$1" -c "import $2" 2>/dev/null; then return 0; fi
  case $mode in
    dry) echo "  # $1 has no $2 ($3): $name would be skipped" ;;
    run) echo "skip $name: $1 has no $2 ($3)" >&2; exit 3 ;;
  esac
}

no_command() {
  case $mode in
    list) cmds+=("(no command: caption needs one)") ;;
    dry) echo "  # no command: caption needs one (see NO_COMMAND in $0)" ;;
    run) echo "skip $name: its caption gives no command (see NO_COMMAND in $0)" >&2; exit 3 ;;
  esac
}

# keep FILE [NAME.EXT]: FILE, finished, becomes docs/images/NAME.EXT (default: FILE's own name).
keep() {
  local src=$1 dst=docs/images/${2:-$(basename "$1")}
  case $mode in
    list) cmds+=("cp $(show "$src") $dst") ;;
    dry) echo "  cp $(show "$src") $dst" ;;
    run)
      [[ -s $src ]] || { echo "error: $name: $src was not written" >&2; exit 1; }
      cp "$src" "$dst.partial"
      mv "$dst.partial" "$dst"
      echo "wrote $dst"
      ;;
  esac
}

fn_of() { echo "img_${1//-/_}"; }

# $KOZU as an absolute path, for commands that run it from another folder (a name on PATH stays a name).
kozu_abs() { if [[ $KOZU == */* ]]; then realpath -m "$KOZU"; else echo "$KOZU"; fi; }

# --check: what the Markdown shows, what docs/images holds and what this script makes.
check() {
  local refs files n status=0
  refs=$( (grep -o '](docs/images/[^)]*)' README.md | sed 's|](docs/images/||; s|)$||'
           grep -o '](images/[^)]*)' docs/*.md | sed 's|.*](images/||; s|)$||') | sort -u)
  files=$(find docs/images -maxdepth 1 -type f -printf '%f\n' | sort)
  for n in $files; do
    if ! grep -qxF "$n" <<<"$refs"; then echo "docs/images/$n: referenced by no Markdown image"; status=1; fi
  done
  for n in $refs; do
    if [[ ! -f docs/images/$n ]]; then echo "docs/images/$n: referenced but missing"; status=1; fi
    if ! declare -F "$(fn_of "${n%.*}")" >/dev/null; then echo "$n: no img_ function here"; status=1; fi
  done
  for n in "${IMAGES[@]}"; do
    if ! grep -q "^$n\." <<<"$refs"; then echo "$n: made here but shown by no Markdown"; status=1; fi
  done
  if [[ $status == 0 ]]; then echo "ok: $(wc -l <<<"$refs") images, each referenced, present and made here"; fi
  return $status
}

# --- Command line -----------------------------------------------------------------------------------------------

mode=run
kozu_arg=
names=()
while (($#)); do
  case $1 in
    --list) mode=list ;;
    --dry-run | -n) mode=dry ;;
    --check) mode=check ;;
    --kozu) kozu_arg=${2:?--kozu needs a path}; shift ;;
    --kozu=*) kozu_arg=${1#--kozu=} ;;
    -h | --help) sed -n '2,/^$/s/^# \{0,1\}//p' "$0"; exit 0 ;;
    -*) die "unknown option $1 (see --help)" ;;
    *) names+=("$1") ;;
  esac
  shift
done

# A first argument that is an executable file, not an image name, is the kozu binary.
if ((${#names[@]})) && [[ -z $kozu_arg && -f ${names[0]} && -x ${names[0]} ]] &&
   ! declare -F "$(fn_of "$(basename "${names[0]%.*}")")" >/dev/null; then
  kozu_arg=${names[0]}
  names=("${names[@]:1}")
fi
KOZU=${kozu_arg:-${KOZU:-build/kozu}}

if [[ $mode == check ]]; then check; exit; fi

selected=()
for n in "${names[@]}"; do
  n=$(basename "$n")
  n=${n%.png}
  n=${n%.jpg}
  declare -F "$(fn_of "$n")" >/dev/null || die "no image '$n'; the images: ${IMAGES[*]}"
  selected+=("$n")
done
((${#selected[@]})) || selected=("${IMAGES[@]}")

# In --list and --dry-run the scratch folder is shown as $tmp.
# shellcheck disable=SC2016
if [[ $mode == list ]]; then
  tmp='$tmp'
  work='$work'
  for name in "${selected[@]}"; do
    est='?'
    cmds=()
    "$(fn_of "$name")"
    line=
    for c in "${cmds[@]}"; do line+=${line:+ && }$c; done
    printf '%-22s %6s  %s\n' "$name" "$est" "$line"
  done
  exit 0
fi

# shellcheck disable=SC2016
if [[ $mode == dry ]]; then
  tmp='$tmp'
  work='$work'
  echo "# KOZU=$KOZU; each image has its own scratch folder \$tmp"
  for name in "${selected[@]}"; do
    est='?'
    echo "# $name"
    "$(fn_of "$name")"
  done
  exit 0
fi

# A real run: kozu must exist unless only the plots (which do not need it) were asked for.
for name in "${selected[@]}"; do
  case $name in sss_* | python-materials) ;; *)
    if [[ $KOZU == */* ]]; then
      [[ -x $KOZU ]] || die "no kozu at $KOZU: build it (cmake --build build) or pass --kozu PATH"
      KOZU=$(realpath "$KOZU")
    else
      KOZU=$(command -v "$KOZU") || die "no kozu on PATH: build it (cmake --build build) or pass --kozu PATH"
    fi
    break ;;
  esac
done
command -v oiiotool >/dev/null || echo "warning: oiiotool is not on PATH: the composed images will fail" >&2

work=$(mktemp -d "${TMPDIR:-/tmp}/kozu-docs-images.XXXXXX")
trap 'rm -rf "$work"' EXIT
trap 'exit 130' INT TERM
made=() skipped=() failed=()
start=$SECONDS
for name in "${selected[@]}"; do
  tmp=$(mktemp -d "$work/$name.XXXXXX")
  t0=$SECONDS
  set +e
  (set -e; "$(fn_of "$name")")
  rc=$?
  set -e
  rm -rf "$tmp"
  case $rc in
    0) made+=("$name ($((SECONDS - t0)) s)") ;;
    3) skipped+=("$name") ;;
    130 | 143) echo "interrupted" >&2; exit "$rc" ;;
    *) failed+=("$name"); echo "FAILED $name (exit status $rc)" >&2 ;;
  esac
done

echo
echo "made (${#made[@]}, $((SECONDS - start)) s in all): ${made[*]:-none}"
if ((${#skipped[@]})); then echo "skipped: ${skipped[*]}"; fi
if ((${#failed[@]})); then echo "FAILED: ${failed[*]}" >&2; exit 1; fi
