#!/usr/bin/env bash
# Runs the LOD benchmark from an existing build and prints its markdown report
# (progress goes to stderr). Builds nothing.
# bench/report.sh builds, runs both benchmarks and regenerates the README summary.
#
#   bench/lod/run.sh [--build DIR] [benchmark options...]
#
#   --build DIR  build directory holding bin/scan2lod_bench_lod
#                (default: $SCAN2LOD_BUILD_DIR, else <repo>/build)
#   anything else goes to the benchmark: --write (also bench/lod/REPORT.md),
#   --quick, --resolution R, --runs N, --repeat-under S, --timeout S, --reps N,
#   --samples N, --seed S, --only TEXT, --input FILE (see --help)
#
# Examples:
#   bench/lod/run.sh --build build-lod --quick    # R=128, 3 levels, 7 cluster cuts, ~5 min on 2 cores
#   bench/lod/run.sh --build build-lod --write    # R=256, 7 levels (see REPORT.md for the time)
set -euo pipefail

here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
repo="$(dirname "$(dirname "$here")")"
source "$repo/bench/common.sh"
build="${SCAN2LOD_BUILD_DIR:-$repo/build}"
args=()
while [[ $# -gt 0 ]]; do
  case "$1" in
    --build) build="$2"; shift 2 ;;
    *) args+=("$1"); shift ;;
  esac
done

bench_binary run.sh "$build" scan2lod_bench_lod
exec "$binary" "${args[@]}"
