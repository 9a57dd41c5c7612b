#!/usr/bin/env bash
# How the build grows with the input: virtual scans of the bunny mesh
# (bun_zipper.ply, scan2lod scan) of growing size, each built in core and
# brick by brick under a memory budget, in the same run, one after the other.
# For each: wall time, peak RSS (/usr/bin/time), the bricks' disk, stage
# times (build --json) and throughput in input points per second. The ratio
# bricks / in core is taken within one run, since these machines vary by up to
# 2x from one hour to the next. Builds nothing.
#
# Each row also gives the brick build's cut errors against the in-core
# build's at 10 k, 50 k and 200 k triangles: the two-sided mean distance of each
# cut to the in-core full detail, bricks over core.
#
# Each row also gives the brick build's own cut errors at 10 k, 50 k and 200 k
# triangles (to its full detail, in 1e-4 of the diagonal), so that rows of
# one shape at growing sizes can be compared, bricks-only rows included.
#
#   bench/scale/run.sh [--build DIR] [--write] [--sizes "M:V:S:R[:MEM[:bricks]] ..."] [--memory 400M] [--shared DIR]
#
#   --sizes   mesh:views:size:resolution per row, mesh "bunny" (bun_zipper.ply)
#             or "pair" (two bunnies side by side: a long scan set, like the
#             Happy Buddha's, whose R = 1024 surface has about 3.3 M triangles
#             from 1 M points); default "pair:16:560:1024 bunny:16:480:1024
#             bunny:32:680:2048": about 1, 1 and 4 M points. A fifth field is
#             the row's budget (else --memory); a sixth, "bricks", skips the
#             in-core build (10^8 points do not fit in core here).
#             The growth table: "pair:16:560:1024:400M pair:32:1230:2048:1G
#             pair:96:2250:4096:4G:bricks" (10^6, 10^7, 10^8 points)
#   --memory  the budget of the brick builds (default 400M)
#   --write   also write bench/scale/REPORT.md
set -euo pipefail

here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
repo="$(dirname "$(dirname "$here")")"
source "$repo/bench/common.sh"
build="${SCAN2LOD_BUILD_DIR:-$repo/build}"
command="bench/scale/run.sh $*"
write=0 sizes="pair:16:560:1024 bunny:16:480:1024 bunny:32:680:2048" memory=400M shared="$repo/../shared"
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

# Two copies of the bunny side by side, 1.1 widths apart.
python3 - "$mesh" "$work/pair.ply" <<'EOF'
import sys
lines = open(sys.argv[1]).read().split("\n")
end = lines.index("end_header")
nv = int(next(l for l in lines if l.startswith("element vertex")).split()[2])
nf = int(next(l for l in lines if l.startswith("element face")).split()[2])
v = [l.split()[:3] for l in lines[end + 1:end + 1 + nv]]
f = [l.split()[1:4] for l in lines[end + 1 + nv:end + 1 + nv + nf]]
xs = [float(p[0]) for p in v]
shift = 1.1 * (max(xs) - min(xs))
with open(sys.argv[2], "w") as out:
    out.write("ply\nformat ascii 1.0\nelement vertex %d\nproperty float x\nproperty float y\nproperty float z\n"
              "element face %d\nproperty list uchar int vertex_indices\nend_header\n" % (2 * nv, 2 * nf))
    for k in range(2):
        for p in v: out.write("%.9g %s %s\n" % (float(p[0]) + k * shift, p[1], p[2]))
    for k in range(2):
        for t in f: out.write("3 %d %d %d\n" % tuple(int(i) + k * nv for i in t))
EOF

# cut_error MODEL TRIANGLES: the cut's two-sided mean distance to full.ply and the diagonal, or "-"
cut_error() {
  # A hierarchy whose coarsest cut is above t has no such cut: "-".
  "$binary" extract "$1" --triangles "$2" -o "$work/cut.ply" --quiet 2>/dev/null || { echo "-"; return; }
  "$binary" compare "$work/cut.ply" "$work/full.ply" --json --samples 200000 |
    python3 -c 'import json,sys; j=json.load(sys.stdin); print((j["a_to_b"]["mean"]+j["b_to_a"]["mean"])/2, j["diagonal"])'
}

