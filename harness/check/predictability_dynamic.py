"""How long a trajectory can be predicted pointwise (docs/model.md §5.4): the largest Lyapunov
rate λ from perturbed twin runs, and the predictability time it gives. Numpy only; nothing
here runs a binary (harness/studies/predictability_dynamic.py runs the twins).

A twin is the same run with one frame's positions perturbed by `d0` (RMS over the points, in
units of L). Its separation from the unperturbed run, d(t) = RMS over points of |x − x'|/L,
grows like d0·e^(λt) while it is small (the linear range) and saturates at the size of the
motion. `rate` fits ln d against t over the linear range: frames where d lies between
tolerances.DYN_LYAPUNOV_FLOOR·d0 (past the alignment of the perturbation with the growing
direction) and tolerances.DYN_LYAPUNOV_CEILING_L (below saturation), the log averaged over the
twins first. A separation that never leaves the floor gives the slope over the frames below
the ceiling and `grew` False: the run is not chaotic over its length, and its predictability
time is beyond the run (infinite here). One that passes the ceiling before three frames lie in
the linear range (frames written too far apart for the rate) gives the secant from the
perturbation to the first frame past the ceiling, a lower bound of λ (`bound`), so the
predictability time is an upper bound.

`predictability_time(λ)`: the time in which a difference of DYN_PREDICT_SEED_L (fp32's
rounding of a coordinate, the smallest difference two modes of a study have) grows to
DYN_PREDICT_TOLERANCE_L at the rate λ: beyond it two runs that differ in rounding alone differ
by more than that, so a pointwise error no longer ranks modes.
"""

import math
from dataclasses import dataclass

import numpy as np

from harness.core import tolerances


@dataclass(frozen=True)
class Rate:
    lam: float  # 1/s (per sample where times are sample numbers)
    grew: bool  # the separation passed the floor: the fit is over the linear range
    t_lo: float  # the fitted range
    t_hi: float
    samples: int  # frames fitted (0: a secant, see `bound`)
    d_end: float  # the separation (log-averaged over the twins) at the last frame, over L
    bound: bool = False  # λ is only a lower bound: the separation passed the ceiling within two frames

    @property
    def predictability(self):
        return predictability_time(self.lam) if self.grew else math.inf


def separation(a, b, L):
    """Per frame, the RMS over the points of |a − b| / L, for positions [F][N][P][3] (or [F][...][3])."""
    d = np.linalg.norm(np.asarray(a, np.float64) - np.asarray(b, np.float64), axis=-1)
    return np.sqrt(np.mean(d.reshape(d.shape[0], -1) ** 2, axis=1)) / L


def rate(times, separations, d0, floor=None, ceiling=None):
    """Rate of the separations [F] or [twins][F] (over L; d0 the perturbation, over L) against
    `times` [F] (module docstring). Frames with a zero or non-finite separation are left out."""
    floor = tolerances.DYN_LYAPUNOV_FLOOR if floor is None else floor
    ceiling = tolerances.DYN_LYAPUNOV_CEILING_L if ceiling is None else ceiling
    t = np.asarray(times, np.float64)
    d = np.atleast_2d(np.asarray(separations, np.float64))
    with np.errstate(divide="ignore", invalid="ignore"):
        logs = np.log(d)
    good = np.all(np.isfinite(logs), axis=0)
    mean_log = np.where(good, np.mean(np.where(np.isfinite(logs), logs, 0.0), axis=0), np.nan)
    below = good & (mean_log <= math.log(ceiling))
    if below.any():  # stop at the first frame past the ceiling: saturation does not return to linear
        past = np.flatnonzero(good & ~below)
        if past.size:
            below[past[0] :] = False
    linear = below & (mean_log >= math.log(floor * d0))
    grew = int(linear.sum()) >= 3
    d_end = float(np.exp(mean_log[good][-1])) if good.any() else math.nan
    past = np.flatnonzero(good & (mean_log > math.log(ceiling)))
    if not grew and past.size:  # past the ceiling before three frames of growth: sampled too coarsely
        k = past[0]  # the secant from the perturbation (at t[0] less a frame) is a lower bound of λ
        t0 = t[0] - (t[1] - t[0]) if len(t) > 1 else t[0] - 1.0
        return Rate((mean_log[k] - math.log(d0)) / (t[k] - t0), True, float(t0), float(t[k]), 0, d_end, True)
    use = linear if grew else below
    if int(use.sum()) < 2:
        return Rate(math.nan, grew, math.nan, math.nan, int(use.sum()), d_end)
    slope = float(np.polyfit(t[use], mean_log[use], 1)[0])
    return Rate(slope, grew, float(t[use][0]), float(t[use][-1]), int(use.sum()), d_end)


def predictability_time(lam, seed=None, tolerance=None):
    """ln(tolerance/seed)/λ (s); infinite where λ ≤ 0 or not finite."""
    seed = tolerances.DYN_PREDICT_SEED_L if seed is None else seed
    tolerance = tolerances.DYN_PREDICT_TOLERANCE_L if tolerance is None else tolerance
    if not (math.isfinite(lam) and lam > 0):
        return math.inf
    return math.log(tolerance / seed) / lam


def perturbation(shape, d0, L, seed=0):
    """A deterministic perturbation of positions [N][P][3] whose RMS over the points is d0·L,
    the roots (point 0) left alone (the head moves them, §3.2)."""
    rng = np.random.default_rng(seed)
    p = rng.standard_normal(shape)
    p[..., 0, :] = 0.0
    rms = math.sqrt(float(np.mean(np.sum(p * p, axis=-1))))
    return p * (d0 * L / rms)
