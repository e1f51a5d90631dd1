"""The long runs of `python -m harness accuracy --model dynamic`: what a hair user sees over
seconds rather than how far each point is from one reference trajectory (docs/harness.md, "The
dynamic accuracy study"). Measured with harness/check/observables_dynamic.py and harness/check/ensemble_dynamic.py.

Three scenes, all made from the study's own scene (curly hair stays curly), `long_strands`
strands (the study's points), `long_seconds` of simulated time (rest: REST_SECONDS at most):

  motion   the study's scene as it is: the metrics that survive chaos against the reference
           ensemble (the distribution of the tip and of the curvature over time, the silhouette's
           area, the tip's spectrum), the kinetic energy of the motion from positions (the stored
           velocities' beside it: ftl's include its correction), the drift of the energy, stretch
           against each segment's own rest length ℓ_k
  release  the study's scene with the head still, no wind and no collider, let go from its rest
           shape: strands sag and swing below their roots and settle; the median over the strands
           whose tip swings (observables.swings) of its swing frequency over the first half and of
           its damping ratio over the whole run (the envelope's decay; its noise is the larger of
           the strand halves' difference and the fit's standard error); no swing, no value
  rest     the study's scene with the head still and no wind (the collider on) and damping
           REST_DAMPING, so that it settles within the run: rest jitter (RMS frame-to-frame
           velocity, largest frame-to-frame move) over the last fifth, what flickers on screen

Every mode of the oracle build (the cpu default variant: solver × s × S × I × precision, and the
no-simulation baseline) runs all three. The reference ensemble of each scene: xpbd fp64 I = 1 at
the short study's converged S (at most `long_ref_max`: statistics converge long before pointwise
positions), the same at 2S, and DYN_LYAPUNOV_TWINS perturbed twins of the S run
(studies/predictability_dynamic.py; their separation also gives the scene's Lyapunov rate and
predictability time, rows of the reference). A distance is the mean over the members beside the
ensemble's spread (the largest distance between two members); a scalar beside the members'
range. Each metric's noise is half the difference between its values on the even and the odd
strands. Written to observables.csv (COLUMNS), one row per scene × mode × metric.
"""

import os
from concurrent.futures import ThreadPoolExecutor
from dataclasses import replace

import numpy as np

from harness.check import ensemble_dynamic as en
from harness.check import observables_dynamic as ob
from harness.core import runner
from harness.studies import predictability_dynamic as predictability
from harness.studies.accuracy import MODE_COLUMNS, REF_ITERATIONS, REF_PRECISION, REF_SOLVER

CSV_NAME = "observables.csv"
SCENES = ("motion", "release", "rest")
REST_DAMPING = 5.0  # 1/s: motion decays as e^(−β·t/2), to e^(−10) of its start in 4 s
REST_SECONDS = 5.0  # the rest scene's time (at most the long time): what the hair takes to settle on the head
COLUMNS = (
    "study",  # mode | reference
    "scene",  # motion | release | rest
    *MODE_COLUMNS,
    "seconds",
    "metric",
    "value",
    "noise",  # half the even-strands against odd-strands difference
    "reference",  # the reference's value (its S run)
    "ref_uncertainty",  # a distance: the ensemble's spread; a scalar: half the members' range
    "verdict",  # ok | diverged | escaped (the worst frame)
    "ref_lo",  # a scalar: the members' range
    "ref_hi",
)
# metric -> (scene, how it is compared: "distance" to the ensemble, "range" of the members' values,
# "" reported beside the reference)
METRICS = {
    "kinetic_pos": ("motion", "range"),
    "kinetic_stored": ("motion", ""),
    "energy_drift": ("motion", ""),
    "stretch_max": ("motion", ""),
    "stretch_p99": ("motion", ""),
    "tip_L": ("motion", "distance"),
    "curvature_rel": ("motion", "distance"),
    "envelope_rel": ("motion", "distance"),
    "tip_spectrum": ("motion", "distance"),
    "tip_frequency_hz": ("release", "range"),
    "tip_damping_ratio": ("release", "range"),
    "jitter_rms_velocity": ("rest", ""),
    "jitter_max_move": ("rest", ""),
}
REFERENCE_ONLY = ("lyapunov_per_s", "predictability_s")  # rows of the reference, per scene
DAMPING_FIT_SE = "tip_damping_fit_se"  # not a row: it widens tip_damping_ratio's noise


