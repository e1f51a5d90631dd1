# shellcheck shell=bash
# The scene that tools/world_timing.sh, world_compare.sh and world_ncu.sh time (sourced by them): the default
# dynamic scene, fp32, 32 points, xpbd S = 8, I = 2, the lanes variant; the grid's friction and
# volume; the default body with friction (issues #42, #43; docs/cuda.md).
# shellcheck disable=SC2034 # used by the scripts that source this file
DYN="--stages init,collide,simulate --points 32 --substeps 8 --iterations 2 --solver xpbd --gravity 981 --drag 0.5 --damping 0.5 --bend-compliance 1e-6 --shape-compliance 1e-4 --shape-range 0.5 --wind-speed 150 --gust-amplitude 0.5 --gust-frequency 1 --gust-wavelength 60 --head-motion nod --motion-amplitude 0.25 --motion-frequency 1 --variant lanes --precision fp32"
GRID="--grid-friction 0.05,0.01 --grid-volume 2000"
# the 32³ grid rows: built once a frame and sampled once (held), sampled every substep (frame), built every substep
HELD32="--grid 32 $GRID --grid-rebuild held"
FRAME32="--grid 32 $GRID"
SUBSTEP32="--grid 32 $GRID --grid-rebuild substep"
BODY="--colliders configs/bodies/default.colliders --friction 0.3,0.2 --depenetration-speed 200"
# the same body met as contact planes found once a frame within 5 cm (docs/model.md §3.17)
BODY_PLANES="$BODY --contact-planes 5"
# the head sphere's friction and bounded depenetration alone, without the file's colliders
HEAD_FRICTION="--friction 0.3,0.2 --depenetration-speed 200"
# world_row OUTDIR LABEL BINARY STRANDS FRAMES REPEAT [FLAGS...]: one row, the scene plus FLAGS, its median,
# min and max ms a frame appended to OUTDIR/bench.txt and printed (a failed run: its exit status)
world_row() {
  local outd=$1 label=$2 bin=$3 n=$4 fr=$5 rep=$6 js rc
  shift 6
  # shellcheck disable=SC2086 # DYN splits into words on purpose
  js=$("$bin" $DYN --strands "$n" --frames "$fr" --repeat "$rep" --warmup 1 "$@" --json --quiet 2>>"$outd/bench.err")
  rc=$?
  [ $rc -ne 0 ] && { echo "$label $n FAILED rc=$rc: $(echo "$js" | head -c 300)" | tee -a "$outd/bench.txt"; return; }
  python3 -c "import json,sys; r=json.loads(sys.argv[1]); s=r['stages'][-1]; print('%-34s %9d  median %9.4f ms  min %9.4f  max %9.4f' % (sys.argv[2], r['strands'], s['median_ms'], s['min_ms'], s['max_ms']))" \
    "$js" "$label" | tee -a "$outd/bench.txt"
}
