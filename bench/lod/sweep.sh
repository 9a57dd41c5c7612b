#!/usr/bin/env bash
# Runs the LOD robustness sweep from an existing build: every case below in its
# own scan2lod_bench_sweep process, one after the other (bench/lod/shape_sweep.cpp
# says what is checked: every offered level of the octree, how far down its
# levels go, and the cluster hierarchy's uniform and view cuts), then prints
# the markdown report (progress goes to stderr).
# Builds nothing.
#
#   bench/lod/sweep.sh [--build DIR] [--write] [--quick] [--only REGEX] [--shared DIR] [--logs DIR]
#
#   --build DIR   build directory holding bin/scan2lod_bench_sweep
#                 (default: $SCAN2LOD_BUILD_DIR, else <repo>/build)
#   --write       also write the report to bench/lod/SWEEP.md
#   --quick       only R = 32 and 64 (42 of the 74 cases)
#   --only REGEX  only the cases whose name matches (bash =~)
#   --shared DIR  the shared data folder (default: ../shared beside the repo)
#   --logs DIR    keep each case's per-level output in DIR/<name>_<R>.log
#
# Examples:
#   bench/lod/sweep.sh --build build --quick        # ~2 min
#   bench/lod/sweep.sh --build build --write        # all 74 cases, ~10 min on 2 cores
set -euo pipefail

here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
repo="$(dirname "$(dirname "$here")")"
source "$repo/bench/common.sh"
build="${SCAN2LOD_BUILD_DIR:-$repo/build}"
command="bench/lod/sweep.sh $*"
write=0 quick=0 only="" logs="" shared=()
while [[ $# -gt 0 ]]; do
  case "$1" in
    --build) build="$2"; shift 2 ;;
    --write) write=1; shift ;;
    --quick) quick=1; shift ;;
    --only) only="$2"; shift 2 ;;
    --shared) shared=(--shared "$2"); shift 2 ;;
    --logs) logs="$2"; shift 2 ;;
    *) echo "sweep.sh: unknown option $1 (see the top of $0)" >&2; exit 2 ;;
  esac
done

bench_binary sweep.sh "$build" scan2lod_bench_sweep

# "name R options": shapes with a known answer carry their components and χ;
# paths are relative to <shared>/data/bunny.
cases=()
for R in 32 64 128; do
  cases+=("box $R --shape box --expect-components 1 --expect-euler 2")
  cases+=("plate $R --shape plate --expect-components 1 --expect-euler 2")
  cases+=("cylinder $R --shape cylinder --expect-components 1 --expect-euler 2")
  cases+=("cone $R --shape cone --expect-components 1 --expect-euler 2")
  cases+=("arrow $R --shape arrow --expect-components 1 --expect-euler 2")
  cases+=("icosahedron $R --shape icosahedron --expect-components 1 --expect-euler 2")
  cases+=("mobius $R --shape mobius")
  cases+=("two_spheres_gap0.5 $R --shape two_spheres --gap-cells 0.5")
  cases+=("two_spheres_gap3 $R --shape two_spheres --gap-cells 3 --expect-components 2 --expect-euler 4")
  cases+=("sphere_touch $R --shape sphere_touch")
  cases+=("thin_cylinder $R --shape thin_cylinder")
  cases+=("genus2 $R --shape genus2 --expect-components 1 --expect-euler -2")
  cases+=("genus3 $R --shape genus3 --expect-components 1 --expect-euler -4")
  cases+=("bun_zipper_mesh $R --input reconstruction/bun_zipper.ply")
  cases+=("bun_res4_mesh $R --input reconstruction/bun_zipper_res4.ply")
  cases+=("bun000 $R --input data/bun000.ply")
  cases+=("bun_sub2 $R --scans bun000,bun045")
  cases+=("bun_sub3 $R --scans bun000,bun090,bun180")
  cases+=("bun_all $R --input data/bun.conf")
  cases+=("bun_virtual256 $R --scan-mesh reconstruction/bun_zipper.ply --size 256")
  cases+=("bun_virtual512 $R --scan-mesh reconstruction/bun_zipper.ply --size 512")
done
# R = 256 only where it adds something: the cases that failed or were close below it.
R=256
cases+=("box $R --shape box --expect-components 1 --expect-euler 2")
cases+=("plate $R --shape plate --expect-components 1 --expect-euler 2")
cases+=("two_spheres_gap0.5 $R --shape two_spheres --gap-cells 0.5")
cases+=("two_spheres_gap3 $R --shape two_spheres --gap-cells 3 --expect-components 2 --expect-euler 4")
cases+=("genus2 $R --shape genus2 --expect-components 1 --expect-euler -2")
cases+=("mobius $R --shape mobius")
cases+=("bun_zipper_mesh $R --input reconstruction/bun_zipper.ply")
cases+=("bun000 $R --input data/bun000.ply")
cases+=("bun_sub2 $R --scans bun000,bun045")
cases+=("bun_virtual256 $R --scan-mesh reconstruction/bun_zipper.ply --size 256")
cases+=("bun_virtual512 $R --scan-mesh reconstruction/bun_zipper.ply --size 512")

work="$(mktemp -d "${TMPDIR:-/tmp}/scan2lod_sweep.XXXXXX")"
trap 'rm -rf "$work"' EXIT
logs="${logs:-$work/logs}"
mkdir -p "$logs"
load_at_start="$(cut -d' ' -f1-3 /proc/loadavg)"

selected=()
for c in "${cases[@]}"; do
  read -r name R _ <<<"$c"
  [[ $quick == 1 && $R -gt 64 ]] && continue
  [[ -n "$only" && ! "$name" =~ $only ]] && continue
  selected+=("$c")
done

i=0
for c in "${selected[@]}"; do
  read -r name R args <<<"$c"
  i=$((i + 1))
  log="$logs/${name}_$R.log"
  start=$SECONDS
  # shellcheck disable=SC2086  # args are the case's options, split on purpose
  if "$binary" --name "$name" --resolution "$R" $args "${shared[@]}" >"$log" 2>&1; then
    outcome="octree $(grep -q $'^RESULT\t.*\tpass=1\t' "$log" && echo pass || echo FAIL)"
    outcome+=", clusters $(grep -q $'^RESULT\t.*\tcl_pass=1\t' "$log" && echo pass || echo FAIL)"
  else
    status=$?
    outcome="exit status $status"
    printf 'RESULT\tname=%s\tR=%s\tstatus=exit status %s\n' "$name" "$R" "$status" >>"$log"
  fi
  grep $'^RESULT\t' "$log" >>"$work/results.txt"
  printf '[%d/%d] %s R=%s: %s (%d s)\n' "$i" "${#selected[@]}" "$name" "$R" "$outcome" $((SECONDS - start)) >&2
done

"$binary" --table "$work/results.txt" --command "$command" --load-at-start "$load_at_start" >"$work/SWEEP.md"
cat "$work/SWEEP.md"
if [[ $write == 1 ]]; then
  # Through a rename, so an interrupted run keeps the old report.
  cp "$work/SWEEP.md" "$here/SWEEP.md.tmp" && mv "$here/SWEEP.md.tmp" "$here/SWEEP.md"
  echo "wrote $here/SWEEP.md" >&2
fi
