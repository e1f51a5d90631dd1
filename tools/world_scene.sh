# shellcheck shell=bash
# The scene that tools/world_timing.sh and tools/world_ncu.sh time (sourced by both): the default
# dynamic scene, fp32, 32 points, xpbd S = 8, I = 2, the lanes variant; the grid's friction and
# volume; the default body with friction (issues #42, #43; docs/cuda.md).
# shellcheck disable=SC2034 # used by the scripts that source this file
DYN="--stages init,collide,simulate --points 32 --substeps 8 --iterations 2 --solver xpbd --gravity 981 --drag 0.5 --damping 0.5 --bend-compliance 1e-6 --shape-compliance 1e-4 --shape-range 0.5 --wind-speed 150 --gust-amplitude 0.5 --gust-frequency 1 --gust-wavelength 60 --head-motion nod --motion-amplitude 0.25 --motion-frequency 1 --variant lanes --precision fp32"
GRID="--grid-friction 0.05,0.01 --grid-volume 2000"
BODY="--colliders configs/bodies/default.colliders --friction 0.3,0.2 --depenetration-speed 200"