def scene_variants(scene, motion_flags=("--head-motion", "--motion-amplitude", "--motion-frequency")):
    """{motion, release, rest}: the study's scene, and its still, windless variants (module
    docstring)."""
    calm = {k: v for k, v in scene.dynamic.items() if k not in motion_flags and not k.startswith(("--wind", "--gust"))}
    calm["--head-motion"] = "still"
    release = replace(scene, dynamic={**calm, "--no-collider": False})
    rest = replace(scene, dynamic={**calm, "--damping": REST_DAMPING})
    return {"motion": scene, "release": release, "rest": rest}


class Signatures:
    """A scene's run as the motion metrics see it: its ensemble signature and tip signal, for the
    whole run and for its even and odd strands."""

    def __init__(self, pos, ctx, ell):
        self.pos = pos
        ell = np.asarray(ell) if np.ndim(ell) else ell
        self.parts = {}
        for part, sl in (("all", slice(None)), ("even", slice(0, None, 2)), ("odd", slice(1, None, 2))):
            e = ell[sl] if np.ndim(ell) == 2 else ell
            x = pos[:, sl]
            self.parts[part] = (ctx.signature(x, e), ob.tip_displacement(x) if np.isfinite(x).all() else None)


def _motion(sig, members, dt, part, vel, gravity):
    """{metric: value} of one part (all, even, odd strands) of a motion run against the members."""
    s, tip = sig.parts[part]
    out = {}
    if s is None:
        return out
    m_sigs = [m.parts[part][0] for m in members if m.parts[part][0] is not None]
    if m_sigs:
        for metric, (v, _) in en.compare(s, m_sigs).items():
            if metric in METRICS:
                out[metric] = v
        out["tip_spectrum"] = float(
            np.mean([ob.spectrum_distance(tip, m.parts[part][1], dt) for m in members if m.parts[part][1] is not None])
        )
    else:
        out.update({m: s[m] for m in en.SCALARS})
    x = sig.pos if part == "all" else sig.pos[:, 0::2] if part == "even" else sig.pos[:, 1::2]
    if vel is not None:
        v = vel if part == "all" else vel[:, 0::2] if part == "even" else vel[:, 1::2]
        k, _, e = ob.energy(x, v, gravity)
        out["kinetic_stored"] = float(np.mean(k))
        out["energy_drift"] = ob.drift(ob.kinetic_from_positions(x, dt) + (e - k), np.arange(len(k)) * dt)
    return out


def _motion_spread(members, dt):
    """The ensemble's spread of the motion distances: the largest between two members."""
    sigs = [m.parts["all"][0] for m in members if m.parts["all"][0] is not None]
    out = {k: v for k, v in en.spread(sigs).items() if k in en.DISTANCES} if sigs else {}
    tips = [m.parts["all"][1] for m in members if m.parts["all"][1] is not None]
    out["tip_spectrum"] = max((ob.spectrum_distance(a, b, dt) for a in tips for b in tips if a is not b), default=0.0)
    return out


