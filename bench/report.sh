#!/usr/bin/env bash
# The full benchmark report in one command: builds the two benchmark programs,
# runs the reconstruction benchmark (every method, both scaling tables) and
# the LOD benchmark, and regenerates the README's summary from the two reports.
# Run it after scripts/build.sh (which installs the peers); progress goes to
# stderr, and the time of each step and of the whole is printed at the end.
#
#   bench/report.sh [--build DIR] [--out DIR] [--quick] [--pcl-256]
#
#   --build DIR  build directory (default: $SCAN2LOD_BUILD_DIR, else <repo>/build);
#                configured (Release) if it is not yet, then only the two
#                benchmark targets are built, with $JOBS jobs (default: nproc)
#   --out DIR    write DIR/REPORT.md, DIR/lod/REPORT.md and DIR/SUMMARY.md
#                (the README section) and leave the repository alone; default:
#                bench/REPORT.md, bench/lod/REPORT.md and the section of
#                README.md between the bench-summary markers
#   --quick      both benchmarks' --quick (small settings, one run each: an
#                end-to-end check in about two minutes); implies nothing about
#                --out, so pair it with one unless the reports should be replaced
#   --pcl-256    also PCL's marching cubes at R = 256 (5 to 9 minutes more)
#
# A report is replaced only when its benchmark finished; a benchmark that
# fails leaves the old one and makes the script exit non-zero after the other
# has run. Peers that fail or time out inside a benchmark are rows of their own.
#
# On the project's 2-core machines, from an empty build directory and beside
# other jobs (load average 3 to 4), the whole took 20 min 07 s: build 2 min 29 s,
# reconstruction 10 min 31 s, LOD 7 min 07 s (2026-11-22). The timing line this
# prints at the end says the same for each run.
set -euo pipefail

here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
repo="$(dirname "$here")"
build="${SCAN2LOD_BUILD_DIR:-$repo/build}"
out=""
recon_args=()
lod_args=()
while [[ $# -gt 0 ]]; do
  case "$1" in
    --build) build="$2"; shift 2 ;;
    --out) out="$2"; shift 2 ;;
    --quick) recon_args+=(--quick); lod_args+=(--quick); shift ;;
    --pcl-256) recon_args+=(--pcl-256); shift ;;
    -h|--help) sed -n '2,/^set -euo/p' "${BASH_SOURCE[0]}" | sed '$d; s/^# \{0,1\}//'; exit 0 ;;
    *) echo "report.sh: unknown option $1 (see --help)" >&2; exit 2 ;;
  esac
done
build="$(mkdir -p "$build" && cd "$build" && pwd)"

if [[ -n "$out" ]]; then
  mkdir -p "$out/lod"
  out="$(cd "$out" && pwd)"
  recon_report="$out/REPORT.md"
  lod_report="$out/lod/REPORT.md"
else
  recon_report="$here/REPORT.md"
  lod_report="$here/lod/REPORT.md"
fi

now() { date +%s; }
minutes() { printf '%d min %02d s' $(($1 / 60)) $(($1 % 60)); }
start=$(now)
status=0

# 1. Build.
echo "report.sh: building the benchmarks in $build" >&2
if [[ ! -f "$build/CMakeCache.txt" ]]; then
  cmake -S "$repo" -B "$build" -DCMAKE_BUILD_TYPE=Release >/dev/null
fi
cmake --build "$build" -j "${JOBS:-$(nproc)}" --target scan2lod_bench_reconstruct scan2lod_bench_lod >&2
built=$(now)

# Runs one benchmark into its report through a temporary file, so that a
# failed or interrupted run keeps the old report.
run_into() {
  local report="$1"; shift
  local tmp
  tmp="$(mktemp "$(dirname "$report")/.REPORT.md.XXXXXX")"
  chmod 644 "$tmp"  # mktemp makes it private; a report is for everyone
  if "$@" > "$tmp"; then
    mv "$tmp" "$report"
    echo "report.sh: wrote $report" >&2
  else
    rm -f "$tmp"
    echo "report.sh: $1 failed; $report left as it was" >&2
    status=1
  fi
}

# 2. Reconstruction: every method, scaling of reconstruct() and of the model build.
run_into "$recon_report" "$here/run.sh" --build "$build" "${recon_args[@]}"
reconstructed=$(now)

# 3. LOD: model build, extraction, the simplifier peers.
run_into "$lod_report" "$here/lod/run.sh" --build "$build" "${lod_args[@]}"
lod_done=$(now)

# 4. The README's summary, from the two reports.
if [[ -n "$out" ]]; then
  python3 "$here/summary.py" --reconstruction "$recon_report" --lod "$lod_report" > "$out/SUMMARY.md"
  echo "report.sh: wrote $out/SUMMARY.md" >&2
else
  python3 "$here/summary.py" --readme "$repo/README.md"
fi

end=$(now)
echo "report.sh: whole run $(minutes $((end - start))) (build $(minutes $((built - start)))," \
     "reconstruction $(minutes $((reconstructed - built))), LOD $(minutes $((lod_done - reconstructed))))" >&2
exit $status
