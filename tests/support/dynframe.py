"""One simulated frame of a dynamic state file, and the rule a GPU frame is held to against
the CPU's frame from the same input (harness/tolerances.py GPU_DYN_*). Shared by
tests/test_gpu_dynamic.py and tests/test_stability_dynamic.py; files are read through
harness.trajectory."""

import numpy as np

from harness.tolerances import (
    GPU_DYN_MAX_OVER_FRACTION,
    GPU_DYN_OBS_ABS,
    GPU_DYN_OBS_REL,
    GPU_DYN_POS,
    GPU_DYN_VEL,
)
from harness.trajectory import open_trajectory


class Frame:
    """A simulated frame of a file (default: the last written): positions, velocities, observables."""

    OBSERVABLES = ("stretch_max", "penetration_max", "kinetic_energy", "blown_up_strands")

    def __init__(self, path, index=-1):
        with open_trajectory(path) as t:
            idx = index % t.n_frames
            self.step = int(t.step[idx])
            self.n, self.p = t.n_strands, t.points
            self.x = t.frame(idx)
            self.flags = t.flags
            self.v = t.velocity_at_step(self.step)
            assert self.v is not None, f"{path}: no velocities stored for step {self.step}"
            rows = t.observables[t.observables["step"] == self.step]
            assert len(rows) == 1, f"{path}: no observables for step {self.step}"
            self.obs = {k: rows.iloc[0][k].item() for k in self.OBSERVABLES}


def point_errors(a, b):
    return np.linalg.norm(a.astype(np.float64) - b.astype(np.float64), axis=-1)


def assert_close(gpu, cpu, build, precision, what, substep, hair_length, record=None):
    """The GPU frame within GPU_DYN_POS/GPU_DYN_VEL of the CPU's (velocities times the
    substep h, so both are positions), over at most GPU_DYN_MAX_OVER_FRACTION of the
    points; observables within GPU_DYN_OBS_*; no blown-up strand. `record(key, worst)`
    receives each worst error when given."""
    for name, ga, ca, tol, scale in (
        ("positions", gpu.x, cpu.x, GPU_DYN_POS, 1.0 / hair_length),
        ("velocities", gpu.v, cpu.v, GPU_DYN_VEL, substep / hair_length),
    ):
        assert ga.shape == ca.shape, f"{what} {name}: shapes {ga.shape} vs {ca.shape}"
        assert np.isfinite(ga).all(), f"{what} {name}: NaN or Inf in the GPU state"
        d = point_errors(ga, ca) * scale
        t = tol[build][precision]
        over = int((d > t).sum())
        allowed = int(GPU_DYN_MAX_OVER_FRACTION[precision] * d.size)
        worst = float(d.max())
        if record:
            record(f"{name} {build} {precision}", worst)
        assert over <= allowed, (
            f"{what} {name}: {over} of {d.size} points more than {t:g} apart (allowed "
            f"{allowed}); worst {worst:.3g} at {np.unravel_index(d.argmax(), d.shape)}"
        )
    for k in ("stretch_max", "penetration_max", "kinetic_energy"):
        g, c = float(gpu.obs[k]), float(cpu.obs[k])
        assert abs(g - c) <= GPU_DYN_OBS_REL[precision] * abs(c) + GPU_DYN_OBS_ABS[precision], (
            f"{what}: {k} {g!r} on the GPU, {c!r} on the CPU"
        )
    assert gpu.obs["blown_up_strands"] == cpu.obs["blown_up_strands"] == 0, f"{what}: blown-up strands"


def same_bits(a, b):
    return (
        a.x.dtype == b.x.dtype and a.x.tobytes() == b.x.tobytes() and a.v.tobytes() == b.v.tobytes() and a.obs == b.obs
    )
