"""The long runs of `python -m harness accuracy --model dynamic`: what a hair user sees over
seconds rather than how far each point is from the reference's after a fraction of one
(docs/harness.md, "The dynamic accuracy study"). Measured with harness/check/observables.py.

Three scenes, `long_strands` strands (the study's points), `long_seconds` of simulated time
(rest: REST_SECONDS at most):

  motion   the study's own scene (a nodding head in gusty wind): energy per particle
           (kinetic mean, drift of kinetic + potential), stretch max and p99, pointwise error
           percentiles over the whole run, the distance between the distributions of the tip
           (relative to its root) and between the tip's spectra, silhouette IoU front/side
  release  still-dynamic (a still head, gravity and damping) without its collider: strands let
           go from their rest shape swing freely below their roots and settle; the median over
           strands of each tip's swing frequency over the first half and damping ratio
           over the whole run (ob.damping_fit: the envelope's decay; its noise is the larger
           of the strand halves' difference and the fit's standard error)
  rest     still-dynamic as shipped (the collider on: hair draped on the head) with damping
           REST_DAMPING, so that it settles within the run: rest jitter (RMS frame-to-frame
           velocity, largest frame-to-frame move) over the last fifth, what flickers on screen

Every mode of the oracle build (the cpu default variant: solver × s × S × I × precision, and
the no-simulation baseline) runs all three; the reference is xpbd fp64 I = 1 at the short study's
converged S (at most `long_ref_max`: statistics converge long before pointwise positions),
and once more at 2S: |metric(S) − metric(2S)| is the reference's own
uncertainty. Each metric's noise is half the difference between its values on the even and
the odd strands. Written to observables.csv (COLUMNS), one row per scene × mode × metric.
"""

import os
from concurrent.futures import ThreadPoolExecutor
from dataclasses import replace

import numpy as np

from harness.check import observables as ob
from harness.core import runner, scenes
from harness.studies.accuracy import REF_ITERATIONS, REF_PRECISION, REF_SOLVER

CSV_NAME = "observables.csv"
RELEASE_SCENE = "still-dynamic"
SCENES = ("motion", "release", "rest")
REST_DAMPING = 5.0  # 1/s: motion decays as e^(−β·t/2), to e^(−10) of its start in 4 s
REST_SECONDS = 5.0  # the rest scene's time (at most the long time): what the hair takes to settle on the head
COLUMNS = (
    "study",  # mode | reference
    "scene",  # motion | release | rest
    "mode",
    "backend",
    "build",
    "variant",
    "solver",
    "ftl_damping",
    "substeps",
    "iterations",
    "precision",
    "strands",
    "points",
    "seconds",
    "metric",
    "value",
    "noise",  # half the even-strands against odd-strands difference
    "reference",  # the reference's value
    "ref_uncertainty",  # |reference at S − at 2S|
    "verdict",  # ok | diverged | escaped (the worst frame)
)
# metric -> (scene, compared with the reference as: "rel" relative error, "abs" the value is
# itself a distance or overlap, "" reported beside the reference)
METRICS = {
    "kinetic_mean": ("motion", "rel"),
    "energy_drift": ("motion", ""),
    "stretch_max": ("motion", ""),
    "stretch_p99": ("motion", ""),
    "err_rms_L": ("motion", "abs"),
    "err_p50_L": ("motion", "abs"),
    "err_p95_L": ("motion", "abs"),
    "err_p99_L": ("motion", "abs"),
    "err_max_L": ("motion", "abs"),
    "tip_distribution_L": ("motion", "abs"),
    "tip_spectrum": ("motion", "abs"),
    "iou_front": ("motion", "abs"),
    "iou_side": ("motion", "abs"),
    "tip_frequency_hz": ("release", "rel"),
    "tip_damping_ratio": ("release", "rel"),
    "jitter_rms_velocity": ("rest", "rel"),
    "jitter_max_move": ("rest", "rel"),
}
DAMPING_FIT_SE = "tip_damping_fit_se"  # not a row: it widens tip_damping_ratio's noise
IOU_EVERY = 10  # silhouettes every 10th frame: they change slowly and cost the most


