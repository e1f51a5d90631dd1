#!/usr/bin/env bash
# Issue 49 on a node with two GPUs or more: the whole `make bench` with one GPU and with all of
# them, same revision, same node, one after the other (never at once), each in the background
# with its log; then the two runs compared step by step and figure by figure. Run from the
# repository root:
#
#   bash tools/gpu_scaling.sh one        # HB_GPUS=0 make bench OUT=results/gpu-scaling/one
#   bash tools/gpu_scaling.sh all        # make bench OUT=results/gpu-scaling/all
#   bash tools/gpu_scaling.sh status     # each run's last log line (poll this)
#   bash tools/gpu_scaling.sh compare    # harness compare one all: results/gpu-scaling/compare/
#
# Each run's steps.json holds every step's wall time and each GPU's work in it; the all-GPU
# log also prints a line a step with its work per GPU and balance. compare.md lists each step
# whose time changed beyond its noise (key `step NAME`: B/A below 1 is the speed-up) and every
# timed figure of the two runs (did two GPUs measuring at once move a GPU row?). Its exit status
# is 1 when a figure is slower beyond 1.05: here that is a finding, not a failure.
set -euo pipefail
root=results/gpu-scaling
py="$(cat build/python 2>/dev/null || echo python3)"
mkdir -p "$root"
case "${1:?usage: bash tools/gpu_scaling.sh one|all|status|compare}" in
one) HB_GPUS=0 nohup make bench OUT="$root/one" >"$root/one.log" 2>&1 & echo "started: $root/one.log" ;;
all) nohup make bench OUT="$root/all" >"$root/all.log" 2>&1 & echo "started: $root/all.log" ;;
status) for r in one all; do [ -f "$root/$r.log" ] && echo "$r: $(tail -n 1 "$root/$r.log")"; done; true ;;
compare) "$py" -m harness compare "$root/one" "$root/all" --out "$root/compare" || true ;;
*) echo "usage: bash tools/gpu_scaling.sh one|all|status|compare" >&2; exit 2 ;;
esac
