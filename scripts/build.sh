#!/usr/bin/env bash
# One entry point for a fresh Debian 12 machine:
#   scripts/build.sh demo   install what is missing, build, reconstruct the bundled bunny,
#                           build its LOD model and extract a level
#   scripts/build.sh test   the same, then run the test suite
#   scripts/build.sh deps   only install the packages (and the tests' npm packages)
# BUILD_DIR (default build) and JOBS (default nproc) can be set in the environment.
set -euo pipefail

here="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$here"
build_dir="${BUILD_DIR:-build}"
jobs="${JOBS:-$(nproc)}"

# Everything comes from Debian's archive (see ../shared/ENVIRONMENT.md).
packages=(
  build-essential cmake pkg-config
  libeigen3-dev liblz4-dev
  libpcl-dev libopen3d-dev libopenmesh-dev libflann-dev libvtk9-dev
  libcli11-dev nlohmann-json3-dev libgtest-dev libbenchmark-dev
  libmeshoptimizer-dev libmetis-dev libtinygltf-dev libxxhash-dev libcpp-httplib-dev
  chromium
  xvfb xauth libgl1-mesa-dri
  libopenmpi-dev openmpi-bin
  python3-dev pybind11-dev python3-numpy python3-pytest
)

install_deps() {
  local missing=()
  for p in "${packages[@]}"; do
    dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
  done
  if [ ${#missing[@]} -eq 0 ]; then
    echo "scan2lod: all ${#packages[@]} packages present"
    return
  fi
  echo "scan2lod: installing ${missing[*]}"
  local sudo=""
  [ "$(id -u)" -eq 0 ] || sudo="sudo"
  export DEBIAN_FRONTEND=noninteractive
  $sudo apt-get update -qq
  $sudo apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
}

# Node.js and npm from Debian when the machine has no node (a NodeSource
# nodejs carries its own npm, which Debian's npm package would conflict with).
# The build needs npm for the viewer page (delivery/CMakeLists.txt), the tests
# need node.
install_node() {
  command -v node >/dev/null && command -v npm >/dev/null && return
  local sudo=""
  [ "$(id -u)" -eq 0 ] || sudo="sudo"
  DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends nodejs npm >/dev/null
}

# The tests' npm packages, into the build folder: the Khronos glTF-Validator
# (npm gltf-validator, version pinned in tests/gltf/package.json), which the
# tests run on every glTF file scan2lod writes, and the web viewers' tests'
# puppeteer-core, pngjs and cesium (pinned by tests/web/package-lock.json),
# which drive Debian's chromium (the package list above).
install_test_packages() {
  local prefix="$build_dir/npm"
  if [ ! -f "$prefix/node_modules/gltf-validator/package.json" ]; then
    mkdir -p "$prefix"
    cp tests/gltf/package.json "$prefix/"
    npm install --prefix "$prefix" --no-audit --no-fund --silent >/dev/null
  fi
  local web="$build_dir/npm-web"
  if ! cmp -s tests/web/package-lock.json "$web/package-lock.json" || [ ! -d "$web/node_modules" ]; then
    mkdir -p "$web"
    cp tests/web/package.json tests/web/package-lock.json "$web/"
    npm ci --prefix "$web" --no-audit --no-fund --loglevel=error >/dev/null
  fi
}

build() {
  cmake -S . -B "$build_dir" -DCMAKE_BUILD_TYPE=Release >/dev/null
  cmake --build "$build_dir" -j "$jobs"
}

demo() {
  mkdir -p out
  "$build_dir/bin/scan2lod" reconstruct data/bunny/bun.conf -o out/bunny.ply --resolution 256
  local reference=../shared/data/bunny/reconstruction/bun_zipper.ply
  if [ -f "$reference" ]; then
    "$build_dir/bin/scan2lod" compare out/bunny.ply "$reference"
  fi
  # The main job: the LOD model (cluster hierarchy and octree), its levels,
  # and levels taken from it by budget, from each structure.
  "$build_dir/bin/scan2lod" build data/bunny/bun.conf -o out/bunny.mco --resolution 256
  "$build_dir/bin/scan2lod" info out/bunny.mco
  "$build_dir/bin/scan2lod" extract out/bunny.mco --triangles 20000 -o out/bunny_20k.ply
  "$build_dir/bin/scan2lod" extract out/bunny.mco --structure octree --percent 20 -o out/bunny_20.ply
  # Delivery: four levels in one glTF file (MSFT_lod over shared vertices).
  "$build_dir/bin/scan2lod" export out/bunny.mco --levels 100,25,5,1 -o out/bunny.glb
  # A 3D Tiles 1.1 tileset and its web page: scan2lod serve out/bunny_tiles shows it.
  "$build_dir/bin/scan2lod" export out/bunny.mco --format 3dtiles -o out/bunny_tiles
}

run_tests() {
  # CTest runs the GoogleTest suite and, as the test Python.Pytest, the
  # Python package's pytest suite (python/tests) against build/python.
  # Tests render with VTK; give them a display when there is none.
  local xvfb=()
  if [ -z "${DISPLAY:-}" ] && command -v xvfb-run >/dev/null; then xvfb=(xvfb-run -a); fi
  (cd "$build_dir" && "${xvfb[@]}" ctest --output-on-failure -j "$jobs")
}

case "${1:-demo}" in
  deps) install_deps; install_node; install_test_packages ;;
  demo) install_deps; install_node; build; demo ;;
  test) install_deps; install_node; install_test_packages; build; demo; run_tests ;;
  *) echo "usage: scripts/build.sh [demo|test|deps]" >&2; exit 2 ;;
esac
