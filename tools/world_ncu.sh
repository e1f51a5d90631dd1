#!/usr/bin/env bash
# Where a frame of the grid's and the colliders' rows goes (issues #42, #43; docs/cuda.md "The
# hair–hair grid and the colliders"): Nsight Compute's per-kernel GPU time (clocks locked, so
# above the table's wall times), registers and throughput for the default dynamic scene at
# STRANDS (default 10,000) without a world, with the held grid 32³ (friction + volume), with the
# default body (exact, and as contact planes) and with the head sphere's friction alone; then each
# row's wall median a frame (--repeat 20 of 10 frames, no profiler). Run from the repository root after `make -j`:
#   bash tools/world_ncu.sh OUTDIR [STRANDS]
set -u
OUTD=${1:?"usage: bash tools/world_ncu.sh OUTDIR [STRANDS]"}
N=${2:-10000}
mkdir -p "$OUTD"
command -v ncu >/dev/null || { echo "error: ncu (Nsight Compute) is not on PATH" >&2; exit 1; }
source "$(dirname "$0")/world_scene.sh"
DYN="$DYN --strands $N --quiet"
METRICS=gpu__time_duration.sum,launch__grid_size,launch__registers_per_thread,sm__throughput.avg.pct_of_peak_sustained_elapsed,dram__throughput.avg.pct_of_peak_sustained_elapsed
for r in "base:" "grid32-held:$HELD32" "body64:$BODY" "body64-planes5:$BODY_PLANES" "head-friction-only:--friction 0.3,0.2 --depenetration-speed 200"; do
  name=${r%%:*}; flags=${r#*:}
  # shellcheck disable=SC2086 # the flag strings split into words on purpose
  ncu --print-summary per-kernel --metrics "$METRICS" build/hairsim-cuda $DYN $flags --frames 2 > "$OUTD/ncu-$name.txt" 2>&1
  # shellcheck disable=SC2086
  ms=$(build/hairsim-cuda $DYN $flags --frames 10 --repeat 20 --warmup 1 --json 2>>"$OUTD/bench.err" |
    python3 -c "import json,sys; s=json.load(sys.stdin)['stages'][-1]; print(f\"{s['median_ms']:.4f} ms (min {s['min_ms']:.4f})\")")
  echo "$name $N strands: wall median $ms a frame" | tee -a "$OUTD/wall.txt"
done
