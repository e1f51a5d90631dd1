#!/usr/bin/env bash
# Two builds' states compared bit for bit (issue #47's moves must change no output): every
# binary of BASE and NEW (build folders: build/ of two checkouts) runs the same paper run
# and the same dynamic run; the files' /particles and /observables must be identical
# (h5diff; /parameters differs by the revision and the timings). Run from the repository root,
# on a GPU node for the CUDA binaries (a binary missing from either build is skipped, said):
#
#   git worktree add /tmp/hb-base 5455e87 && make -C /tmp/hb-base -j16 all
#   make -j16 all && bash tools/same_outputs.sh /tmp/hb-base/build build
#
# Exit status 0 when every pair ran and matched, 1 otherwise.
set -u
base=${1:?usage: same_outputs.sh BASE_BUILD NEW_BUILD}
new=${2:?usage: same_outputs.sh BASE_BUILD NEW_BUILD}
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
paper=(--strands 2000 --points 32 --stages init,collide,wind,collide)
dynamic=(--strands 1000 --points 32 --hair-length 10 --stages init,simulate --frames 8 --velocities all
    --substeps 2 --iterations 2 --bend-compliance 1e-6 --wind-speed 300 --drag 2 --head-motion nod)
status=0
check() { # NAME BIN FLAGS...: both builds' BIN with FLAGS, then the two files diffed
    local name=$1 bin=$2
    shift 2
    if [ ! -x "$base/$bin" ] || [ ! -x "$new/$bin" ]; then
        echo "skip $name: $bin is not in both builds"
        return
    fi
    "$base/$bin" "$@" --output "$out/a.h5" --force --quiet && "$new/$bin" "$@" --output "$out/b.h5" --force --quiet ||
        { echo "FAIL $name: a run failed"; status=1; return; }
    for g in /particles /observables; do
        h5ls "$out/a.h5$g" >/dev/null 2>&1 || continue
        h5diff -q "$out/a.h5" "$out/b.h5" "$g" "$g" || { echo "FAIL $name: $g differs"; status=1; return; }
    done
    echo "same $name"
}
for p in fp32 fp64; do
    check "cpu paper $p" hairsim-cpu "${paper[@]}" --precision "$p"
    check "cpu dynamic $p" hairsim-cpu "${dynamic[@]}" --precision "$p"
    for bin in hairsim-cuda hairsim-cuda-strict hairsim-cuda-fastmath; do
        check "$bin paper $p" "$bin" "${paper[@]}" --precision "$p"
        for v in strand warp lanes; do
            check "$bin dynamic $v $p" "$bin" "${dynamic[@]}" --precision "$p" --variant "$v"
        done
    done
done
exit $status
