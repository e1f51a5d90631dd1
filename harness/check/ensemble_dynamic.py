"""Metrics that survive chaos (docs/model.md §5.4): what a run looks like, compared with a
reference ensemble rather than with one trajectory. Numpy only; nothing here runs a binary.

Beyond the predictability time (harness/check/predictability_dynamic.py) two runs that differ in
rounding alone part, so a mode is compared with several reference runs (the converged
reference, its perturbed twins, the next finer rung): the spread of the ensemble is what
"equal" means, and a use's allowance (tolerances.DYN_ACC_USES_CHAOS) is added to it.

A run's `signature` (positions [F][N][P][3], frames dt apart) holds, over windows of
tolerances.DYN_ENSEMBLE_WINDOW_S:

  tip        the quantiles of the tip's position relative to its root (x, y, z), over the
             window's frames and strands
  curvature  the quantiles of the discrete curvature κ = |t_{k+1} − t_k| / ½(|e_k| + |e_{k+1}|)
             at every interior point (1/cm), t the unit segment directions
  area       the silhouette's area (cm²) seen from the front and from the side, on a fixed raster
             around the head (the hair's envelope), every AREA_EVERY_S of the run
  kinetic    the mean over frames of the kinetic energy of the motion, from positions
             (observables.kinetic_from_positions; ftl's stored correction does not enter)
  stretch    max and p99 of |len/ℓ_k − 1| against each segment's own rest length

`distances(a, b)`: tip (the windows' mean of the summed W1 over x, y, z, over L), curvature
(the windows' mean W1, over b's mean curvature), envelope (the mean over frames and views of
|A_a − A_b| over b's mean area). `compare(sig, members)`: each distance averaged over the
members, beside the ensemble's spread (the largest distance between two members) and each
scalar beside the members' range; `passes(row, use)` applies the use's allowance.
"""

import itertools
import math

import numpy as np

from harness.check import observables_dynamic as ob
from harness.core import tolerances

QUANTILES = (np.arange(128) + 0.5) / 128
PIXELS = 96
AREA_EVERY_S = 0.05  # the envelope changes slowly: a raster every 3rd frame at 60 frames a second
DISTANCES = ("tip_L", "curvature_rel", "envelope_rel")
SCALARS = ("kinetic_pos", "stretch_max", "stretch_p99")


def windows(frames, dt):
    """Slices of consecutive frames, each DYN_ENSEMBLE_WINDOW_S long (at least one frame); the
    last takes what is left."""
    n = max(1, round(tolerances.DYN_ENSEMBLE_WINDOW_S / dt))
    starts = list(range(0, frames, n)) or [0]
    if len(starts) > 1 and frames - starts[-1] < n:
        starts.pop()
    return [slice(a, b) for a, b in zip(starts, starts[1:] + [frames])]


def curvatures(x):
    """κ (1/cm) at the interior points of positions [..., P, 3]: [..., P − 2]."""
    e = np.diff(x, axis=-2)
    n = np.linalg.norm(e, axis=-1)
    t = e / np.where(n > 0, n, 1.0)[..., None]
    turn = np.linalg.norm(np.diff(t, axis=-2), axis=-1)
    return turn / (0.5 * (n[..., 1:] + n[..., :-1]) + 1e-300)


def envelope_box(head_radius, L):
    """The fixed raster box (lo, hi) of both views: the head and a hair length around it."""
    r = head_radius + L
    return np.array([-r, -r]), np.array([r, r])


def areas(pos, box):
    """Per frame, the silhouette area (cm²) from the front and the side: [F][2]."""
    lo, hi = box
    pixel = float(np.prod((hi - lo) / PIXELS))
    out = np.zeros((len(pos), 2))
    for f, x in enumerate(pos):
        for j, axes in enumerate(ob.VIEWS.values()):
            out[f, j] = np.count_nonzero(ob.rasterise(x, axes, lo, hi, PIXELS)) * pixel
    return out


