"""`python -m harness accuracy --model dynamic`: speed against accuracy of the dynamic model,
the measuring part (accuracy_dynamic_report.py renders it; docs/harness.md, "The dynamic
accuracy study").

Every mode, solver × substeps S × iterations I × precision × build (each cpu variant and,
with a usable GPU, each cuda build's variants that run `simulate`; all read from the
binaries; ftl once per s of `ftl_damping`; the no-simulation baseline, solver `rigid`, once
per precision where a variant declares it), runs the same dynamic scene (same seed, so the
same roots) for `seconds` of simulated time. Each run is compared frame by frame with a
converged reference:

  rms_err_L, max_err_L   RMS and max over all points of |x − x_ref|, over the hair length L
  err_p50/p95/p99_L, iou_front, iou_side   error percentiles, silhouette overlap
  stretch_max, penetration_max, blown_up_strands   the mode's own observables (§3.8)
  stretch_p99, kinetic, potential, verdict   (harness/check/observables_dynamic.py)

The reference is xpbd, fp64, I = 1, with S doubled from `ref_start` until, at every frame
up to the horizon, the RMS difference between S and 2S is under
tolerances.DYN_ACC_REF_FACTOR times the smallest RMS error any mode (not blown up) has at
that frame; modes are compared with the finer of the two. The max measure is shown against
the same rule in the report but does not decide S: it is set by single points near
contacts and nearly straight bend triples, which converge far more slowly
(docs/decisions.md, "The dynamic accuracy study"). It runs on the C reference, or on the GPU in fp64
where one is usable, once the GPU's rung S0 agrees with the CPU's within a share of that
margin (tolerances.DYN_ACC_GPU_REF_SHARE); otherwise the CPU ladder is used.

After the ladder, `ref_extra` more doublings measure the reference's own error
(Study.reference_error); perturbed twins of the converged rung give the scene's Lyapunov rate
and predictability time T_p, and pointwise errors are judged only up to min(horizon, T_p)
(Study.predictability, studies/accuracy_ensemble_dynamic.py); every mode's statistics over the whole run
go against the reference ensemble (ensemble.csv); and the long runs (studies/observables_long_dynamic.py,
observables.csv) measure what a user sees over `long_seconds`.

Time per frame is measured apart from the checked run: the same mode at `time_strands`
strands, `time_frames` frames, `--repeat`, no output file (never a run that also checks);
it is the simulate stage's median.

Writes results/dynamic-accuracy/dynamic_accuracy.csv (one row per mode and frame, plus the
reference ladder and the GPU check), analytic.json (harness/studies/analytic_table_dynamic.py's sweeps) and
env.json; then accuracy_dynamic_report.py writes report/dynamic_accuracy.md and its PNGs. On
another scene (`--scene curly`) the folder is results/dynamic-accuracy-curly/ and the page
report/dynamic_accuracy_curly.md.
"""

import itertools
import os
import shutil
import time
from concurrent.futures import ThreadPoolExecutor, as_completed
from dataclasses import asdict, dataclass, replace
from pathlib import Path

import numpy as np

from harness import HarnessError
from harness.check import observables_dynamic as observables
from harness.core import env, rounds, runner, scenes, timing, tolerances, variants
from harness.core.limits import limits
from harness.core.paths import CUDA_BUILDS, RESULTS, binary_path, display
from harness.core.progress import Progress
from harness.io import files, grooms
from harness.io.trajectory import open_trajectory
from harness.studies import accuracy_ensemble_dynamic as accuracy_ensemble
from harness.studies import observables_long_dynamic as observables_long
from harness.studies import predictability_dynamic as predictability
from harness.studies.accuracy import (
    ANALYTIC_MD,
    ANALYTIC_NAME,
    COLUMNS,
    CSV_NAME,
    NO_SIMULATION,
    REF_ITERATIONS,
    REF_PRECISION,
    REF_SOLVER,
    Mode,
    frame_errors,
    holds_until,
    results_name,
    smallest,
)

SIMULATE = "simulate"  # the stage a variant must run to take part
CHECKED_A_BATCH = 8  # GPU checked runs one process runs (runner.run_batch); the runs go on in parallel


@dataclass(frozen=True)
class Plan:
    """What a study measures; Plan() is the full study, Plan.quick() the small one."""

    scene: str = "dynamic"
    strands: int = 256
    points: int | None = None
    seconds: float = 1.0
    horizon: float = 0.5
    substeps: tuple = (1, 2, 4, 8, 16, 32)
    iterations: tuple = (1, 2, 4)
    time_strands: int = 10_000
    time_frames: int = 1
    repeat: int = 3
    ref_start: int | None = None  # None: 2 × the largest S of the grid
    ref_max: int = 16384
    jobs: int | None = None  # parallel checked runs (None: one per core)
    analytic: str = "full"  # full | quick | none
    gpu: str = "auto"  # auto | no
    ftl_damping: tuple = (0.0, 0.5, 0.9, 1.0)  # ftl's s, an axis of the study (docs/model.md §3.7)
    ref_extra: int = 2  # doublings past the converged rung that measure the reference's own error
    long_seconds: float = 10.0  # the long runs' simulated time (0: no long runs)
    long_strands: int = 8
    long_ref_max: int = 512  # the long runs' reference S at most (its change to 2S is reported)
    stop_rule: timing.StopRule = timing.RULE  # the timed runs' stopping rule (core/timing.py)

    @classmethod
    def quick(cls, **changes):
        """A few minutes on a 2-core machine, every section of the page still filled
        (docs/decisions/studies.md, "The dynamic accuracy study")."""
        base = dict(
            strands=16,
            seconds=0.25,
            horizon=0.25,
            substeps=(1, 4, 16),
            iterations=(1,),  # the grid still holds 1 × 4 and 1 × 16 for small steps against iterations
            time_strands=1000,
            analytic="quick",
            long_seconds=5.0,
            long_strands=6,
            long_ref_max=128,
        )
        return cls(**{**base, **changes})

    @property
    def first_rung(self):
        return self.ref_start or 2 * max(self.substeps)


