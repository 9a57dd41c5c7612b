#!/usr/bin/env bash
# The installed package works from a separate project: install the build tree
# into a scratch prefix, configure and build tests/consumer against it, and
# take a level out of a real model with it. Also checks that the consumer
# links neither PCL, VTK nor Open3D.
# usage: run.sh BUILD_DIR SCRATCH_DIR
set -euo pipefail
build_dir="$1"
scratch="$2"
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
source_dir="$(cd "$here/../.." && pwd)"
rm -rf "$scratch"
mkdir -p "$scratch"
cmake --install "$build_dir" --prefix "$scratch/prefix" >/dev/null
# Every installed header, included as an application would.
(cd "$scratch/prefix/include" && find scan2lod -name '*.h' | sort | sed 's/.*/#include <&>/') > "$scratch/every_header.cpp"
[ -s "$scratch/every_header.cpp" ] || { echo "no headers installed" >&2; exit 1; }
# The build's own compile and link flags: a library built under the sanitizer
# preset links only into code built the same way.
cached() { sed -n "s/^$1:STRING=//p" "$build_dir/CMakeCache.txt"; }
cmake -S "$here" -B "$scratch/build" -DCMAKE_PREFIX_PATH="$scratch/prefix" -DCMAKE_BUILD_TYPE=Release \
  -DCMAKE_CXX_FLAGS="$(cached CMAKE_CXX_FLAGS)" -DCMAKE_EXE_LINKER_FLAGS="$(cached CMAKE_EXE_LINKER_FLAGS)" \
  -DEVERY_HEADER="$scratch/every_header.cpp" >/dev/null
cmake --build "$scratch/build" -j 2 >/dev/null
if ldd "$scratch/build/consumer" | grep -E -i "libpcl|libvtk|libOpen3D"; then
  echo "the consumer links PCL, VTK or Open3D" >&2
  exit 1
fi
"$scratch/prefix/bin/scan2lod" build "$source_dir/data/bunny/bun.conf" -o "$scratch/bunny.mco" -r 64 -q
line="$("$scratch/build/consumer" "$scratch/bunny.mco" 1000 "$scratch/level.glb" "$scratch/tiles")"
echo "consumer: $line"
read -r structure triangles vertices tiles <<<"$line"
[ "$structure" = clusters ] || { echo "expected the cluster hierarchy, got $structure" >&2; exit 1; }
[ "$triangles" -gt 0 ] && [ "$triangles" -le 1000 ] || { echo "expected 1..1000 triangles, got $triangles" >&2; exit 1; }
[ -s "$scratch/level.glb" ] || { echo "no glTF written" >&2; exit 1; }
[ "$tiles" -gt 0 ] && [ -s "$scratch/tiles/tileset.json" ] || { echo "no tileset written ($tiles tiles)" >&2; exit 1; }
rm -rf "$scratch"
echo "consumer project built against the installed scan2lod and took a level of $triangles triangles"