def _scalar(scene, pos, dt):
    """{metric: value} of a release or rest run (positions of some strands)."""
    if scene == "release":
        half = max(4, len(pos) // 2)
        out = {"tip_frequency_hz": ob.swing(pos[:half], dt)[0]}
        _, out["tip_damping_ratio"], out[DAMPING_FIT_SE] = ob.swing(pos, dt)
        return out
    rms, most = ob.jitter(pos[-max(2, len(pos) // 5) :], dt)
    return {"jitter_rms_velocity": rms, "jitter_max_move": most}


def metrics(scene, pos, vel, L, gravity, dt, ctx=None, ell=None, members=()):
    """({metric: value}, {metric: noise}, verdict) of one run; noise from the strand halves.
    Motion runs need ctx (accuracy_ensemble.Context), ell and the members (Signatures)."""
    verdict = ob.verdict(pos, L, vel)
    if verdict == ob.DIVERGED:
        return {}, {}, verdict
    if scene == "motion":
        sig = Signatures(pos, ctx, ell)
        whole = _motion(sig, members, dt, "all", vel, gravity)
        halves = [_motion(sig, members, dt, part, vel, gravity) for part in ("even", "odd")]
    else:
        whole = _scalar(scene, pos, dt)
        halves = [_scalar(scene, pos[:, h::2], dt) for h in (0, 1)]
    noise = {k: abs(halves[0][k] - halves[1][k]) / 2 for k in whole if k in halves[0] and k in halves[1]}
    if DAMPING_FIT_SE in whole:  # the envelope fit's own scatter, where it is the larger
        noise.pop(DAMPING_FIT_SE, None)
        both = [v for v in (noise["tip_damping_ratio"], whole.pop(DAMPING_FIT_SE)) if np.isfinite(v)]
        noise["tip_damping_ratio"] = max(both) if both else float("nan")
    return whole, noise, verdict


class LongRuns:
    def __init__(self, study, ref_build, ref_S, log, configure, read_run):
        """study: accuracy_dynamic.Study; configure and read_run: its scene-with-a-mode and
        its reader (passed in, so that this module does not import the study back)."""
        from harness.studies import accuracy_ensemble_dynamic as accuracy_ensemble

        self.study, self.plan, self.log = study, study.plan, log
        self.configure, self.read_run = configure, read_run
        self.ref_build = ref_build
        self.ctx = accuracy_ensemble.context(study)
        self.frames = max(4, round(self.plan.long_seconds / study.frame_dt))
        self.scenes = scene_variants(study.scene)
        self.ref_S = min(ref_S, self.plan.long_ref_max)

    def frames_of(self, scene):
        if scene == "rest":
            return max(4, min(self.frames, round(REST_SECONDS / self.study.frame_dt)))
        return self.frames

    def run(self, scene, build, solver, substeps, iterations, precision, ftl_damping, tag, threads, keep=False):
        sc = self.configure(
            self.scenes[scene],
            solver=solver,
            substeps=substeps,
            iterations=iterations,
            precision=precision,
            frames=self.frames_of(scene),
            strands=self.plan.long_strands,
            ftl_damping=ftl_damping,
        )
        out = self.study.path(f"long_{scene}_{tag}")
        flags = runner.run_flags(sc, build.backend, variant=build.variant, threads=threads, output=out, force=True)
        runner.run_binary(build.binary, flags + ["--velocities", "all"], timeout=3600)
        r = self.read_run(out)
        if not keep:
            os.unlink(out)
        return r, out

    def reference(self, scene, threads):
        """(the S run, {metric: value}, {metric: (lo, hi) or spread}, the members' Signatures, rate)."""
        st = self.study
        runs = [
            self.run(
                scene,
                self.ref_build,
                REF_SOLVER,
                S,
                REF_ITERATIONS,
                REF_PRECISION,
                None,
                f"ref_S{S}",
                threads,
                keep=S == self.ref_S,
            )  # fmt: skip
            for S in (self.ref_S, 2 * self.ref_S)
        ]
        base, base_path = runs[0]
        twins = predictability.run_twins(self.ref_build, base_path, st.scratch, threads=threads)
        os.unlink(base_path)
        positions = [base.pos, runs[1][0].pos, *twins.positions]
        gravity = float(self.scenes[scene].dynamic.get("--gravity", 981.0))
        dt = st.frame_dt
        members = [Signatures(x, self.ctx, base.ell) for x in positions] if scene == "motion" else []
        values = [
            metrics(
                scene,
                x,
                base.vel if k == 0 else None,
                st.L,
                gravity,
                dt,
                self.ctx,
                base.ell,
                members[:k] + members[k + 1 :],
            )[0]  # fmt: skip
            for k, x in enumerate(positions)
        ]
        own = values[0]
        band = _motion_spread(members, dt) if scene == "motion" else {}
        for metric, (where, how) in METRICS.items():
            vals = [v[metric] for v in values if np.isfinite(v.get(metric, np.nan))]
            if where == scene and how == "range" and vals:
                band[metric] = (min(vals), max(vals))
        return base, own, band, members, twins.rate

    def measure(self, modes, jobs):
        """Rows of observables.csv for the reference and every mode."""
        st = self.study
        threads = st.cpu_threads if self.ref_build.backend == "cpu" else None
        rows, refs = [], {}
        for scene in SCENES:
            base, own, band, members, rate = self.reference(scene, threads)
            gravity = float(self.scenes[scene].dynamic.get("--gravity", 981.0))
            refs[scene] = (base, own, band, members, gravity)
            self.log(
                f"dynamic accuracy: long runs, {scene}: reference S = {self.ref_S}, {2 * self.ref_S} and "
                f"{len(members) or 'its'} twins ({self.frames_of(scene)} frames × {self.plan.long_strands} strands); "
                f"Lyapunov rate {rate.lam:.3g} /s, predictability {rate.predictability:.3g} s"
            )
            keys = dict(
                mode=f"{self.ref_build.label} {REF_SOLVER} S{self.ref_S} I{REF_ITERATIONS} {REF_PRECISION}",
                backend=self.ref_build.backend,
                build=self.ref_build.build,
                variant=self.ref_build.variant,
                solver=REF_SOLVER,
                substeps=self.ref_S,
                iterations=REF_ITERATIONS,
                precision=REF_PRECISION,
            )
            own_rate = {"lyapunov_per_s": rate.lam, "predictability_s": rate.predictability}
            rows += self._rows("reference", scene, keys, (own, {}, ob.OK), own, band, extra=own_rate)

        def one(m, scene):
            r, _ = self.run(scene, m.runner, m.solver, m.substeps, m.iterations, m.precision, m.ftl_damping, m.tag, 1)
            base, _, _, members, gravity = refs[scene]
            return m, scene, metrics(scene, r.pos, r.vel, st.L, gravity, st.frame_dt, self.ctx, r.ell, members)

        with ThreadPoolExecutor(max_workers=jobs) as pool:
            futures = [pool.submit(one, m, scene) for m in modes for scene in SCENES]
            for k, f in enumerate(futures, 1):
                m, scene, got = f.result()
                _, own, band, _, _ = refs[scene]
                rows += self._rows("mode", scene, m.columns(), got, own, band)
                if k % 40 == 0 or k == len(futures):
                    self.log(f"dynamic accuracy: long runs {k}/{len(futures)}")
        return rows

    def _rows(self, study, scene, keys, got, own, band, extra=None):
        values, noise, verdict = got
        shared = dict(
            study=study,
            scene=scene,
            strands=self.plan.long_strands,
            points=self.study.scene.points,
            seconds=self.frames_of(scene) * self.study.frame_dt,
            verdict=verdict,
            **keys,
        )
        out = []
        cells = [(m, values.get(m, np.nan)) for m, (where, _) in METRICS.items() if where == scene]
        cells += list((extra or {}).items())
        for metric, value in cells:
            b = band.get(metric, np.nan)
            lo, hi = b if isinstance(b, tuple) else (np.nan, np.nan)
            unc = (hi - lo) / 2 if isinstance(b, tuple) else b
            out.append(
                {
                    **{c: None for c in COLUMNS},
                    **shared,
                    "metric": metric,
                    "value": value,
                    "noise": noise.get(metric, np.nan),
                    "reference": own.get(metric, np.nan),
                    "ref_uncertainty": unc,
                    "ref_lo": lo,
                    "ref_hi": hi,
                }
            )
        return out
