#!/usr/bin/env bash
# Delivery benchmark: `scan2lod export` of 8 levels in one process against
# what it cannot avoid: starting the program (`scan2lod --version`, timed in
# the same run), loading the model once and writing the file (both reported
# by the export process itself, --json). Also against the old way, one
# `extract` process per level. Each way runs --runs times, interleaved; medians are
# reported. Builds nothing; needs a model (built here at R = 256 if absent).
#
#   bench/export/run.sh [--build DIR] [--model M.mco] [--runs N] [--write]
#
# --write also writes bench/export/REPORT.md.
set -euo pipefail

here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
repo="$(dirname "$(dirname "$here")")"
source "$repo/bench/common.sh"
build="${SCAN2LOD_BUILD_DIR:-$repo/build}"
model="" runs=5 write=0
while [[ $# -gt 0 ]]; do
  case "$1" in
    --build) build="$2"; shift 2 ;;
    --model) model="$2"; shift 2 ;;
    --runs) runs="$2"; shift 2 ;;
    --write) write=1; shift ;;
    *) echo "bench/export/run.sh: unknown option $1" >&2; exit 2 ;;
  esac
done
bench_binary "$0" "$build" scan2lod
cli="$binary"
scratch="$(mktemp -d)"
trap 'rm -rf "$scratch"' EXIT
if [[ -z "$model" ]]; then
  model="$scratch/bunny256.mco"
  echo "building the bunny's model at R = 256" >&2
  "$cli" build "$repo/data/bunny/bun.conf" -o "$model" -r 256 -q
fi
levels="100,70,50,30,20,10,5,1"
now() { date +%s.%N; }
median() { sort -g | awk '{a[NR]=$1} END {print (NR % 2) ? a[(NR + 1) / 2] : (a[NR / 2] + a[NR / 2 + 1]) / 2}'; }

: >"$scratch/export" ; : >"$scratch/inside" ; : >"$scratch/separate"; : >"$scratch/plys"; : >"$scratch/start"
for ((run = 1; run <= runs; ++run)); do
  echo "run $run of $runs" >&2
  start=$(now)
  "$cli" --version >/dev/null
  startup=$(echo "$(now) - $start" | bc -l)
  echo "$startup" >>"$scratch/start"
  start=$(now)
  "$cli" export "$model" --levels "$levels" -o "$scratch/chain.glb" --json >"$scratch/json"
  echo "$(now) - $start" | bc -l >>"$scratch/export"
  python3 -c 'import json,sys; s=json.load(open(sys.argv[1]))["seconds"]; print(float(sys.argv[2]) + s["load"] + s["write"])' \
    "$scratch/json" "$startup" >>"$scratch/inside"
  start=$(now)
  "$cli" export "$model" --levels "$levels" -o "$scratch/level.ply" -q
  echo "$(now) - $start" | bc -l >>"$scratch/plys"
  start=$(now)
  IFS=, read -ra percents <<<"$levels"
  for p in "${percents[@]}"; do "$cli" extract "$model" --percent "$p" -o "$scratch/one_$p.glb" -q; done
  echo "$(now) - $start" | bc -l >>"$scratch/separate"
done
export_s=$(median <"$scratch/export")
inside_s=$(median <"$scratch/inside")
plys_s=$(median <"$scratch/plys")
separate_s=$(median <"$scratch/separate")
start_s=$(median <"$scratch/start")
glb_bytes=$(stat -c %s "$scratch/chain.glb")
ply_bytes=$(cat "$scratch"/level_LOD*.ply | wc -c)
model_bytes=$(stat -c %s "$model")

report="$(cat <<REPORT
# Delivery benchmark: export of 8 levels

Run $(date -u +%Y-%m-%dT%H:%MZ) on $(git -C "$repo" rev-parse --short HEAD), $(nproc) cores,
OMP_WAIT_POLICY=$OMP_WAIT_POLICY, medians of $runs interleaved runs. Model: $(basename "$model"),
$((model_bytes / 1000000)) MB. Levels: $levels % of the default structure.

| way | seconds | ratio |
|---|---:|---:|
| \`scan2lod export ... -o chain.glb\`, whole process | $(printf %.3f "$export_s") | 1.00 |
| what it cannot avoid: program start + its model load + its glTF write | $(printf %.3f "$inside_s") | $(printf %.2f "$(echo "$export_s / $inside_s" | bc -l)")× (export over this) |
| of which program start (\`scan2lod --version\`) | $(printf %.3f "$start_s") | |
| \`scan2lod export ... -o level.ply\` (8 binary PLYs), whole process | $(printf %.3f "$plys_s") | |
| 8 \`scan2lod extract\` processes, one .glb each (the old way) | $(printf %.3f "$separate_s") | $(printf %.2f "$(echo "$separate_s / $export_s" | bc -l)")× export's time |

Files: the chain is $((glb_bytes / 1000)) kB; the same levels as 8 binary PLYs take $((ply_bytes / 1000)) kB.
REPORT
)"
echo "$report"
[[ $write -eq 1 ]] && echo "$report" >"$here/REPORT.md"
exit 0
