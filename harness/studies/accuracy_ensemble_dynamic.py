"""The dynamic accuracy study's reference ensemble and predictability (docs/model.md §5.4): what
`python -m harness accuracy --model dynamic` measures beyond one reference trajectory.

After the reference ladder, the converged rung S gets tolerances.DYN_LYAPUNOV_TWINS perturbed twins
(harness/studies/predictability_dynamic.py). Their separation from it gives the scene's Lyapunov rate λ
and predictability time T_p; pointwise errors are judged only up to min(horizon, T_p). The
ensemble is the rung S, its twins and the next finer rung 2S (the reference's own error): the
spread of its members is what "equal" means for the metrics that survive chaos
(harness/check/ensemble_dynamic.py), computed for every mode over the whole run and written to
ensemble.csv, one row per mode and metric.
"""

import math
from dataclasses import dataclass

import numpy as np

from harness.check import ensemble_dynamic as en
from harness.studies import predictability_dynamic as predictability

CSV_NAME = "ensemble.csv"
COLUMNS = (
    "study",  # mode | member
    "mode",
    "metric",  # ensemble.DISTANCES and ensemble.SCALARS
    "value",  # a distance: mean over the members; a scalar: the run's own
    "spread",  # a distance: the largest between two members
    "lo",  # a scalar: the members' range
    "hi",
)


@dataclass(frozen=True)
class Context:
    """What a run's signature needs besides its positions."""

    L: float
    dt: float
    box: tuple

    def signature(self, pos, ell):
        return en.signature(pos, self.dt, self.L, ell, self.box)


def context(study):
    return Context(study.L, study.frame_dt, en.envelope_box(float(study.scene.head_radius), study.L))


@dataclass
class Ensemble:
    twins: predictability.Twins
    members: list  # signatures
    labels: list
    spread: dict
    pointwise_frames: int  # frames judged pointwise: up to min(horizon, T_p), at least one


def build(study, ref, finer, ctx, threads=None):
    """The ensemble of the reference `ref` (Study.ladder's result, its final rung's file still
    on disk) and `finer` (Runs of the extra doublings, Study.reference_error, possibly empty)."""
    final = ref["final"]
    S = ref["steps"][-1]["S2"]
    twins = predictability.run_twins(ref["build"], ref["final_path"], study.scratch, threads=threads)
    members = [ctx.signature(final.pos, final.ell)]
    labels = [f"S = {S}"]
    for j, x in enumerate(twins.positions):
        members.append(ctx.signature(x, final.ell))
        labels.append(f"S = {S}, twin {j + 1}")
    if finer:
        members.append(ctx.signature(finer[0].pos, finer[0].ell))
        labels.append(f"S = {2 * S}")
    kept = [(m, lab) for m, lab in zip(members, labels) if m is not None]
    members, labels = [m for m, _ in kept], [lab for _, lab in kept]
    tp = twins.rate.predictability
    within = study.horizon_frames if math.isinf(tp) else int(math.floor(tp / study.frame_dt + 1e-9))
    return Ensemble(twins, members, labels, en.spread(members), max(1, min(study.horizon_frames, within)))


def mode_rows(name, sig, ens):
    """ensemble.csv rows of one mode's signature (None: diverged) against the ensemble."""
    return _rows("mode", name, en.compare(sig, ens.members, ens.spread))


def member_rows(ens):
    """One row per member: its own distances to the others and its scalars (what the spread
    is made of)."""
    out = []
    for k, (sig, label) in enumerate(zip(ens.members, ens.labels)):
        others = ens.members[:k] + ens.members[k + 1 :]
        if others:
            out += _rows("member", label, en.compare(sig, others, ens.spread))
    return out


def _rows(study, name, cells):
    out = []
    for metric, (value, sp) in cells.items():
        lo, hi = sp if isinstance(sp, tuple) else (np.nan, np.nan)
        out.append(
            dict(
                study=study,
                mode=name,
                metric=metric,
                value=value,
                spread=np.nan if isinstance(sp, tuple) else sp,
                lo=lo,
                hi=hi,
            )
        )
    return out
