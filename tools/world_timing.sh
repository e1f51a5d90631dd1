#!/usr/bin/env bash
# The hair–hair grid's and the colliders' GPU timings (issues #42, #43; docs/cuda.md "The hair–hair
# grid and the colliders"): median frame ms of the lanes variant, fp32, 32 points, the default
# dynamic scene, with and without each, every row of a strand count in one run on one GPU.
# Run from the repository root after `make -j`:   bash tools/world_timing.sh OUTDIR
# Each line: the row, strands, median/min/max ms a frame (--repeat 5 of 3 frames at 4M, 20 of 10 at 10k).
set -u
OUTD=${1:?"usage: bash tools/world_timing.sh OUTDIR"}
mkdir -p "$OUTD"
source "$(dirname "$0")/world_scene.sh"
A=${HAIRSIM_CUDA:-build/hairsim-cuda} # another build to compare: HAIRSIM_CUDA=PATH
BODIES="$OUTD/bodies"; mkdir -p "$BODIES"; cp configs/bodies/head.obj "$BODIES/"
sed 's/head.obj 64/head.obj 128/' configs/bodies/default.colliders > "$BODIES/body128.colliders"
for n in 4194304 10000; do
  fr=3; rep=5; [ $n -lt 100000 ] && { fr=10; rep=20; }
  world_row "$OUTD" base "$A" $n $fr $rep
  world_row "$OUTD" grid32-held "$A" $n $fr $rep $HELD32
  world_row "$OUTD" grid32-held-friction-only "$A" $n $fr $rep --grid 32 --grid-friction 0.05,0.01 --grid-rebuild held
  world_row "$OUTD" grid32-splat-only "$A" $n $fr $rep --grid 32
  world_row "$OUTD" grid32-frame "$A" $n $fr $rep $FRAME32
  world_row "$OUTD" grid32-substep "$A" $n $fr $rep $SUBSTEP32
  world_row "$OUTD" body64 "$A" $n $fr $rep $BODY
  world_row "$OUTD" body64-planes5 "$A" $n $fr $rep $BODY_PLANES
  world_row "$OUTD" body-bounded-head-only "$A" $n $fr $rep $HEAD_FRICTION
  # the collision step once a substep (--collide-once, docs/model.md §3.6)
  world_row "$OUTD" base-once "$A" $n $fr $rep --collide-once
  world_row "$OUTD" body64-once "$A" $n $fr $rep $BODY --collide-once
  world_row "$OUTD" body64-planes5-once "$A" $n $fr $rep $BODY_PLANES --collide-once
  world_row "$OUTD" body-bounded-head-only-once "$A" $n $fr $rep $HEAD_FRICTION --collide-once
  world_row "$OUTD" base-again "$A" $n $fr $rep
done
world_row "$OUTD" grid64-held "$A" 4194304 3 5 --grid 64 $GRID --grid-rebuild held
world_row "$OUTD" grid128-held "$A" 4194304 3 5 --grid 128 $GRID --grid-rebuild held
world_row "$OUTD" grid128-frame "$A" 4194304 3 5 --grid 128 $GRID
world_row "$OUTD" body128 "$A" 4194304 3 5 --colliders "$BODIES/body128.colliders" --friction 0.3,0.2 --depenetration-speed 200
