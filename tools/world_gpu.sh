#!/usr/bin/env bash
# Issues 42 and 43's studies on a GPU node (one GPU is enough): the GPU rows of the stability
# map's grid and body slices, of the world study and of the dynamic sweep's body groups, each
# into results/world-gpu/<part> with its log. Run from the repository root after `make -j`:
#
#   bash tools/world_gpu.sh stability   # the five slices, --quick, CPU and every built CUDA build
#   bash tools/world_gpu.sh world       # harness world (full form): CPU rounds and the GPU's times
#   bash tools/world_gpu.sh sweep       # the body scene's throughput: cpu ref all cores, cuda lanes
#   bash tools/world_gpu.sh all         # the three, one after the other
#
# What each should show: stability.csv has rows with backend cuda for grid-dense, grid-nod,
# grid-gale, body-nod and body-inside (variant lanes where the slice has the grid or colliders);
# world.csv's gpu_ms_frame is filled for every row (gpu_variant lanes) and the grid's
# "32³ frame, friction on, volume on" row's gpu_cost_ratio is the issue-42 figure at 1M strands;
# the sweep's runs.csv has scene "body" rows for cuda lanes up to 4,194,304 strands.
set -euo pipefail
root=results/world-gpu
py="$(cat build/python 2>/dev/null || echo python3)"
mkdir -p "$root"
slices=(--slice grid-dense --slice grid-nod --slice grid-gale --slice body-nod --slice body-inside)
stability() { "$py" -m harness stability --quick --gpu yes "${slices[@]}" --out "$root/stability" \
  --report-dir "$root/stability" 2>&1 | tee "$root/stability.log"; }
world() { "$py" -m harness world --gpu auto --out "$root/world" 2>&1 | tee "$root/world.log"; }
sweep() {
  cat >"$root/body-sweep.toml" <<TOML
name = "world-gpu-body"
scene = "body"
frames = 1
repeat = 9
warmup = 1
[axes]
strands = [10000, 1000000, 4194304]
points = [32]
precision = ["fp32"]
solver = ["xpbd"]
[[cpu]]
variant = ["ref"]
threads = ["all"]
strands = [10000]
[[cuda]]
build = ["default"]
variant = ["lanes"]
block_size = [128]
TOML
  "$py" -m harness sweep "$root/body-sweep.toml" --gpu yes --out "$root/sweep" 2>&1 | tee "$root/sweep.log"
}
case "${1:?usage: bash tools/world_gpu.sh stability|world|sweep|all}" in
stability) stability ;;
world) world ;;
sweep) sweep ;;
all) stability && world && sweep ;;
*) echo "usage: bash tools/world_gpu.sh stability|world|sweep|all" >&2; exit 2 ;;
esac