def grid(substeps, iterations):
    """(S, I) pairs: every S with every I, plus S × 1 and 1 × S for each S (the small-steps
    comparison of Macklin et al. 2019 needs both)."""
    pairs = set(itertools.product(substeps, iterations))
    pairs |= {(n, 1) for n in substeps} | {(1, n) for n in substeps}
    return sorted(pairs)


def check_plan(plan, frame_dt):
    """Refuse a plan that cannot give a meaningful study (HarnessError, exit 2)."""
    bad = []
    if not 0 < plan.horizon <= plan.seconds:
        bad.append(f"--horizon {plan.horizon:g} must be > 0 and at most --seconds {plan.seconds:g}")
    if round(plan.horizon / frame_dt) < 1:
        bad.append(f"--horizon {plan.horizon:g} s is shorter than one frame ({frame_dt:g} s)")
    if not plan.substeps or not plan.iterations:
        bad.append("--substeps and --iterations need at least one value each")
    for flag, vals in (("--substeps", plan.substeps), ("--iterations", plan.iterations)):
        bad += sorted({f"{flag} values {why}" for v in vals if (why := limits().count_error(flag[2:], v))})
    if plan.substeps and plan.first_rung <= max(plan.substeps):
        bad.append(f"--ref-start {plan.first_rung} must exceed the largest --substeps ({max(plan.substeps)})")
    if plan.ref_max < 2 * plan.first_rung:
        bad.append(f"--ref-max {plan.ref_max} must be at least twice --ref-start ({plan.first_rung})")
    elif why := limits().substep_error(frame_dt / plan.ref_max):
        bad.append(f"--ref-max {plan.ref_max}: {why}")
    if plan.analytic not in ("full", "quick", "none"):
        bad.append(f"--analytic must be full, quick or none (got '{plan.analytic}')")
    if not plan.ftl_damping or any(not 0.0 <= s <= 1.0 for s in plan.ftl_damping):
        bad.append("--ftl-damping needs at least one value, each in [0, 1]")
    if plan.ref_extra < 0 or plan.ref_extra > 4:
        bad.append(f"--ref-extra must lie in 0 … 4 (got {plan.ref_extra})")
    if plan.long_seconds < 0 or (plan.long_seconds > 0 and plan.long_seconds < 4 * frame_dt):
        bad.append(f"--long-seconds must be 0 (none) or at least 4 frames (got {plan.long_seconds:g})")
    if plan.long_strands < 2:
        bad.append(
            f"--long-strands must be at least 2 (its noise is the two halves' difference; got {plan.long_strands})"
        )
    if bad:
        raise HarnessError("accuracy --model dynamic: " + "; ".join(bad))


def study_builds(gpu_ok, groom=False):
    """Every binary × variant here that runs simulate: the cpu variants, then (with a GPU)
    each cuda build present; for a groom, only the variants that declare its per-segment
    rest lengths (docs/model.md §3.15). Returns (runners, the left-out variants' labels)."""

    def runners(backend, build):
        d = variants.declared(backend, build)
        got = [variants.Runner(backend, build, v) for v in d.running(SIMULATE)]
        return [r for r in got if not groom or r.variant in d.per_segment], [
            r.label for r in got if groom and r.variant not in d.per_segment
        ]

    out, left = runners("cpu", "default")
    if gpu_ok:
        for build in CUDA_BUILDS:
            if binary_path("cuda", build).exists():
                got, lost = runners("cuda", build)
                out, left = out + got, left + lost
    return out, left


def study_modes(builds, plan):
    """Every variant's solvers (its own list in --list-variants) × precision × (S, I); ftl
    once for each s of the plan; the no-simulation baseline once per precision (S = I = 1:
    it solves nothing)."""
    pairs = grid(plan.substeps, plan.iterations)
    out = []
    for b in builds:
        d = variants.declared(b.backend, b.build)
        for solver, precision in itertools.product(d.solvers_of(b.variant or d.default_variant), d.precisions):
            if solver == NO_SIMULATION:
                out.append(Mode(b, precision, solver, 1, 1))
                continue
            for damping in plan.ftl_damping if solver == "ftl" else (None,):
                out += [Mode(b, precision, solver, s, i, ftl_damping=damping) for s, i in pairs]
    return out


