#!/usr/bin/env bash
# The same build on 1, 2, ... N MPI ranks of this machine, one after the
# other in one run: wall time, stage times (build --json of rank 0), each
# rank's peak RSS (/usr/bin/time), the hierarchy's blocks (made, made by
# rank 0, MiB each rank exchanged), and whether every model is the
# single-rank model byte for byte. What bench/scale/DISTRIBUTED.md reports.
#
#   bench/scale/ranks.sh SCANS.conf [--ranks 3] [--threads T] [--] [build options]
#
# Build options default to "--structure clusters -r 1024 --memory 400M".
# --threads T passes -j T to every rank (one thread a rank shows how the
# work divides; the default, every core a rank, shows what this machine
# does). Ranks past the core count run oversubscribed. Builds nothing; needs
# scan2lod built with MPI and mpirun.
set -euo pipefail

here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
repo="$(dirname "$(dirname "$here")")"
binary="${SCAN2LOD_BUILD_DIR:-$repo/build}/bin/scan2lod"
[[ $# -ge 1 ]] || { sed -n '2,13p' "$0" >&2; exit 2; }
conf="$1"; shift
ranks=3 threads="" options=()
while [[ $# -gt 0 ]]; do
  case "$1" in
    --ranks) ranks="$2"; shift 2 ;;
    --threads) threads="$2"; shift 2 ;;
    --) shift; options+=("$@"); break ;;
    *) options+=("$1"); shift ;;
  esac
done
[[ ${#options[@]} -gt 0 ]] || options=(--structure clusters -r 1024 --memory 400M)
[[ -n "$threads" ]] && options+=(-j "$threads")
[[ -x "$binary" ]] || { echo "ranks.sh: no $binary (run scripts/build.sh)" >&2; exit 1; }
command -v mpirun >/dev/null || { echo "ranks.sh: no mpirun (openmpi-bin)" >&2; exit 1; }

work="$(mktemp -d "${TMPDIR:-/tmp}/scan2lod_ranks.XXXXXX")"
trap 'rm -rf "$work"' EXIT
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1

echo "| N | wall s | read s | reconstruction s | clusters s | write s | peak RSS per rank (MiB) | blocks made / by rank 0 | exchanged per rank (MiB) | same model |"
echo "|--:|--:|--:|--:|--:|--:|---|---|--:|---|"
for ((n = 1; n <= ranks; ++n)); do
  run="$work/n$n"
  mkdir -p "$run"
  start=$(date +%s.%N)
  mpirun --bind-to none --oversubscribe -np "$n" sh -c \
    "/usr/bin/time -f '%M' -o '$run/rss.'\$OMPI_COMM_WORLD_RANK \"\$0\" \"\$@\"" \
    "$binary" build "$conf" "${options[@]}" -q --json --work-dir "$run/w" -o "$run/m.mco" > "$run/out.json" 2> "$run/err.txt" ||
    { echo "ranks.sh: the build on $n ranks failed:" >&2; tail -5 "$run/err.txt" >&2; exit 1; }
  wall=$(python3 -c "import sys; print(float(sys.argv[2]) - float(sys.argv[1]))" "$start" "$(date +%s.%N)")
  rss=$(for ((r = 0; r < n; ++r)); do echo $(($(cat "$run/rss.$r") / 1024)); done | paste -sd/ | sed 's|/| / |g')
  same="-"
  if ((n > 1)); then cmp -s "$work/n1/m.mco" "$run/m.mco" && same=yes || same=NO; fi
  python3 - "$run/out.json" "$n" "$wall" "$rss" "$same" <<'EOF'
import json, sys
text = open(sys.argv[1]).read()
j = json.loads(text[text.find("{"):text.rfind("}") + 1])
s = j["seconds"]
blocks = j.get("cluster_blocks", {})
made = "%d / %d" % (blocks["made"], blocks["here"]) if blocks else "-"
exchanged = "%.0f" % blocks["exchanged_mib"] if blocks and blocks["exchanged_mib"] > 0 else "-"
print("| %s | %.1f | %.2f | %.1f | %.1f | %.1f | %s | %s | %s | %s |" % (
    sys.argv[2], float(sys.argv[3]), s["read"], s["reconstruct"], s["clusters"], s["write"], sys.argv[4], made,
    exchanged, sys.argv[5]))
EOF
done
