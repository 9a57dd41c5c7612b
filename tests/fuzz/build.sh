#!/usr/bin/env bash
# Builds and runs the .mco reader's fuzz target (model_fuzzer.cpp) with clang's
# libFuzzer, AddressSanitizer and UBSan. Not part of CI: a run is open-ended.
#
#   tests/fuzz/build.sh [SECONDS]   build into build-fuzz/, make a seed model
#                                   (the bunny at R = 16, with build/bin/scan2lod)
#                                   and fuzz for SECONDS (default 300) on all cores
# Needs clang, libomp-dev (Debian's clang and libomp-dev) and a normal build for the seed.
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
repo="$(dirname "$(dirname "$here")")"
out="$repo/build-fuzz"
seconds="${1:-300}"
mkdir -p "$out/corpus"
sources=(lod/model_file.cpp lod/extract.cpp lod/transition.cpp lod/lod_array.cpp lod/lod_cursor.cpp
         core/mesh_edges.cpp core/types.cpp reconstruct/cube_table.cpp io/atomic_file.cpp)
clang++ -std=c++17 -O1 -g -fopenmp -fsanitize=fuzzer,address,undefined -fno-sanitize-recover=undefined \
  -I"$repo" -I/usr/include/eigen3 "$here/model_fuzzer.cpp" "${sources[@]/#/$repo/}" -o "$out/model_fuzzer"
seed="$out/seed16.mco"
if [[ ! -f "$seed" ]]; then
  "$repo/build/bin/scan2lod" build "$repo/data/bunny/bun.conf" -o "$seed" --resolution 16 --quiet
  "$repo/build/bin/scan2lod" build "$repo/data/bunny/bun.conf" -o "$out/seed32.mco" --resolution 32 --quiet
  { printf 'R'; cat "$seed"; } > "$out/corpus/raw16"
  { printf 'R'; cat "$out/seed32.mco"; } > "$out/corpus/raw32"
  printf 'S' > "$out/corpus/none"
fi
cd "$out"
MODEL_FUZZ_SEED="$seed" ./model_fuzzer -max_total_time="$seconds" -jobs="$(nproc)" -workers="$(nproc)" \
  -max_len=600000 corpus