def configured(scene, *, solver, substeps, iterations, precision, frames, strands, ftl_damping=None):
    """The dynamic scene with one mode's settings, every frame written."""
    dyn = {
        **scene.dynamic,
        "--solver": solver,
        "--substeps": int(substeps),
        "--iterations": int(iterations),
        "--frames": int(frames),
        "--output-every": 1,
    }
    if ftl_damping is not None:
        dyn["--ftl-damping"] = float(ftl_damping)
    return replace(scene.with_overrides(strands=strands, precision=precision), dynamic=dyn)


# ---- errors ---------------------------------------------------------------------------


def reference_ok(diff, smallest_error, factor):
    """Per frame: the reference's S-vs-2S difference under `factor` × the smallest mode
    error (False where either is NaN)."""
    with np.errstate(invalid="ignore"):
        return np.asarray(diff) < factor * np.asarray(smallest_error)


# ---- runs -----------------------------------------------------------------------------


@dataclass
class Run:
    """A checked run read back: times [F], positions and velocities [F][N][P][3] (velocities
    None where the file stores only the last), observables per frame."""

    times: np.ndarray
    pos: np.ndarray
    stretch: np.ndarray
    penetration: np.ndarray
    blown: np.ndarray
    vel: np.ndarray | None = None
    ell: object = None  # the stretch rest lengths in double: ℓ, or a groom's [N][P−1] (§3.15)


def read_run(path):
    with open_trajectory(path) as t:
        sim = t.simulated
        pos = np.stack([t.frame(f) for f in sim]).astype(np.float64)
        vel = [t.velocity_at_step(s) for s in t.step[sim]]
        obs = t.observables.set_index("step").reindex(t.step[sim])
        return Run(
            times=t.time[sim].copy(),
            pos=pos,
            stretch=obs["stretch_max"].to_numpy(np.float64),
            penetration=obs["penetration_max"].to_numpy(np.float64),
            blown=obs["blown_up_strands"].to_numpy(np.int64),
            vel=np.stack(vel).astype(np.float64) if all(v is not None for v in vel) else None,
            ell=t.segment_rest(),
        )


def _mode_rms(path, ref_pos, L):
    """A mode's RMS error [F] against ref_pos; NaN throughout if it blew up at any frame."""
    r = read_run(path)
    rms, _ = frame_errors(r.pos, ref_pos, L)
    return np.full_like(rms, np.nan) if (r.blown > 0).any() else rms


def _mode_metrics(path, ref, gravity, ctx):
    """A mode's run (its positions dropped), RMS and max error against `ref`, frame_metrics and
    its signature over the whole run (accuracy_ensemble.Context `ctx`)."""
    r = read_run(path)
    rms, mx = frame_errors(r.pos, ref.pos, ctx.L)
    sig = ctx.signature(r.pos, r.ell)
    return replace(r, pos=None, vel=None), rms, mx, frame_metrics(r, ref, ctx.L, gravity, ctx.dt), sig


def reader_pool(jobs):
    """Processes that read and compare the modes' state files (about 15 ms each, hundreds of
    them a rung). All start at once, forked before the study starts any thread; they ignore
    Ctrl-C, and the study ends them (Study.close) however it ends."""
    return runner.fork_pool(jobs)


def frame_metrics(run, ref, L, gravity, dt):
    """Per frame of `run`: the verdict, error percentiles and silhouette overlaps against
    `ref` (a Run, or None), stretch p99 against each segment's ℓ_k, kinetic energy per
    particle from the stored velocities and from the positions (frames dt apart), potential."""
    F = len(run.times)
    out = {k: [np.nan] * F for k in ("err_p50_L", "err_p95_L", "err_p99_L", "iou_front", "iou_side")}
    out["verdict"] = [observables.verdict(run.pos[f], L, None if run.vel is None else run.vel[f]) for f in range(F)]
    out["stretch_p99"] = [observables.stretch_stats(run.pos[f], L, run.ell)[1] for f in range(F)]
    with np.errstate(invalid="ignore", over="ignore"):
        out["kinetic_pos"] = list(observables.kinetic_from_positions(run.pos, dt))
    if run.vel is not None:
        k, p, _ = observables.energy(run.pos, run.vel, gravity)
        out["kinetic"], out["potential"] = list(k), list(p)
    for f in range(F):
        if ref is None or out["verdict"][f] == observables.DIVERGED:
            continue
        e = observables.error_percentiles(run.pos[f], ref.pos[f], L)
        out["err_p50_L"][f], out["err_p95_L"][f], out["err_p99_L"][f] = e["p50"], e["p95"], e["p99"]
        iou = observables.silhouette_iou(run.pos[f], ref.pos[f])
        out["iou_front"][f], out["iou_side"][f] = iou["front"], iou["side"]
    return out


