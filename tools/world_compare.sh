#!/usr/bin/env bash
# Builds of the CUDA binary timed side by side on the grid's rows (issue #42; docs/cuda.md "The
# hair–hair grid and the colliders"): tools/world_timing.sh's grid32-held, grid32-frame and
# grid32-substep rows (its scene, tools/world_scene.sh), each row run by every build in turn,
# ROUNDS times over, so that a build's rows and its neighbours' share the GPU's state. A build is
# NAME=BINARY, or NAME=VAR=VALUE[,VAR=VALUE...]@BINARY: the binary run with those variables set
# (a probe build's switches, read from the environment). Make a build by changing a define of
# cuda/dynamic/world.cu in a copy of the tree and `make build/hairsim-cuda` there. Run from the
# repository root, on a GPU node:
#
#   bash tools/world_compare.sh OUTDIR head=build/hairsim-cuda w512=/tmp/hb-w512/build/hairsim-cuda
#   BITS=1 bash tools/world_compare.sh OUTDIR main=probe/hairsim-cuda keep=HB_SPLAT_KEEP=1@probe/hairsim-cuda
#
# SMALL (default 10000) and LARGE (default 4194304; empty: none) choose the strand counts; ROWS
# (default "held frame substep") the rows: base (the default scene), held, frame, substep (the 32³
# grid), body, planes, headf (the head sphere's friction alone), and any of these with -once
# (--collide-once, docs/model.md §3.6). Each line of OUTDIR/bench.txt: build, round, row,
# strands, median/min/max ms a frame (--repeat 20 of 10 frames below 100,000 strands, 5 of 3 above).
# BITS=1 first runs every build on short scenes (10,000 strands: held 4 frames, substep 3, the body
# colliding once 3, held in fp64 3) and compares each state with the first build's by
# `python3 -m harness diff --exact` (bit-identical positions at every frame): a line of
# OUTDIR/bits.txt a build and scene, "same" or "differs"; any difference is exit status 1, before
# any row is timed.
set -u
OUTD=${1:?"usage: bash tools/world_compare.sh OUTDIR NAME=BINARY..."}
shift
[ $# -ge 1 ] || { echo "error: give at least one build as NAME=BINARY" >&2; exit 2; }
bin_of() { local spec=${1#*=}; echo "${spec#*@}"; }         # NAME=[ENV@]BINARY: its binary
env_of() { local spec=${1#*=}; [[ $spec == *@* ]] && echo "${spec%%@*}"; } # its VAR=VALUE list
for b in "$@"; do
  [[ $b == *=* ]] || { echo "error: '$b' is not NAME=BINARY" >&2; exit 2; }
  e=$(env_of "$b")
  if [ -n "$e" ]; then
    IFS=, read -r -a kvs <<<"$e"
    for kv in "${kvs[@]}"; do
      [[ $kv =~ ^[A-Za-z_][A-Za-z0-9_]*=[^[:space:]]*$ ]] ||
        { echo "error: '$kv' in build '${b%%=*}' is not VAR=VALUE" >&2; exit 2; }
    done
  fi
  [ -x "$(bin_of "$b")" ] || { echo "error: $(bin_of "$b") is not an executable binary" >&2; exit 2; }
done
for what in ${ROWS:-held frame substep}; do
  case ${what%-once} in base | held | frame | substep | body | planes | headf) ;;
    *) echo "error: row '$what' is none of base, held, frame, substep, body, planes, headf (each with -once or not)" >&2; exit 2 ;;
  esac
done
mkdir -p "$OUTD"
source "$(dirname "$0")/world_scene.sh"
run_as() { # BUILD COMMAND...: the command run with the build's variables set, in a subshell
  local e kv kvs
  e=$(env_of "$1")
  shift
  (
    if [ -n "$e" ]; then IFS=, read -r -a kvs <<<"$e"; for kv in "${kvs[@]}"; do export "${kv?}"; done; fi
    "$@"
  )
}
row() { # name build round row strands
  local name=$1 bin r=$3 what=$4 n=$5 fr=3 rep=5 flags
  bin=$(bin_of "$2")
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
  run_as "$2" world_row "$OUTD" "$name r$r $what" "$bin" "$n" $fr $rep $flags
}
bits() { # every build's states on short scenes against the first build's, bit for bit
  local scenes=("held:4:$HELD32" "substep:3:$SUBSTEP32" "body-once:3:$BODY --collide-once" "fp64-held:3:$HELD32 --precision fp64")
  local first="" sc name b fr flags out bad=0
  mkdir -p "$OUTD/bits"
  for b in "$@"; do
    name=${b%%=*}
    for sc in "${scenes[@]}"; do
      fr=${sc#*:}; flags=${fr#*:}; fr=${fr%%:*}; out="$OUTD/bits/$name-${sc%%:*}.h5"
      # shellcheck disable=SC2086 # DYN and the flags split into words on purpose
      if ! run_as "$b" "$(bin_of "$b")" $DYN --strands "${SMALL:-10000}" --frames "$fr" $flags --output "$out" \
        --force --quiet 2>>"$OUTD/bits.err"; then
        echo "$name ${sc%%:*} failed" | tee -a "$OUTD/bits.txt"; bad=1; continue
      fi
      [ -z "$first" ] && { echo "$name ${sc%%:*} reference" | tee -a "$OUTD/bits.txt"; continue; }
      if "${PYTHON:-python3}" -m harness diff --exact "$OUTD/bits/$first-${sc%%:*}.h5" "$out" >/dev/null 2>>"$OUTD/bits.err"; then
        echo "$name ${sc%%:*} same" | tee -a "$OUTD/bits.txt"
      else
        echo "$name ${sc%%:*} differs" | tee -a "$OUTD/bits.txt"; bad=1
      fi
    done
    [ -z "$first" ] && first=$name
  done
  return $bad
}
if [ "${BITS:-0}" = 1 ]; then bits "$@" || { echo "error: a build's states differ from ${1%%=*}'s (OUTDIR/bits.txt)" >&2; exit 1; }; fi
for r in $(seq 1 "${ROUNDS:-2}"); do
  for n in ${SMALL-10000} ${LARGE-4194304}; do
    for what in ${ROWS:-held frame substep}; do
      for b in "$@"; do row "${b%%=*}" "$b" "$r" "$what" "$n"; done
    done
  done
done
