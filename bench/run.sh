#!/usr/bin/env bash
# Runs the reconstruction benchmark from an existing build and prints its
# markdown report (progress goes to stderr). Builds nothing.
# bench/report.sh builds, runs both benchmarks and regenerates the README summary.
#
#   bench/run.sh [--build DIR] [--write] [benchmark options...]
#
#   --build DIR  build directory holding bin/scan2lod_bench_reconstruct
#                (default: $SCAN2LOD_BUILD_DIR, else <repo>/build)
#   --write      write the report to bench/REPORT.md instead of stdout
#   anything else goes to the benchmark: --quick, --pcl-256, --no-slow,
#   --runs N, --repeat-under S, --timeout S, --trim Q, --only TEXT,
#   --input FILE, --reference FILE, --samples N (see --help)
#
# Examples:
#   bench/run.sh --build build-bench --quick            # end-to-end check, under a minute
#   bench/run.sh --build build-bench --no-slow          # peers under a minute only (~4 min)
#   bench/run.sh --build build-bench --write            # every peer but PCL MC 256 (~10 min)
#   bench/run.sh --build build-bench --write --pcl-256  # adds PCL MC at R=256 (5-9 min more)
set -euo pipefail

here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
repo="$(dirname "$here")"
source "$repo/bench/common.sh"
build="${SCAN2LOD_BUILD_DIR:-$repo/build}"
write=0
args=()
while [[ $# -gt 0 ]]; do
  case "$1" in
    --build) build="$2"; shift 2 ;;
    --write) write=1; shift ;;
    *) args+=("$1"); shift ;;
  esac
done

bench_binary run.sh "$build" scan2lod_bench_reconstruct

if [[ $write -eq 1 ]]; then
  # Through a temporary file, so a failed or interrupted run keeps the old report.
  tmp="$(mktemp "$here/.REPORT.md.XXXXXX")"
  trap 'rm -f "$tmp"' EXIT
  "$binary" "${args[@]}" > "$tmp"
  mv "$tmp" "$here/REPORT.md"
  trap - EXIT
  echo "run.sh: wrote $here/REPORT.md" >&2
else
  exec "$binary" "${args[@]}"
fi