class Study:
    def __init__(self, plan, out_dir, log):
        self.log = log
        base = scenes.load_scene(plan.scene)
        if base.model != "dynamic":
            raise HarnessError(
                f"accuracy --model dynamic: scene {plan.scene} is a {base.model}-model scene (its model key)"
            )
        most = grooms.hair_strand_count(base.groom_file) if base.groom_file else None
        if most is not None and plan.time_strands > most:  # a groom file holds no more (docs/model.md §3.15)
            log(f"dynamic accuracy: the groom holds {most} strands: each mode is timed at {most}, "
                f"not {plan.time_strands}")  # fmt: skip
            plan = replace(plan, time_strands=most)
        self.plan = plan
        self.scene = base.with_overrides(strands=plan.strands, points=plan.points)
        self.frame_dt = float(self.scene.dynamic.get("--frame-dt", 1 / 60))
        check_plan(plan, self.frame_dt)
        self.frames = max(1, round(plan.seconds / self.frame_dt))
        self.horizon_frames = min(self.frames, round(plan.horizon / self.frame_dt))
        self.L = self.scene.hair_length
        self.gravity = float(self.scene.dynamic.get("--gravity", 981.0))
        self.scratch = Path(out_dir) / "states"
        self.cpu_threads = env.usable_cores()
        self.jobs = plan.jobs or self.cpu_threads
        self.readers = None  # reader_pool(), from start_readers() to close()

    def start_readers(self):
        self.readers = reader_pool(self.jobs)

    def close(self):
        if self.readers is not None:
            self.readers.terminate()  # nothing is left to read: end them at once
            self.readers.join()
            self.readers = None

    def path(self, tag):
        return self.scratch / f"{tag}.h5"

    def checked(self, build, solver, substeps, iterations, precision, tag, threads=None, ftl_damping=None):
        flags, out = self.checked_flags(build, solver, substeps, iterations, precision, tag, threads, ftl_damping)
        return out, runner.run_binary(build.binary, flags)

    def checked_modes(self, modes):
        """The checked runs of modes of one build, in one process (runner.run_batch; the CPU's on
        one thread): (mode, its file, its record) of each."""
        runs = [self.checked_flags(m.runner, m.solver, m.substeps, m.iterations, m.precision, m.tag,
                                   1 if m.runner.backend == "cpu" else None, m.ftl_damping) for m in modes]  # fmt: skip
        done = []
        for i, rec, error in runner.run_batch(modes[0].runner.binary, [f for f, _ in runs]):
            if error is not None:
                raise error
            done.append((modes[i], runs[i][1], rec))
        return done

    def checked_flags(self, build, solver, substeps, iterations, precision, tag, threads=None, ftl_damping=None):
        """(the flags of a checked run, its file)."""
        sc = configured(
            self.scene,
            solver=solver,
            substeps=substeps,
            iterations=iterations,
            precision=precision,
            frames=self.frames,
            strands=self.plan.strands,
            ftl_damping=ftl_damping,
        )
        out = self.path(tag)
        flags = runner.run_flags(sc, build.backend, variant=build.variant, threads=threads, output=out, force=True)
        flags += ["--velocities", "all"]  # the energy of every frame
        return flags, out

    def timed_all(self, modes):
        """name → (median ms, min ms, record, timing.Figure) of each mode's timed run, by the
        stopping rule (core.rounds.measure, the plan's `timing`), one binary's runs in batches
        and nothing else running. ftl's damping s is one factor of the velocity update (no
        branch on it), so modes that differ only in s share a run (Mode.timing_key)."""
        first = {}
        for m in modes:
            first.setdefault(m.timing_key, m)
        cases = list(first.values())
        runs = {}
        with Progress(len(cases), "dynamic accuracy: timed") as bar:

            def ended(i, t):
                if t.error is not None:
                    raise t.error
                runs[cases[i].timing_key] = self.timed_result(cases[i], t)
                bar.update()

            rule = self.plan.stop_rule
            rule = replace(rule, min_samples=max(rule.min_samples, self.plan.repeat))  # --repeat: the first round
            rounds.measure(cases, self.timed_flags, lambda m: m.runner.binary, rule=rule, on_done=ended)
        return {m.name: runs[m.timing_key] for m in modes}

    def timed_flags(self, mode, repeat=None):
        sc = configured(
            self.scene,
            solver=mode.solver,
            substeps=mode.substeps,
            iterations=mode.iterations,
            precision=mode.precision,
            frames=self.plan.time_frames,
            strands=self.plan.time_strands,
            ftl_damping=mode.ftl_damping,
        )
        repeat = repeat or self.plan.repeat
        return runner.run_flags(sc, mode.runner.backend, variant=mode.runner.variant, repeat=repeat)

    def timed_result(self, mode, t):
        """(median ms, min ms, record, figure) of a mode's simulate stage (a rounds.Timed)."""
        rec = t.record
        sim = [i for i, s in enumerate(rec["stages"]) if s.get("stage") == SIMULATE]
        if not sim:
            raise HarnessError(f"{mode.runner.binary.name}: its record has no simulate stage")
        st = rec["stages"][sim[0]]
        fig = t.figures.get(sim[0]) or timing.Figure(st.get("times_ms") or [], backend=mode.runner.backend)
        return float(st["median_ms"]), float(st["min_ms"]), rec, fig

    # the reference ladder ------------------------------------------------------------

    def rung(self, build, S):
        tag = f"ref_{build.label.replace(' ', '_')}_S{S}"
        threads = self.cpu_threads if build.backend == "cpu" else None
        t0 = time.monotonic()
        path, _ = self.checked(build, REF_SOLVER, S, REF_ITERATIONS, REF_PRECISION, tag, threads=threads)
        self.log(f"dynamic accuracy: reference {build.label} S = {S}: {time.monotonic() - t0:.1f} s")
        return path

    def mode_rms(self, paths, ref):
        """{mode name: RMS error [F]} against ref positions; a mode blown up at any frame
        gives NaN throughout (it takes no part in the smallest error)."""
        names = list(paths)
        errs = self.readers.starmap(_mode_rms, [(paths[n], ref.pos, self.L) for n in names], chunksize=8)
        return dict(zip(names, errs))

    def ladder(self, build, mode_paths, first_path=None):
        """Double S until the criterion holds up to the horizon or --ref-max is reached
        (first_path: rung S0 already run on `build`).

        Every mode is compared with the first finer rung; after that only the modes that can
        still hold a frame's smallest error are compared again: the reference has moved by at
        most B = the sum of the rung differences since (RMS obeys the triangle inequality), so
        a mode can be the smallest at frame f only if its error then was within 2·B(f) of the
        smallest then (candidates)."""
        H = self.horizon_frames
        factor = tolerances.DYN_ACC_REF_FACTOR
        steps = []
        S = self.plan.first_rung
        prev_path = first_path or self.rung(build, S)
        then, moved = None, None
        rungs, top = 1, S  # the most rungs: S doubles until 4·S passes --ref-max
        while 4 * top <= self.plan.ref_max:
            top, rungs = 2 * top, rungs + 1
        with Progress(rungs, "dynamic accuracy: reference ladder (at most)") as bar:
            return self._climb(build, mode_paths, S, prev_path, then, moved, steps, factor, H, bar)

    def _climb(self, build, mode_paths, S, prev_path, then, moved, steps, factor, H, bar):
        while True:
            cur_path = self.rung(build, 2 * S)
            prev, cur = read_run(prev_path), read_run(cur_path)
            d_rms, d_max = frame_errors(prev.pos, cur.pos, self.L)
            extra = frame_metrics(prev, cur, self.L, self.gravity, self.frame_dt)
            steps.append(dict(S=S, S2=2 * S, rms=d_rms, max=d_max, run=replace(prev, pos=None, vel=None), extra=extra))
            if then is None:
                then, moved = self.mode_rms(mode_paths, cur), np.zeros_like(d_rms)
                errs = then
            else:
                moved = moved + d_rms
                low = smallest(then) + 2 * moved
                cand = {k: mode_paths[k] for k, e in then.items() if np.any(e <= low)}
                errs = self.mode_rms(cand, cur)
            min_rms = smallest(errs)
            ok = reference_ok(d_rms, min_rms, factor)
            converged = bool(ok[:H].all())
            self.log(
                f"dynamic accuracy: reference S = {S} vs {2 * S}: criterion "
                f"{'holds' if converged else 'fails'} up to the horizon; "
                f"holds until t = {holds_until(ok, cur.times):.3f} s ({len(errs)} modes compared)"
            )
            os.unlink(prev_path)
            bar.update()
            if converged or 4 * S > self.plan.ref_max:
                return dict(
                    build=build,
                    steps=steps,
                    final_path=cur_path,
                    final=cur,
                    min_rms=min_rms,
                    ok=ok,
                    converged=converged,
                )
            prev_path, S = cur_path, 2 * S

    def reference_error(self, ref):
        """The reference's own error, measured: its final rung against plan.ref_extra more
        doublings: per frame the RMS and max difference from the finest rung; reference_tail adds
        the Richardson-style estimate once the pointwise horizon is known."""
        if self.plan.ref_extra < 1:
            return None
        S = ref["steps"][-1]["S2"]
        prev, prev_S, diffs, finer = ref["final"], S, [], []
        for _ in range(self.plan.ref_extra):
            path = self.rung(ref["build"], 2 * prev_S)
            cur = read_run(path)
            os.unlink(path)
            diffs.append((prev_S, 2 * prev_S, *frame_errors(prev.pos, cur.pos, self.L)))
            finer.append(cur)
            prev, prev_S = cur, 2 * prev_S
        rms, mx = frame_errors(ref["final"].pos, prev.pos, self.L)
        self.log(
            f"dynamic accuracy: the reference S = {S} against S = {prev_S}: RMS {np.nanmax(rms):.2e}·L, max "
            f"{np.nanmax(mx):.2e}·L over the run"
        )
        return dict(S=S, finest=prev_S, rms=rms, max=mx, diffs=diffs, finer=finer[:1])  # finer: an ensemble member

    def reference_tail(self, err):
        """With two or more extra doublings, the tail they predict over the (pointwise) horizon: each
        doubling shrinks the change by q, the worst of the last change over the one before (no
        estimate if q ≥ 1); adds est_rms, est_max and ratio to `err`."""
        H, diffs = self.horizon_frames, err["diffs"]
        q = float("nan")
        tail_rms = tail_max = np.full_like(err["rms"], np.nan)
        if len(diffs) >= 2:
            with np.errstate(invalid="ignore", divide="ignore"):
                q = float(np.nanmax(diffs[-1][2][:H]) / np.nanmax(diffs[-2][2][:H]))
            if q < 1:
                tail_rms, tail_max = diffs[-1][2] * q / (1 - q), diffs[-1][3] * q / (1 - q)
        err.update(est_rms=err["rms"] + tail_rms, est_max=err["max"] + tail_max, ratio=q)
        self.log(f"dynamic accuracy: change ratio per doubling {q:.3g} over the horizon")

    def predictability(self, ref, ref_err):
        """The reference ensemble (accuracy_ensemble.build): λ and T_p from the final rung's twins;
        from here on pointwise errors are judged up to min(horizon, T_p) (horizon_frames), and
        whether the ladder converged is read again over that horizon."""
        threads = self.cpu_threads if ref["build"].backend == "cpu" else None
        finer = ref_err["finer"] if ref_err else []
        ens = accuracy_ensemble.build(self, ref, finer, accuracy_ensemble.context(self), threads)
        r = ens.twins.rate
        self.log(
            f"dynamic accuracy: Lyapunov rate {r.lam:.3g} /s ({'fitted from' if r.grew else 'no growth past'} "
            f"{tolerances.DYN_LYAPUNOV_FLOOR:g}× the perturbation), predictability time {r.predictability:.3g} s; "
            f"pointwise errors judged over {ens.pointwise_frames} of {self.horizon_frames} frames"
        )
        self.horizon_frames = ens.pointwise_frames
        ref["converged"] = bool(ref["ok"][: self.horizon_frames].all())
        if ref_err:
            self.reference_tail(ref_err)
        return ens


