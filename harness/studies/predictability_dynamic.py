"""Perturbed twin runs: the Lyapunov rate λ and the predictability time of a scene
(harness/check/predictability_dynamic.py fits them), and the twins themselves, which are members of a
study's reference ensemble (harness/check/ensemble_dynamic.py).

A twin resumes a run from its first simulated frame with that frame's positions perturbed by
tolerances.DYN_LYAPUNOV_PERTURBATION_L (RMS over the non-root points, ·L; each twin its own
direction), on the same binary and variant, so the run and its twins differ by the perturbation
alone. The run must store the velocities of its first written simulated frame (`--velocities
all`: a resumed run needs them); the twins are written at the run's steps.
"""

from dataclasses import dataclass

import numpy as np

from harness import HarnessError
from harness.check import predictability_dynamic as pr
from harness.core import runner, tolerances
from harness.io import files
from harness.io.trajectory import open_trajectory


@dataclass
class Twins:
    rate: pr.Rate
    times: np.ndarray  # the written simulated frames' times, the first (the perturbed one) included
    positions: list  # each twin's positions [F][N][P][3] in double (or what `reduce` kept of them)


def _positions(path):
    with open_trajectory(path) as t:
        sim = t.simulated
        return t.step[sim].copy(), t.time[sim].copy(), np.stack([t.frame(f) for f in sim]).astype(np.float64)


def run_twins(build, base, scratch, n=None, threads=None, timeout=3600, reduce=None):
    """n (default DYN_LYAPUNOV_TWINS) twins of the run in file `base` on `build`
    (variants.Runner), perturbed at its first written simulated frame and written at its steps
    (its --output-every); Twins with their rate against the run. `reduce(x)`: what to keep of each
    twin's positions (default: the positions)."""
    n = tolerances.DYN_LYAPUNOV_TWINS if n is None else n
    d0 = tolerances.DYN_LYAPUNOV_PERTURBATION_L
    steps, times, x_base = _positions(base)
    with open_trajectory(base) as t:
        k, L, shape = t.paper_frames, t.hair_length, (t.n_strands, t.points, 3)
        first, last = t.simulated_index(k), t.simulated_index(t.n_frames - 1)
        every = int(t.dynamic_params.get("output_every", 1))
    twins, seps = [], []
    for j in range(n):
        src, out = scratch / f"{base.stem}_twin{j}_in.h5", scratch / f"{base.stem}_twin{j}.h5"
        _perturbed_copy(base, src, k, shape, d0, L, seed=j)
        flags = ["--input", src, "--input-frame", k, "--stages", "simulate", "--frames", last - first]
        flags += ["--output-every", every, "--output", out, "--force"]
        if build.variant:
            flags += ["--variant", build.variant]
        if build.backend == "cpu" and threads:
            flags += ["--threads", threads]
        try:
            runner.run_binary(build.binary, flags, timeout=timeout)
        finally:
            src.unlink(missing_ok=True)
        s, _, x = _positions(out)
        out.unlink()
        if not np.array_equal(s, steps):
            raise HarnessError(f"a twin of {base.name} was written at other steps than the run")
        seps.append(pr.separation(x[1:], x_base[1:], L))
        twins.append(x if reduce is None else reduce(x))
    return Twins(pr.rate(times[1:], np.array(seps), d0), times, twins)


def _perturbed_copy(base, path, frame, shape, d0, L, seed):
    """`base` copied to `path` with predictability.perturbation added to the positions of file
    frame `frame` (harness/io/files.py: whole or not at all)."""
    import h5py

    with files.writing(path) as tmp:
        files.copy(base, tmp)
        with h5py.File(tmp, "r+") as f:
            ds = f["particles/hair/position/value"]
            x = ds[frame].astype(np.float64).reshape(shape)
            ds[frame] = (x + pr.perturbation(shape, d0, L, seed)).reshape(-1, 3).astype(ds.dtype)


def rate_columns(rate):
    """The rate as a flat dict (an env.json entry, a CSV row's columns)."""
    return dict(
        lyapunov_per_s=rate.lam,
        lower_bound=rate.bound,
        grew=rate.grew,
        fit_from_s=rate.t_lo,
        fit_to_s=rate.t_hi,
        fit_frames=rate.samples,
        separation_end_L=rate.d_end,
        predictability_s=rate.predictability,
        perturbation_L=tolerances.DYN_LYAPUNOV_PERTURBATION_L,
        twins=tolerances.DYN_LYAPUNOV_TWINS,
    )