def _scene_metrics(scene, pos, vel, ref, L, gravity, dt):
    """{metric: value} of one run (arrays [F][N][P][3]) against the reference's positions."""
    out = {}
    if scene == "motion":
        k, _, e = ob.energy(pos, vel, gravity)
        t = np.arange(len(k)) * dt
        out["kinetic_mean"] = float(np.mean(k))
        out["energy_drift"] = ob.drift(e, t)
        out["stretch_max"], out["stretch_p99"] = ob.stretch_stats(pos, L)
        if ref is not None:
            e = ob.error_percentiles(pos, ref, L)
            out.update({f"err_{k}_L": v for k, v in e.items()})
            out["tip_distribution_L"] = ob.tip_distribution_distance(pos, ref, L)
            out["tip_spectrum"] = ob.spectrum_distance(ob.tip_displacement(pos), ob.tip_displacement(ref), dt)
            ious = [ob.silhouette_iou(pos[f], ref[f]) for f in range(0, len(pos), IOU_EVERY)]
            out["iou_front"] = float(np.mean([i["front"] for i in ious]))
            out["iou_side"] = float(np.mean([i["side"] for i in ious]))
    elif scene == "release":
        half = max(4, len(pos) // 2)
        out["tip_frequency_hz"], _, _ = ob.swing(pos[:half], dt)
        _, out["tip_damping_ratio"], out[DAMPING_FIT_SE] = ob.swing(pos, dt)
    else:
        out["jitter_rms_velocity"], out["jitter_max_move"] = ob.jitter(pos[-max(2, len(pos) // 5) :], dt)
    return out


def metrics(scene, pos, vel, ref, L, gravity, dt):
    """({metric: value}, {metric: noise}, verdict) of one run; noise from the strand halves."""
    verdict = ob.verdict(pos, L, vel)
    if verdict == ob.DIVERGED:
        return {}, {}, verdict
    whole = _scene_metrics(scene, pos, vel, ref, L, gravity, dt)
    halves = [
        _scene_metrics(scene, pos[:, h::2], vel[:, h::2], None if ref is None else ref[:, h::2], L, gravity, dt)
        for h in (0, 1)
    ]
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
        self.study, self.plan, self.log = study, study.plan, log
        self.configure, self.read_run = configure, read_run
        self.ref_build = ref_build
        self.frames = max(4, round(self.plan.long_seconds / study.frame_dt))
        release = scenes.load_scene(RELEASE_SCENE).with_overrides(points=study.scene.points)
        # no collider: the strands swing freely below their roots instead of draping on the head
        release = replace(release, dynamic={**release.dynamic, "--no-collider": False})
        still = scenes.load_scene(RELEASE_SCENE).with_overrides(points=study.scene.points)
        rest = replace(still, dynamic={**still.dynamic, "--damping": REST_DAMPING})
        self.scenes = {"motion": study.scene, "release": release, "rest": rest}
        self.ref_S = min(ref_S, self.plan.long_ref_max)

    def frames_of(self, scene):
        if scene == "rest":
            return max(4, min(self.frames, round(REST_SECONDS / self.study.frame_dt)))
        return self.frames

    def run(self, scene, build, solver, substeps, iterations, precision, ftl_damping, tag, threads):
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
        os.unlink(out)
        return r

    def measure(self, modes, jobs):
        """Rows of observables.csv for the reference and every mode."""
        st = self.study
        threads = st.cpu_threads if self.ref_build.backend == "cpu" else None
        rows, refs = [], {}
        for scene in SCENES:
            runs = [
                self.run(
                    scene, self.ref_build, REF_SOLVER, S, REF_ITERATIONS, REF_PRECISION, None, f"ref_S{S}", threads
                )
                for S in (self.ref_S, 2 * self.ref_S)
            ]
            dt = st.frame_dt
            gravity = float(self.scenes[scene].dynamic.get("--gravity", 981.0))
            fine = metrics(scene, runs[0].pos, runs[0].vel, runs[0].pos, st.L, gravity, dt)
            finer = metrics(scene, runs[1].pos, runs[1].vel, runs[0].pos, st.L, gravity, dt)
            unc = {k: abs(v - finer[0].get(k, np.nan)) for k, v in fine[0].items()}
            refs[scene] = (runs[0], fine[0], unc, gravity)
            self.log(
                f"dynamic accuracy: long runs, {scene}: reference S = {self.ref_S} and {2 * self.ref_S} "
                f"({self.frames_of(scene)} frames × {self.plan.long_strands} strands)"
            )
            rows += self._rows(
                "reference",
                scene,
                dict(
                    mode=f"{self.ref_build.label} {REF_SOLVER} S{self.ref_S} I{REF_ITERATIONS} {REF_PRECISION}",
                    backend=self.ref_build.backend,
                    build=self.ref_build.build,
                    variant=self.ref_build.variant,
                    solver=REF_SOLVER,
                    substeps=self.ref_S,
                    iterations=REF_ITERATIONS,
                    precision=REF_PRECISION,
                ),
                fine,
                fine[0],
                unc,
            )

        def one(m, scene):
            r = self.run(scene, m.runner, m.solver, m.substeps, m.iterations, m.precision, m.ftl_damping, m.tag, 1)
            ref_run, ref_vals, unc, gravity = refs[scene]
            return m, scene, metrics(scene, r.pos, r.vel, ref_run.pos, st.L, gravity, st.frame_dt)

        with ThreadPoolExecutor(max_workers=jobs) as pool:
            futures = [pool.submit(one, m, scene) for m in modes for scene in SCENES]
            for k, f in enumerate(futures, 1):
                m, scene, got = f.result()
                _, ref_vals, unc, _ = refs[scene]
                rows += self._rows(
                    "mode",
                    scene,
                    m.columns(),
                    got,
                    ref_vals,
                    unc,
                )
                if k % 40 == 0 or k == len(futures):
                    self.log(f"dynamic accuracy: long runs {k}/{len(futures)}")
        return rows

    def _rows(self, study, scene, keys, got, ref_vals, unc):
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
        for metric, (where, _) in METRICS.items():
            if where != scene:
                continue
            out.append(
                {
                    **{c: None for c in COLUMNS},
                    **shared,
                    "metric": metric,
                    "value": values.get(metric, np.nan),
                    "noise": noise.get(metric, np.nan),
                    "reference": ref_vals.get(metric, np.nan),
                    "ref_uncertainty": unc.get(metric, np.nan),
                }
            )
        return out
