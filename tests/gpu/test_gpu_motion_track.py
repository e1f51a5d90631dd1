"""A recorded head motion (--head-motion track, docs/model.md §3.2) on the CUDA port: the
rotation table is made on the host from the track (and the GPU reads the track the CPU's file
stores), so each simulate variant's frame of the strict build from the CPU's state, in the
middle of the recorded fast turn, equals the CPU's next frame bit for bit (no gusts: the rule of
tests/gpu/test_gpu_dynamic.py)."""

import pytest

from conftest import CPU_BIN, CUDA_STRICT_BIN
from harness import HarnessError
from harness.check import diff_dynamic
from harness.core import variants
from harness.io import motion_tracks
from harness.io.trajectory import open_trajectory
from support.statecheck import run

pytestmark = pytest.mark.gpu

SCENE = ["--strands", 700, "--points", 32, "--stages", "init,collide,simulate", "--substeps", 8, "--iterations", 2]
SCENE += ["--bend-compliance", "1e-6", "--shape-compliance", "1e-4", "--drag", "0.5", "--damping", "0.5"]


def _variants():
    try:
        d = variants.declared("cuda", "strict")
    except HarnessError:
        return ()
    return tuple(v for v in d.variants if d.runs(v, points=32))


@pytest.mark.parametrize("variant", _variants())
@pytest.mark.parametrize("precision", ["fp32", "fp64"])
def test_a_track_frame_on_the_gpu_is_the_cpus_bit_for_bit(tmp_path, variant, precision):
    track = motion_tracks.write_csv(tmp_path / "turn.csv", motion_tracks.fast_turn())
    cpu, gpu = tmp_path / "cpu.h5", tmp_path / "gpu.h5"
    flags = [*SCENE, "--precision", precision, "--head-motion", "track", "--motion-track", track]
    run(CPU_BIN, *flags, "--frames", 20, "--velocities", "all", "--output", cpu, "--quiet")  # into the turn
    with open_trajectory(cpu) as t:
        k = t.n_frames - 2
        step = int(t.step[k + 1])
    run(CUDA_STRICT_BIN, "--input", cpu, "--input-frame", k, "--stages", "simulate", "--frames", 1,
        "--variant", variant, "--output", gpu, "--quiet")  # fmt: skip
    r = diff_dynamic.compare(cpu, gpu, frames=[step], exact=True, check_paper=False)
    assert r.equivalent, f"{variant} {precision}: " + "; ".join(r.failures()[:5])