rows=()
for size in $sizes; do
  IFS=: read -r shape views pixels resolution budget mode <<< "$size"
  budget="${budget:-$memory}"
  scans="$work/scans_$views"
  mkdir -p "$scans"
  source_mesh="$mesh"
  [[ "$shape" == pair ]] && source_mesh="$work/pair.ply"
  "$binary" scan "$source_mesh" -o "$scans" --views "$views" --size "${pixels}x${pixels}" --quiet
  if [[ "$mode" != bricks ]]; then
    echo "scale: $views views of ${pixels}^2 at R = $resolution: in core" >&2
    run core "$scans/scans.conf" -r "$resolution" -o "$work/core.mco"
  fi
  echo "scale: $views views of ${pixels}^2 at R = $resolution: in bricks (--memory $budget)" >&2
  # The work folder at its largest: sampled while the build runs.
  # (du fails when a file vanishes under it; under set -e and pipefail that
  # must not end the sampler, nor the kill of an ended sampler the script.)
  ( peak=0; while sleep 2; do d=$(du -sb "$work/w" 2>/dev/null | cut -f1 || true); (( ${d:-0} > peak )) && peak=$d; echo "$peak" > "$work/disk"; done ) &
  sampler=$!
  run bricks "$scans/scans.conf" -r "$resolution" -o "$work/bricks.mco" --memory "$budget" --work-dir "$work/w"
  kill "$sampler" 2>/dev/null || true; wait "$sampler" 2>/dev/null || true
  disk=$(cat "$work/disk" 2>/dev/null || echo 0)
  rm -rf "$scans"
  reference=core
  [[ "$mode" == bricks ]] && reference=bricks
  "$binary" extract "$work/$reference.mco" --percent 100 -o "$work/full.ply" --quiet
  errors=()
  for m in core bricks; do
    for t in 10000 50000 200000; do
      if [[ -f "$work/$m.mco" ]]; then errors+=("$(cut_error "$work/$m.mco" "$t")"); else errors+=("-"); fi
    done
  done
  rows+=("$(python3 - "$work" "$disk" "$resolution" "$shape" "$budget" "${errors[@]}" <<'EOF'
import json, os, sys
work, disk, R, shape, budget = sys.argv[1], int(sys.argv[2]), sys.argv[3], sys.argv[4], sys.argv[5]
err = [None if e == "-" else tuple(map(float, e.split())) for e in sys.argv[6:12]]
def load(name):
    if not os.path.exists(f"{work}/{name}.json"): return None, None, None
    j = json.load(open(f"{work}/{name}.json"))
    wall, kb = open(f"{work}/{name}.time").read().split()
    return j, float(wall), int(kb) / 1024
c, cw, cm = load("core")
b, bw, bm = load("bricks")
p = b["points"]
tri = b["clusters"]["full_triangles"]
bs = b["seconds"]
br = b.get("bricks", {})
def ratio(i):  # bricks over core at one cut
    return "-" if err[i] is None or err[i + 3] is None else "%.2f" % (err[i + 3][0] / err[i][0])
def own(i):
    return "-" if err[i + 3] is None else "%.1f" % (1e4 * err[i + 3][0] / err[i + 3][1])
same = "-" if c is None else str(c["clusters"]["full_triangles"] == tri)
core = "-" if c is None else f"{cw:.1f} / {cm:.0f}"
core_r = "-" if c is None else f"{c['seconds']['reconstruct']:.1f}"
core_c = "-" if c is None else f"{c['seconds']['clusters']:.1f}"
core_t = "-" if c is None else f"{p/cw/1e3:.0f} k"
ratio_t = "-" if c is None else f"{bw/cw:.2f}"
print(f"| {shape} | {p/1e6:.2f} M | {R} | {tri/1e6:.2f} M | {same} | {budget} "
      f"| {core} | {bw:.1f} / {bm:.0f} | {br.get('bricks', '-')} of {br.get('brick_cubes', '-')} "
      f"| {b.get('cluster_block', 0)/1e3:.0f} k | {ratio(0)} / {ratio(1)} / {ratio(2)} | {own(0)} / {own(1)} / {own(2)} "
      f"| {disk/2**20:.0f} | {core_r} / {bs['reconstruct']:.1f} | {core_c} / {bs['clusters']:.1f} "
      f"| {core_t} / {p/bw/1e3:.0f} k | {ratio_t} | {tri/bs['clusters']/2e3:.0f} k |")
EOF
)")
  rm -rf "$work/w" "$work"/*.mco "$work"/*.json "$work"/*.time "$work"/cut.ply "$work"/full.ply "$work/disk"
done

{
  echo "# Scale: in core and brick by brick"
  echo
  echo "$(date -u '+%Y-%m-%d %H:%M UTC') · $(uname -m) · nproc $(nproc) · load average at start $(cut -d' ' -f1-3 /proc/loadavg)  "
  echo "Command: \`$command\`  "
  echo "OpenMP: \`OMP_WAIT_POLICY=$OMP_WAIT_POLICY\`  "
  echo "Source: $(git -C "$repo" rev-parse --short HEAD) (at run time)"
  echo
  echo "Inputs: \`scan2lod scan\` (views × size² range images) of \`bun_zipper.ply\` or of two copies side by side (*pair*), built with"
  echo "\`scan2lod build SCANS.conf -r R --structure clusters --json\`, in core and with \`--memory\` the row's budget."
  echo "Wall time and peak RSS from \`/usr/bin/time\`; disk: the work folder at its largest (sampled every 2 s)."
  echo "*same*: the brick build's full detail has the in-core triangle count (the tests check the triangles"
  echo "themselves). Throughput: input points per second of the whole build. *clusters/core*: triangles"
  echo "per second per core of the cluster stage (2 cores). *blocks*: triangles per block of the cluster"
  echo "hierarchy in the brick build (0: in core). *cuts*: the brick build's cut error over the in-core"
  echo "build's at 10 k / 50 k / 200 k triangles (two-sided mean distance to the in-core full detail, 200 k samples);"
  echo "*own cut error*: the brick build's, in 1e-4 of the diagonal (to the in-core full detail, or its own"
  echo "in bricks-only rows). \"-\": not run (bricks-only rows), or no cut that small."
  echo
  echo "| scans of | points | R | triangles | same | budget | in core: s / MiB | bricks: s / MiB | bricks of cubes | blocks | cuts 10 k / 50 k / 200 k | own cut error 10 k / 50 k / 200 k | disk MiB | reconstruct s (core / bricks) | clusters s (core / bricks) | points/s (core / bricks) | bricks ÷ core time | clusters/core |"
  echo "|---|--:|--:|--:|---|--:|--:|--:|--:|--:|--:|--:|--:|--:|--:|--:|--:|--:|"
  for row in "${rows[@]}"; do echo "$row"; done
} > "$work/report.md"
cat "$work/report.md"
if [[ $write -eq 1 ]]; then cp "$work/report.md" "$here/REPORT.md"; fi