def signature(pos, dt, L, ell, box):
    """The run's signature (module docstring) from positions [F][N][P][3]; ell: ℓ_k ([P−1] or
    [N][P−1]) or ℓ; box: envelope_box(). None for a run with a non-finite position."""
    x = np.asarray(pos, np.float64)
    if not np.isfinite(x).all():
        return None
    ws = windows(len(x), dt)
    tip = x[:, :, -1, :] - x[:, :, 0, :]
    kappa = curvatures(x)
    smax, sp99 = ob.stretch_stats(x, L, ell)
    return dict(
        tip=np.stack([[np.quantile(tip[w, :, c], QUANTILES) for c in range(3)] for w in ws]),
        curvature=np.stack([np.quantile(kappa[w], QUANTILES) for w in ws]),
        curvature_mean=float(np.mean(kappa)),
        area=areas(x[:: max(1, round(AREA_EVERY_S / dt))], box),
        kinetic_pos=float(np.mean(ob.kinetic_from_positions(x, dt))),
        stretch_max=smax,
        stretch_p99=sp99,
        L=float(L),
    )


def distances(a, b):
    """{tip_L, curvature_rel, envelope_rel} between signatures a and b (b the scale)."""
    tip = float(np.mean(np.sum(np.mean(np.abs(a["tip"] - b["tip"]), axis=-1), axis=-1))) / b["L"]
    curv = float(np.mean(np.abs(a["curvature"] - b["curvature"]))) / max(b["curvature_mean"], 1e-300)
    env = float(np.mean(np.abs(a["area"] - b["area"]))) / max(float(np.mean(b["area"])), 1e-300)
    return dict(tip_L=tip, curvature_rel=curv, envelope_rel=env)


def spread(members):
    """The ensemble's own spread: per distance the largest between two members (0 with one), per
    scalar the members' (lo, hi)."""
    out = {m: 0.0 for m in DISTANCES}
    for a, b in itertools.permutations(members, 2):
        for m, v in distances(a, b).items():
            out[m] = max(out[m], v)
    for m in SCALARS:
        vals = [s[m] for s in members]
        out[m] = (min(vals), max(vals))
    return out


def compare(sig, members, ens=None):
    """{metric: (value, spread or (lo, hi))} of a run's signature against the members' (ens:
    spread(members), when already computed). A diverged run (sig None) gives NaN values."""
    ens = ens or spread(members)
    out = {}
    if sig is None:
        return {m: (math.nan, ens[m]) for m in DISTANCES + SCALARS}
    d = [distances(sig, m) for m in members]
    for m in DISTANCES:
        out[m] = (float(np.mean([x[m] for x in d])), ens[m])
    for m in SCALARS:
        out[m] = (sig[m], ens[m])
    return out


def within_range(value, lo, hi, rel=0.0, factor=1.0):
    """value in [lo/factor − rel·|mid|, hi·factor + rel·|mid|] (mid the range's middle)."""
    if not math.isfinite(value):
        return False
    slack = rel * abs(0.5 * (lo + hi))
    return lo / factor - slack <= value <= hi * factor + slack


def passes(row, use):
    """{metric: passes} of compare()'s result for a use (tolerances.DYN_ACC_USES_CHAOS): a
    distance within the ensemble's spread plus the use's allowance; the kinetic energy of the
    motion within the members' range widened by the use's factor; stretch (against ℓ_k) under
    the use's stretch budget (tolerances.DYN_ACC_USES)."""
    allow = tolerances.DYN_ACC_USES_CHAOS[use]
    out = {}
    for m in DISTANCES:
        if m in row:
            v, sp = row[m]
            out[m] = bool(math.isfinite(v) and v <= sp + allow[m])
    if "kinetic_pos" in row:
        v, (lo, hi) = row["kinetic_pos"]
        out["kinetic_pos"] = within_range(v, lo, hi, factor=allow["kinetic_factor"])
    if "stretch_max" in row:
        v, _ = row["stretch_max"]
        out["stretch_max"] = bool(math.isfinite(v) and v <= tolerances.DYN_ACC_USES[use][1])
    return out