def _gpu_reference_build(gpu_ok, scene):
    """The default cuda build's fastest variant that runs `scene` with the reference's
    solver (variants.fastest); None without a GPU or such a variant (the CPU ladder runs)."""
    if not gpu_ok or not binary_path("cuda").exists():
        return None
    d = variants.declared("cuda")
    v = variants.fastest(d, scene.points, variants.features_of(scene.dynamic), REF_SOLVER, bool(scene.groom))
    return variants.Runner("cuda", "default", v) if v else None


def _row(**kw):
    return {k: kw.get(k) for k in COLUMNS}


def _frame_rows(run, rms, mx, extra, **shared):
    """One row per simulated frame of `run`, with its errors against a reference (rms, mx,
    per frame), frame_metrics' columns (extra) and the columns every frame shares."""
    return [
        _row(
            **shared,
            **{k: v[f] for k, v in extra.items()},
            frame=f + 1,
            time_s=run.times[f],
            rms_err_L=rms[f],
            max_err_L=mx[f],
            stretch_max=run.stretch[f],
            penetration_max=run.penetration[f],
            blown_up_strands=run.blown[f],
        )
        for f in range(len(run.times))
    ]


def run_study(plan, out_dir=None, force=False, command=None, log=print):
    """Measure, write the CSV, analytic.json and env.json (render/accuracy_dynamic_report.py
    draws them); return the exit status (0: reference converged over the horizon, 1: it
    did not)."""
    started = time.monotonic()
    out_dir = Path(out_dir or RESULTS / results_name(plan.scene))
    csv_path = out_dir / CSV_NAME
    if csv_path.exists() and not force:
        raise HarnessError(f"{display(csv_path)} exists: pass --force to replace it")
    study = Study(plan, out_dir, log)
    if study.scratch.exists():
        log(f"dynamic accuracy: removing the scratch states of an earlier run ({display(study.scratch)})")
        shutil.rmtree(study.scratch)
    study.scratch.mkdir(parents=True)
    gpu_ok, gpu_why = env.gpu_status()
    if gpu_ok and plan.gpu == "no":
        gpu_ok, gpu_why = False, "--gpu no"
    builds, left_out = study_builds(gpu_ok, groom=bool(study.scene.groom))
    cpu_oracle = variants.Runner("cpu", "default", variants.declared("cpu").default_variant)
    if REF_SOLVER not in variants.declared("cpu").solvers:
        raise HarnessError(f"{display(cpu_oracle.binary)} declares no {REF_SOLVER} solver (--list-variants)")
    modes = study_modes(builds, plan)
    log(
        f"dynamic accuracy: {len(modes)} modes ({', '.join(b.label for b in builds)}), "
        f"{plan.strands} strands, {study.frames} frames of {study.frame_dt:.4g} s, horizon "
        f"{study.horizon_frames} frames"
        + ("" if gpu_ok else f"; no GPU modes: {gpu_why}")
        + (f"; left out (no per-segment rest lengths, docs/model.md §3.15): {', '.join(left_out)}" if left_out else "")
    )

    # 1. the checked runs (in parallel: nothing here is timed) and the analytic tables
    analytic = None
    mode_paths, records = {}, {}
    jobs = study.jobs
    try:
        study.start_readers()  # before any thread of the study
        with ThreadPoolExecutor(max_workers=jobs) as pool:
            futures = {}
            if plan.analytic != "none":
                from harness.studies import analytic_table_dynamic as analytic_table

                futures[pool.submit(analytic_table.measure, str(cpu_oracle.binary), plan.analytic == "quick")] = None
            units = [[m] for m in modes if m.runner.backend == "cpu"]  # a process each, the pool's jobs in parallel
            on_gpu = [m for m in modes if m.runner.backend != "cpu"]
            units += runner.batches(on_gpu, lambda m: m.runner.binary, CHECKED_A_BATCH)
            for chunk in units:
                futures[pool.submit(study.checked_modes, chunk)] = chunk
            with Progress(len(modes) + (plan.analytic != "none"), "dynamic accuracy: checked runs") as bar:
                for f in as_completed(futures):
                    ms = futures[f]
                    if ms is None:
                        analytic = f.result()
                        bar.update()
                        bar.write("dynamic accuracy: analytic tables done")
                        continue
                    for m, path, rec in f.result():
                        mode_paths[m.name], records[m.name] = path, rec
                    bar.update(len(ms))

        # 2. the reference (GPU fp64 where usable and validated against the CPU)
        gpu_ref = _gpu_reference_build(gpu_ok, study.scene)
        check_rows, gpu_note = (
            [],
            f"not used: {gpu_why if not gpu_ok else 'no default cuda build, or none of its variants runs the scene'}",
        )
        if gpu_ref is not None:
            S0 = plan.first_rung
            cpu_path = study.rung(cpu_oracle, S0)
            cpu_run = read_run(cpu_path)
            gpu_path = study.rung(gpu_ref, S0)
            gpu_run = read_run(gpu_path)
            g_rms, g_max = frame_errors(gpu_run.pos, cpu_run.pos, study.L)
            ref = study.ladder(gpu_ref, mode_paths, first_path=gpu_path)
            share = tolerances.DYN_ACC_GPU_REF_SHARE * tolerances.DYN_ACC_REF_FACTOR
            H = study.horizon_frames
            valid = bool(reference_ok(g_rms[:H], ref["min_rms"][:H], share).all()) and not (gpu_run.blown > 0).any()
            check_rows += _frame_rows(
                gpu_run,
                g_rms,
                g_max,
                frame_metrics(gpu_run, cpu_run, study.L, study.gravity, study.frame_dt),
                study="gpu_check",
                mode=f"{gpu_ref.label} vs {cpu_oracle.label} S{S0}",
                **_ref_columns(study, gpu_ref, S0),
                ref_substeps=S0,
            )
            if valid:
                gpu_note = "validated"
            else:
                gpu_note = "rejected: it differs from the CPU's by more than allowed; the CPU ladder is used"
                log(f"dynamic accuracy: the GPU fp64 reference is {gpu_note}")
                ref = study.ladder(cpu_oracle, mode_paths, first_path=cpu_path)
        else:
            ref = study.ladder(cpu_oracle, mode_paths)
        ref_err = study.reference_error(ref)
        ens = study.predictability(ref, ref_err)

        # the long runs: what a user sees over seconds (studies/observables_long_dynamic.py)
        long_rows = []
        if plan.long_seconds > 0:
            oracle_modes = [m for m in modes if m.runner == builds[0]]
            long = observables_long.LongRuns(study, ref["build"], ref["steps"][-1]["S2"], log, configured, read_run)
            long_rows = long.measure(oracle_modes, jobs)

        # 3. timing, one run at a time, nothing else running
        timed = study.timed_all(modes)

        mode_rows, ens_rows = _rows(study, modes, mode_paths, ref, timed, ens)
        rows = mode_rows + _ladder_rows(study, ref) + check_rows
        rows += _ref_error_rows(study, ref, ref_err)
    finally:
        study.close()
        shutil.rmtree(study.scratch, ignore_errors=True)

    out_dir.mkdir(parents=True, exist_ok=True)
    files.write_csv(csv_path, COLUMNS, rows)
    files.write_csv(out_dir / accuracy_ensemble.CSV_NAME, accuracy_ensemble.COLUMNS, ens_rows)
    long_path = out_dir / observables_long.CSV_NAME
    if long_rows:
        files.write_csv(long_path, observables_long.COLUMNS, long_rows)
    elif long_path.exists():
        long_path.unlink()  # stale long runs must not be rendered with these rows
    if (out_dir / ANALYTIC_MD).exists():
        (out_dir / ANALYTIC_MD).unlink()  # tables from before #47 must not be rendered with these rows
    if analytic:
        files.write_json(out_dir / ANALYTIC_NAME, analytic)
    elif (out_dir / ANALYTIC_NAME).exists():
        (out_dir / ANALYTIC_NAME).unlink()  # a stale sweep must not be rendered with these rows
    meta = _env(study, plan, builds, (gpu_ok, gpu_why, gpu_note), ref, ref_err, ens, started, command)
    final_S = ref["steps"][-1]["S2"]
    files.write_json(out_dir / "env.json", meta)
    log(f"wrote {display(csv_path)}")
    if not ref["converged"]:
        log(
            f"dynamic accuracy: the reference did NOT converge over the horizon by S = {final_S} "
            f"(--ref-max {plan.ref_max}); the report says so"
        )
        return 1
    return 0


