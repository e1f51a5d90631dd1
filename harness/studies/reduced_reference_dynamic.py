"""The reduced-model study's references (harness/studies/reduced_dynamic.py): every strand and every point
simulated, xpbd, fp64, I = 1, with S doubled from the plan's ref_start until, at every written
frame up to the pointwise horizon, the RMS difference between S and 2S is under
tolerances.DYN_ACC_REF_FACTOR × the smallest RMS error of the rows it ranks (the accuracy study's
rule), or the plan's ref_max. The converged (finer) rung then gets perturbed twins
(studies/predictability_dynamic.py): their separation gives the scene's Lyapunov rate and predictability
time. The pointwise horizon is the written frames within that time over which the ladder's rule
holds from the start (`pointwise_frames`): a rung's truncation error grows with the scene's
sensitivity like any perturbation, so a reference converged early is not converged late, and no
row is judged pointwise where its reference is not. The rung, the coarser rung it was compared with
and the twins are the reference ensemble whose spread the rows' statistics
(harness/check/ensemble_dynamic.py) are judged against.

A row is kept as its file; its errors against a rung are read again when the rung changes.
"""

import math
import os
from dataclasses import dataclass, field

import numpy as np

from harness.check import ensemble_dynamic as en
from harness.check import observables_dynamic as ob
from harness.core import env, runner, tolerances
from harness.io.trajectory import open_trajectory
from harness.studies import predictability_dynamic as predictability
from harness.studies.accuracy import frame_errors


def read_positions(path):
    """(positions [F][N][P][3] in double of the written simulated frames, their steps, rest shape in
    double, stretch_max and blown-up strands over every simulated frame)."""
    with open_trajectory(path) as t:
        sim = t.simulated
        pos = np.stack([t.frame(f).reshape(t.n_strands, t.points, 3) for f in sim]).astype(np.float64)
        obs = t.observables
        return (
            pos,
            t.step[sim].copy(),
            t.rest.astype(np.float64),
            float(np.nanmax(obs["stretch_max"])),
            int(np.max(obs["blown_up_strands"])),
        )


@dataclass
class Reference:
    key: tuple  # (scene variant, strands)
    pos: np.ndarray
    steps: np.ndarray
    rest: np.ndarray
    substeps: int  # the finer rung of the last comparison
    ladder: list  # (S, 2S, worst RMS of S − 2S, worst ratio to the smallest row error): within T_p
    converged: bool  # the rule holds over at least the first written frame (horizon_frames ≥ 1)
    build: str = ""  # the binary and variant that ran it
    rate: object = None  # predictability.Rate of the twins
    members: list = field(default_factory=list)  # ensemble signatures: the rung, then its twins
    spread: dict = field(default_factory=dict)
    horizon_frames: int = 0  # written frames judged pointwise: within T_p and converged
    converged_frames: int = 0  # written frames from the start over which the ladder's rule holds
    coarse: object = None  # the coarser rung's positions (an ensemble member)


def pointwise_frames(ratio, within):
    """The written frames judged pointwise: of the first `within` (those within the predictability
    time), the leading ones whose ladder ratio (S − 2S over the smallest row error) is under
    tolerances.DYN_ACC_REF_FACTOR; a frame where both are zero (NaN) counts as converged.
    Returns (judged frames, leading converged frames over the whole run)."""
    q = np.asarray(ratio, dtype=np.float64)
    ok = np.isnan(q) | (q < tolerances.DYN_ACC_REF_FACTOR)
    lead = int(np.argmin(ok)) if not ok.all() else int(ok.size)
    return min(lead, int(within)), lead


class References:
    def __init__(self, plan, scratch, binary_for, frame_dt, L, box, log):
        """binary_for(points): the variants.Runner that runs a reference of that many points a strand."""
        self.plan, self.scratch, self.binary_for, self.dt, self.L, self.box, self.log = (
            plan, scratch, binary_for, frame_dt, L, box, log)  # fmt: skip
        self.cache = {}

    def rung(self, flags_for, tag, S, build):
        path = self.scratch / f"ref_{tag}_S{S}.h5"
        flags = flags_for(S, path) + ["--velocities", "all"]
        if build.variant:
            flags += ["--variant", build.variant]
        if build.backend == "cpu":
            flags += ["--threads", str(self.plan.threads or env.usable_cores())]
        runner.run_binary(build.binary, flags, timeout=3600)
        return path

    def get(self, key, flags_for, row_paths, written_dt, points):
        """The Reference of `key` (cached); flags_for(S, out) the binary flags of a rung, row_paths
        the files of the rows it ranks, written_dt the time between written frames, points the
        reference's points a strand."""
        if key in self.cache:
            return self.cache[key]
        tag = "_".join(str(k) for k in key)
        build = self.binary_for(points)
        S = self.plan.ref_start
        prev = self.rung(flags_for, tag, S, build)
        ladder = []
        while True:
            cur = self.rung(flags_for, tag, 2 * S, build)
            a, b = read_positions(prev)[0], read_positions(cur)[0]
            coarse = a
            d_rms, _ = frame_errors(a, b, self.L)
            low = np.nanmin(np.array([frame_errors(read_positions(p)[0], b, self.L)[0] for p in row_paths]), axis=0)
            with np.errstate(invalid="ignore", divide="ignore"):
                q = d_rms / low
            os.unlink(prev)
            ladder.append((S, 2 * S, d_rms, q))
            ok = bool(np.all(q < tolerances.DYN_ACC_REF_FACTOR))
            self.log(f"reduced: reference {tag} S = {S} vs {2 * S}: worst ratio {np.nanmax(q):.3g}")
            if ok or 4 * S > self.plan.ref_max:
                break
            prev, S = cur, 2 * S
        pos, steps, rest, _, _ = read_positions(cur)
        ref = Reference(key, pos, steps, rest, 2 * S, ladder, ok, build=build.label, coarse=coarse)
        self._ensemble(ref, cur, written_dt, build)
        self.cache[key] = ref
        return ref

    def _ensemble(self, ref, path, written_dt, build):
        """Twins of the converged rung: the rate, the pointwise horizon, the ensemble."""
        ell = ob.rest_lengths(ref.rest)

        def sig(x):
            return en.signature(x, written_dt, self.L, ell, self.box)

        twins = predictability.run_twins(build, path, self.scratch, threads=self.plan.threads, reduce=sig)
        os.unlink(path)
        ref.rate = twins.rate
        ref.members = [m for m in [sig(ref.pos), sig(ref.coarse), *twins.positions] if m is not None]
        ref.coarse = None
        ref.spread = en.spread(ref.members)
        tp = twins.rate.predictability
        F = len(ref.steps)
        within = max(1, min(F, F if math.isinf(tp) else int(math.floor(tp / written_dt + 1e-9))))
        ref.horizon_frames, ref.converged_frames = pointwise_frames(ref.ladder[-1][3], within)
        ref.converged = ref.horizon_frames > 0
        self.log(
            f"reduced: reference {ref.key}: S = {ref.substeps}, Lyapunov rate {twins.rate.lam:.3g} /s, "
            f"predictability {tp:.3g} s, converged over {ref.converged_frames} written frames; "
            f"pointwise over {ref.horizon_frames} of {F}"
        )
        ref.ladder = [(S, S2, float(np.nanmax(d[:within])), float(np.nanmax(q[:within])))
                      for S, S2, d, q in ref.ladder]  # fmt: skip
