#!/usr/bin/env bash
# Installs kozu's build and test dependencies from Debian 12 packages: the one list of them.
# A no-op when everything is present; works as root or through sudo.
#   scripts/install-deps.sh          install what is missing
#   scripts/install-deps.sh --tests  also the optional test set: Blender, which the add-on's tests compare kozu
#                                    with (never a build dependency; scripts/test.sh asks for it)
#   scripts/install-deps.sh --list   print the build package names, one per line (scripts/test.sh checks the build
#                                    against them with check-debian-deps, where CI's machine provides it)
set -euo pipefail

packages=(
  build-essential cmake ninja-build pkg-config
  libembree-dev libtbb-dev
  libopenimageio-dev openimageio-tools
  nlohmann-json3-dev libcli11-dev libfmt-dev libglm-dev libtinyobjloader-dev libtinygltf-dev
  # OpenVDB's headers include Boost (boost/numeric/conversion); libopenvdb-dev does not depend on it.
  libopenvdb-dev libboost-dev
  # oneDNN 2.x (the learned denoiser's inference on the CPU, on OpenMP: libgomp, which g++ provides).
  libdnnl-dev
  libgtest-dev libgmock-dev libbenchmark-dev
  # Distributed rendering (mpirun -np N kozu render ...); optional at configure time, on in CI.
  libopenmpi-dev openmpi-bin
  # cmake --install writes scenes/showcase.glb with scripts/make-showcase-gltf.py (standard library only).
  python3
  # The Python module (-DKOZU_PYTHON=ON, docs/python.md) and its tests: pybind11, the interpreter's headers, numpy.
  pybind11-dev python3-dev python3-numpy
  # The fuzz targets (tests/fuzz) build with clang's libFuzzer; clang's OpenMP runtime (libomp) is what
  # find_package(OpenMP) finds in that build (the learned denoiser sets oneDNN's thread count through it).
  clang libclang-rt-dev libomp-dev
)

# The optional test set: Blender 3.4 runs the add-on's comparison tests (ctest label blender, skipped without it).
test_packages=(blender)

case "${1:-}" in
  --list) printf '%s\n' "${packages[@]}"; exit 0 ;;
  --tests) packages+=("${test_packages[@]}") ;;
  "") ;;
  *) echo "usage: $0 [--tests | --list]" >&2; exit 2 ;;
esac

missing=()
for p in "${packages[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done

if [ ${#missing[@]} -eq 0 ]; then
  echo "install-deps: all ${#packages[@]} packages present"
  exit 0
fi

echo "install-deps: installing ${missing[*]}"
if [ "$(id -u)" -eq 0 ]; then sudo=(); else sudo=(sudo); fi
export DEBIAN_FRONTEND=noninteractive
"${sudo[@]}" apt-get update -qq
"${sudo[@]}" apt-get install -y -qq --no-install-recommends "${missing[@]}"