def _env(study, plan, builds, gpu, ref, ref_err, ens, started, command):
    """env.json's record: the machine, the plan and what the study decided (gpu: (usable, why, note))."""
    gpu_ok, gpu_why, gpu_note = gpu
    final_S = ref["steps"][-1]["S2"]
    return dict(
        env.collect(),
        study=dict(
            asdict(plan),
            scene_file=study.scene.file,
            scene_description=study.scene.description,
            frame_dt=study.frame_dt,
            frames=study.frames,
            horizon_frames=study.horizon_frames,
            horizon=study.horizon_frames * study.frame_dt,  # judged pointwise: min(asked, T_p)
            asked_horizon=plan.horizon,
            predictability=predictability.rate_columns(ens.twins.rate),
            ensemble=ens.labels,
            points=study.scene.points,
            hair_length=study.L,
            builds=[b.label for b in builds],
            gpu=gpu_why if not gpu_ok else "usable",
            reference=dict(
                backend=ref["build"].backend,
                build=ref["build"].build,
                variant=ref["build"].variant,
                label=ref["build"].label,
                solver=REF_SOLVER,
                precision=REF_PRECISION,
                iterations=REF_ITERATIONS,
                substeps=final_S,
                converged=ref["converged"],
                converged_until_s=holds_until(ref["ok"], ref["final"].times),
                factor=tolerances.DYN_ACC_REF_FACTOR,
                gpu_check=gpu_note,
                gpu_share=tolerances.DYN_ACC_GPU_REF_SHARE,
                error=None
                if ref_err is None
                else dict(
                    against_substeps=ref_err["finest"],
                    rms_horizon=float(np.nanmax(ref_err["rms"][: study.horizon_frames])),
                    max_horizon=float(np.nanmax(ref_err["max"][: study.horizon_frames])),
                    est_rms_horizon=float(np.nanmax(ref_err["est_rms"][: study.horizon_frames])),
                    est_max_horizon=float(np.nanmax(ref_err["est_max"][: study.horizon_frames])),
                    ratio_per_doubling=ref_err["ratio"],
                ),
            ),
            wall_s=round(time.monotonic() - started, 1),
            command=command,
        ),
    )


