#!/usr/bin/env bash
# Builds of the CUDA binary timed side by side on the grid's rows (issue #42; docs/cuda.md "The
# hair–hair grid and the colliders"): tools/world_timing.sh's grid32-held, grid32-frame and
# grid32-substep rows (its scene, tools/world_scene.sh), each row run by every build in turn,
# ROUNDS times over, so that a build's rows and its neighbours' share the GPU's state. A build is
# NAME=PATH; make one by changing a define of cuda/dynamic/world.cu in a copy of the tree and
# `make build/hairsim-cuda` there. Run from the repository root, on a GPU node:
#
#   bash tools/world_compare.sh OUTDIR head=build/hairsim-cuda w512=/tmp/hb-w512/build/hairsim-cuda
#
# SMALL (default 10000) and LARGE (default 4194304; empty: none) choose the strand counts; ROWS
# (default "held frame substep") the rows: base (the default scene), held, frame, substep (the 32³
# grid), body, planes, headf (the head sphere's friction alone), and any of these with -once
# (--collide-once, docs/model.md §3.6). Each line of OUTDIR/bench.txt: build, round, row,
# strands, median/min/max ms a frame (--repeat 20 of 10 frames below 100,000 strands, 5 of 3 above).
set -u
OUTD=${1:?"usage: bash tools/world_compare.sh OUTDIR NAME=BINARY..."}
shift
[ $# -ge 1 ] || { echo "error: give at least one build as NAME=BINARY" >&2; exit 2; }
for b in "$@"; do
  [[ $b == *=* ]] || { echo "error: '$b' is not NAME=BINARY" >&2; exit 2; }
  [ -x "${b#*=}" ] || { echo "error: ${b#*=} is not an executable binary" >&2; exit 2; }
done
for what in ${ROWS:-held frame substep}; do
  case ${what%-once} in base | held | frame | substep | body | planes | headf) ;;
    *) echo "error: row '$what' is none of base, held, frame, substep, body, planes, headf (each with -once or not)" >&2; exit 2 ;;
  esac
done
mkdir -p "$OUTD"
source "$(dirname "$0")/world_scene.sh"
row() { # name binary round row strands
  local name=$1 bin=$2 r=$3 what=$4 n=$5 fr=3 rep=5 flags
  [ "$n" -lt 100000 ] && { fr=10; rep=20; }
  case ${what%-once} in
    held) flags=$HELD32 ;;
    frame) flags=$FRAME32 ;;
    substep) flags=$SUBSTEP32 ;;
    body) flags=$BODY ;;
    planes) flags=$BODY_PLANES ;;
    headf) flags=$HEAD_FRICTION ;;
    *) flags="" ;; # base
  esac
  [ "$what" != "${what%-once}" ] && flags="$flags --collide-once"
  # shellcheck disable=SC2086 # the flag string splits into words on purpose
  world_row "$OUTD" "$name r$r $what" "$bin" "$n" $fr $rep $flags
}
for r in $(seq 1 "${ROUNDS:-2}"); do
  for n in ${SMALL-10000} ${LARGE-4194304}; do
    for what in ${ROWS:-held frame substep}; do
      for b in "$@"; do row "${b%%=*}" "${b#*=}" "$r" "$what" "$n"; done
    done
  done
done
