#!/usr/bin/env bash
# How the build grows with the input: virtual scans of the bunny mesh
# (bun_zipper.ply, scan2lod scan) of growing size, each built in core and
# brick by brick under a memory budget, in the same run, one after the other.
# For each: wall time, peak RSS (/usr/bin/time), the bricks' disk, stage
# times (build --json) and throughput in input points per second. The ratio
# bricks / in core is taken within one run, since these machines vary by up to
# 2x from one hour to the next. Builds nothing.
#
#   bench/scale/run.sh [--build DIR] [--write] [--sizes "V:S:R ..."] [--memory 400M] [--shared DIR]
#
#   --sizes   views:size:resolution per row (default "16:480:1024 32:680:2048":
#             about 1 M and 4 M points; points per cube held about even, so
#             that the surface's triangles grow with the points)
#   --memory  the budget of the brick builds (default 400M)
#   --write   also write bench/scale/REPORT.md
set -euo pipefail

here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
repo="$(dirname "$(dirname "$here")")"
source "$repo/bench/common.sh"
build="${SCAN2LOD_BUILD_DIR:-$repo/build}"
command="bench/scale/run.sh $*"
write=0 sizes="16:480:1024 32:680:2048" memory=400M shared="$repo/../shared"
while [[ $# -gt 0 ]]; do
  case "$1" in
    --build) build="$2"; shift 2 ;;
    --write) write=1; shift ;;
    --sizes) sizes="$2"; shift 2 ;;
    --memory) memory="$2"; shift 2 ;;
    --shared) shared="$2"; shift 2 ;;
    *) echo "bench/scale/run.sh: unknown argument $1" >&2; exit 2 ;;
  esac
done
bench_binary bench/scale/run.sh "$build" scan2lod
mesh="$shared/data/bunny/reconstruction/bun_zipper.ply"
[[ -f "$mesh" ]] || { echo "bench/scale/run.sh: no $mesh" >&2; exit 1; }
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT

# run NAME ARGS...: build with /usr/bin/time; leaves $work/NAME.json and NAME.time
run() {
  local name="$1"; shift
  /usr/bin/time -f "%e %M" -o "$work/$name.time" "$binary" build "$@" --structure clusters --json --quiet \
    > "$work/$name.json"
}

rows=()
for size in $sizes; do
  IFS=: read -r views pixels resolution <<< "$size"
  scans="$work/scans_$views"
  mkdir -p "$scans"
  "$binary" scan "$mesh" -o "$scans" --views "$views" --size "${pixels}x${pixels}" --quiet
  echo "scale: $views views of ${pixels}^2 at R = $resolution: in core" >&2
  run core "$scans/scans.conf" -r "$resolution" -o "$work/core.mco"
  echo "scale: ... in bricks (--memory $memory)" >&2
  run bricks "$scans/scans.conf" -r "$resolution" -o "$work/bricks.mco" --memory "$memory" --work-dir "$work/w"
  disk=$(du -sb "$work/w" | cut -f1)
  rows+=("$(python3 - "$work" "$disk" "$resolution" <<'EOF'
import json, sys
work, disk, R = sys.argv[1], int(sys.argv[2]), sys.argv[3]
def load(name):
    j = json.load(open(f"{work}/{name}.json"))
    wall, kb = open(f"{work}/{name}.time").read().split()
    return j, float(wall), int(kb) / 1024
c, cw, cm = load("core")
b, bw, bm = load("bricks")
p = c["points"]
tri = c["clusters"]["full_triangles"]
cs, bs = c["seconds"], b["seconds"]
br = b.get("bricks", {})
print(f"| {p/1e6:.2f} M | {R} | {tri/1e6:.2f} M | {b['clusters']['full_triangles'] == tri} "
      f"| {cw:.1f} / {cm:.0f} | {bw:.1f} / {bm:.0f} | {br.get('bricks', '-')} of {br.get('brick_cubes', '-')} "
      f"| {disk/2**20:.0f} | {cs['reconstruct']:.1f} / {bs['reconstruct']:.1f} | {cs['clusters']:.1f} / {bs['clusters']:.1f} "
      f"| {p/cw/1e3:.0f} k / {p/bw/1e3:.0f} k | {bw/cw:.2f} | {tri/bs['clusters']/2e3:.0f} k |")
EOF
)")
  rm -rf "$work/w" "$scans" "$work"/*.mco
done

{
  echo "# Scale: in core and brick by brick"
  echo
  echo "$(date -u '+%Y-%m-%d %H:%M UTC') · $(uname -m) · nproc $(nproc) · load average at start $(cut -d' ' -f1-3 /proc/loadavg)  "
  echo "Command: \`$command\`  "
  echo "OpenMP: \`OMP_WAIT_POLICY=$OMP_WAIT_POLICY\`  "
  echo "Source: $(git -C "$repo" rev-parse --short HEAD) (at run time)"
  echo
  echo "Inputs: \`scan2lod scan\` of \`bun_zipper.ply\` (views × size² range images), built with"
  echo "\`scan2lod build SCANS.conf -r R --structure clusters --json\`, in core and with \`--memory $memory\`."
  echo "Wall time and peak RSS from \`/usr/bin/time\`; disk: the work folder's bricks at the end."
  echo "*same*: the brick build's full detail has the in-core triangle count (the tests check the triangles"
  echo "themselves). Throughput: input points per second of the whole build. *clusters/core*: triangles"
  echo "per second per core of the cluster stage (2 cores)."
  echo
  echo "| points | R | triangles | same | in core: s / MiB | bricks: s / MiB | bricks of cubes | disk MiB | reconstruct s (core / bricks) | clusters s (core / bricks) | points/s (core / bricks) | bricks ÷ core time | clusters/core |"
  echo "|--:|--:|--:|---|--:|--:|--:|--:|--:|--:|--:|--:|--:|"
  for row in "${rows[@]}"; do echo "$row"; done
} > "$work/report.md"
cat "$work/report.md"
if [[ $write -eq 1 ]]; then cp "$work/report.md" "$here/REPORT.md"; fi