def _rows(study, modes, mode_paths, ref, timed, ens):
    """(the modes' rows, one per frame; ensemble.csv's rows: the members', then every mode's)."""
    rows, ens_rows = [], accuracy_ensemble.member_rows(ens)
    final_S = ref["steps"][-1]["S2"]
    ctx = accuracy_ensemble.context(study)
    measured = study.readers.starmap(
        _mode_metrics, [(mode_paths[m.name], ref["final"], study.gravity, ctx) for m in modes], chunksize=8
    )
    for m, (r, rms, mx, extra, sig) in zip(modes, measured):
        ens_rows += accuracy_ensemble.mode_rows(m.name, sig, ens)
        ms, ms_min, rec, fig = timed[m.name]
        rows += _frame_rows(
            r,
            rms,
            mx,
            extra,
            **m.columns(),
            study="mode",
            strands=study.plan.strands,
            points=study.scene.points,
            time_per_frame_ms=ms,
            time_per_frame_min_ms=ms_min,
            **fig.columns("time_"),
            time_strands=study.plan.time_strands,
            threads=rec.get("threads") if m.runner.backend == "cpu" else None,
            block_size=rec.get("block_size") if m.runner.backend == "cuda" else None,
            device=rec.get("device"),
            ref_substeps=final_S,
        )
    return rows, ens_rows


