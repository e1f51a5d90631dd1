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
row() { # binary name strands frames repeat flags...
  local B=$1 name=$2 n=$3 fr=$4 rep=$5; shift 5
  local js rc; js=$($B $DYN --strands $n --frames $fr --repeat $rep --warmup 1 "$@" --json --quiet 2>>$OUTD/bench.err); rc=$?
  [ $rc -ne 0 ] && { echo "$name $n FAILED rc=$rc: $(echo "$js" | head -c 300)" | tee -a $OUTD/bench.txt; return; }
  python3 -c "import json,sys; r=json.loads(sys.argv[1]); s=r['stages'][-1]; print('%-34s %9d  median %9.4f ms  min %9.4f  max %9.4f' % (sys.argv[2], r['strands'], s['median_ms'], s['min_ms'], s['max_ms']))" "$js" "$name" | tee -a $OUTD/bench.txt
}
A=${HAIRSIM_CUDA:-build/hairsim-cuda} # another build to compare: HAIRSIM_CUDA=PATH
BODIES="$OUTD/bodies"; mkdir -p "$BODIES"; cp configs/bodies/head.obj "$BODIES/"
sed 's/head.obj 64/head.obj 128/' configs/bodies/default.colliders > "$BODIES/body128.colliders"
for n in 4194304 10000; do
  fr=3; rep=5; [ $n -lt 100000 ] && { fr=10; rep=20; }
  row $A base $n $fr $rep
  row $A grid32-held $n $fr $rep --grid 32 $GRID --grid-rebuild held
  row $A grid32-held-friction-only $n $fr $rep --grid 32 --grid-friction 0.05,0.01 --grid-rebuild held
  row $A grid32-splat-only $n $fr $rep --grid 32
  row $A grid32-frame $n $fr $rep --grid 32 $GRID
  row $A grid32-substep $n $fr $rep --grid 32 $GRID --grid-rebuild substep
  row $A body64 $n $fr $rep $BODY
  row $A body-bounded-head-only $n $fr $rep --friction 0.3,0.2 --depenetration-speed 200
  row $A base-again $n $fr $rep
done
row $A grid64-held 4194304 3 5 --grid 64 $GRID --grid-rebuild held
row $A grid128-held 4194304 3 5 --grid 128 $GRID --grid-rebuild held
row $A grid128-frame 4194304 3 5 --grid 128 $GRID
row $A body128 4194304 3 5 --colliders "$BODIES/body128.colliders" --friction 0.3,0.2 --depenetration-speed 200