def _ladder_rows(study, ref):
    rows = []
    b = ref["build"]
    for st in ref["steps"]:
        run = st["run"]
        for f in range(len(st["rms"])):
            rows.append(
                _ref_row(
                    study,
                    b,
                    "reference",
                    f"{b.label} {REF_SOLVER} S{st['S']} I{REF_ITERATIONS} {REF_PRECISION}",
                    st["S"],
                    f,
                    run.times[f],
                    st["rms"][f],
                    st["max"][f],
                    stretch_max=run.stretch[f],
                    penetration_max=run.penetration[f],
                    blown_up_strands=run.blown[f],
                    ref_substeps=st["S2"],
                    **{k: v[f] for k, v in st["extra"].items()},
                )
            )
    return rows


def _ref_columns(study, b, substeps):
    """The columns a run of the reference solver (REF_SOLVER, REF_ITERATIONS, REF_PRECISION) on
    build b at `substeps` shares with every row it gives."""
    return dict(
        backend=b.backend,
        build=b.build,
        variant=b.variant,
        solver=REF_SOLVER,
        substeps=substeps,
        iterations=REF_ITERATIONS,
        precision=REF_PRECISION,
        strands=study.plan.strands,
        points=study.scene.points,
    )


def _ref_row(study, b, name, mode, substeps, f, time_s, rms, mx, **extra):
    """One frame's row of the reference solver on build b."""
    return _row(
        **_ref_columns(study, b, substeps),
        study=name,
        mode=mode,
        frame=f + 1,
        time_s=time_s,
        rms_err_L=rms,
        max_err_L=mx,
        **extra,
    )


def _ref_error_rows(study, ref, err):
    """The reference's own error per frame: its final rung against the finest extra doubling
    (study ref_error) and with the estimated tail (ref_error_est)."""
    if err is None:
        return []
    b = ref["build"]
    run = ref["final"]
    rows = []
    for name, rms, mx in (("ref_error", err["rms"], err["max"]), ("ref_error_est", err["est_rms"], err["est_max"])):
        for f in range(len(rms)):
            mode = f"{b.label} {REF_SOLVER} S{err['S']} against S{err['finest']}"
            if name == "ref_error_est":
                mode += " + tail"
            rows.append(
                _ref_row(study, b, name, mode, err["S"], f, run.times[f], rms[f], mx[f], ref_substeps=err["finest"])
            )
    return rows
