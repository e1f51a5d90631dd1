"""`python -m harness reduced`: what modelling less costs and saves (docs/model.md §3.14) — the
measuring part; harness/render/reduced_dynamic_report.py renders it.

Rows of one dynamic scene (default `dynamic`), each run for `seconds` of simulated time, written
every `write_every` s:

  guides   at each strand count of the plan: solver × guide fraction × scheme (one, blend3), at
           the scene's S and I: followers placed from the guides. Beside the fraction: the guide
           count and the guide spacing (the mean distance from a follower's root to its nearest
           guide's root, cm): the error follows the spacing, not the fraction
  lra      at the largest strand count: solver × iterations × LRA off/on, at the scene's S, with
           the head nodding at `lra_frequency` Hz (fast enough to over-stretch at few iterations);
           lra_excess is how far past its bound s_L·k·ℓ a point ends up in the output (LRA runs
           before the collider in xpbd and on predicted positions in ftl, docs/model.md §3.14),
           lra_moved_cm how far LRA moved the output from the same row without it
  sagfree  solver × shape range (`sag_ranges`) × sag-free off/on: the scene held still (no head
           motion, no wind) for `sag_seconds`; rest_rms_L and rest_max_L, the largest RMS and max
           displacement from the rest shape over L, say how far the groom sags
  sagfreq  solver × sag-free off/on, shape range 1: the same still scene hit at t = 0 by a steady
           wind of `sag_wind` cm/s (no gusts), a step load that sets every strand swinging; tip_hz
           and tip_damping are the median over the strands that swing of the tip's frequency and
           damping ratio (harness/check/observables_dynamic.py swing): sag-free must leave them as they were
  lod      at the largest strand count: solver × simulated points P_s (`lod_points`) written with
           `lod_render_points` points (--render-points; P_s = P_r simulates every point); the
           reference simulates P_r points

Each row's checked run (fp32, the CPU oracle on every core) is compared with a converged
reference of the same scene (studies/reduced_reference_dynamic.py: xpbd fp64 I = 1, S doubled until it
is ten times closer than the smallest row error, on the GPU in fp64 where one is usable): rms_err_L
and max_err_L are the worst written frame up to the pointwise horizon (the frames within the scene's
predictability time over which the reference holds the rule; none judged where it fails at the
first: the columns are then empty); tip_L, curvature_rel and envelope_rel the statistics of the whole run
against the reference ensemble (harness/check/ensemble_dynamic.py); stretch_max the binary's observable,
stretch_max_k and stretch_p99_k recomputed against each segment's own rest length over every
strand (a LOD row: over its rendered points and rendered rest shape), stretch_followers over the
followers alone.

Time per frame: the same settings at `time_strands` strands (no file, --repeat; each distinct
binary and flags once, so a guide row at 1,000 and at 10,000 strands shares its timing), on the cpu oracle
and, with a usable GPU, on each cuda variant that runs all the features (its `--list-variants`
entry lists them; `lanes` lacks guides and LRA, docs/cuda.md). Writes the CSV (one row per case and
timing binary) and, beside it, references.csv (each reference's ladder, rate and horizon), once every
row is measured; until then the rows so far are kept beside it, and a stopped run resumed keeps their
timings (studies/reduced_partial_dynamic.py).
"""

import math
import tempfile
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from harness import HarnessError
from harness.check import ensemble_dynamic as en
from harness.check import observables_dynamic as ob
from harness.core import env, runner, scenes, variants
from harness.core.guides import guide_count, guide_strands
from harness.core.paths import binary_path, display
from harness.io.files import write_csv
from harness.studies.accuracy import frame_errors
from harness.studies.reduced_partial_dynamic import Partial
from harness.studies.reduced_reference_dynamic import References, read_positions

FIELDS = (
    "study",
    "solver",
    "substeps",
    "iterations",
    "guides",
    "guide_count",
    "guide_spacing_cm",
    "follow",
    "lra",
    "sag_free",
    "shape_range",
    "points",
    "render_points",
    "precision",
    "strands",
    "seconds",
    "horizon_s",
    "rms_err_L",
    "max_err_L",
    "tip_L",
    "curvature_rel",
    "envelope_rel",
    "stretch_max",
    "stretch_max_k",
    "stretch_p99_k",
    "stretch_followers",
    "lra_excess",
    "lra_moved_cm",
    "rest_rms_L",
    "rest_max_L",
    "tip_hz",
    "tip_damping",
    "blown_up",
    "ref_substeps",
    "backend",
    "variant",
    "time_strands",
    "median_ms",
    "render_ms",
    "device",
)
TIMING_FIELDS = ("backend", "variant", "time_strands", "median_ms", "render_ms", "device")  # a timing's columns
REF_FIELDS = (
    "scene",
    "strands",
    "build",
    "substeps",
    "converged",
    "worst_ratio",
    "ladder",
    "lyapunov_per_s",
    "lyapunov_lower_bound",
    "predictability_s",
    "converged_s",
    "horizon_s",
    "tip_L_spread",
    "curvature_rel_spread",
    "envelope_rel_spread",
)
SCHEMES = ("one", "blend3")
PARTS = ("guides", "lra", "sagfree", "sagfreq", "lod")
SOLVERS = ("xpbd", "ftl")
STUDIED = ("guides", "lra", "sagfree", "lod")  # the §3.14 features the rows declare


@dataclass(frozen=True)
class Plan:
    scene: str = "dynamic"
    strands: tuple = (1_000, 10_000)
    seconds: float = 1.0
    write_every: float = 0.05  # s between written frames
    fractions: tuple = (1.0, 0.5, 0.25, 0.1, 0.05, 0.01)
    ref_start: int = 64
    ref_max: int = 8192
    lra_frequency: float = 6.0
    lra_iterations: tuple = (1, 2)
    sag_seconds: float = 2.0
    sag_wind: float = 600.0
    sag_ranges: tuple = (0.5, 1.0)
    lod_render_points: int = 33
    lod_points: tuple = (33, 17, 9, 5)
    time_strands: int = 10_000
    time_gpu_strands: int = 1_000_000
    repeat: int = 3
    gpu: str = "auto"  # auto | no
    threads: int | None = None  # the CPU's checked runs and references (None: every core)
    parts: tuple = PARTS  # which rows to measure
    solvers: tuple = SOLVERS  # whose rows (a share of the study: no timing is shared across solvers)

    @classmethod
    def quick(cls, **changes):
        base = dict(
            strands=(200, 1000),
            fractions=(1.0, 0.5, 0.1, 0.05),
            ref_max=512,
            time_strands=1000,
            sag_seconds=1.0,
            lod_points=(33, 9),
            # the GPU timed at 100,000 strands, not 1,000,000: on an H200 node the full size took
            # the quick study past a 10-minute job (its GPU rows at 20–40 ms a frame, 3 repeats each)
            time_gpu_strands=100_000,
        )
        return cls(**{**base, **changes})


@dataclass(frozen=True)
class Case:
    study: str
    solver: str
    substeps: int
    iterations: int
    strands: int
    guides: float = 1.0
    follow: str = ""
    lra: int = 0
    sag_free: int = 0
    shape_range: float | None = None
    points: int | None = None  # simulated points a strand (None: the scene's)
    extra: tuple = ()

    @property
    def key(self):
        """The case in one word (the partial file's `case` column)."""
        shape = "-" if self.shape_range is None else repr(self.shape_range)
        return (f"{self.study}/{self.solver}/S{self.substeps}/I{self.iterations}/N{self.strands}/g{self.guides!r}/"
                f"{self.follow or '-'}/lra{self.lra}/sag{self.sag_free}/r{shape}/P{self.points or '-'}")  # fmt: skip

    @property
    def ref_key(self):
        """The reference the case is compared with: (scene variant, strands), or None."""
        if self.study.startswith("sag"):
            return None
        return ("nod" if self.study == "lra" else "lod" if self.study == "lod" else "scene", self.strands)


def cases(plan, scene):
    """Every row's Case."""
    s, it = int(scene.dynamic["--substeps"]), int(scene.dynamic["--iterations"])
    big, small = max(plan.strands), min(plan.strands)
    out = []
    for n in plan.strands:
        for solver in plan.solvers:
            for frac in plan.fractions:
                for follow in SCHEMES if frac < 1.0 else ("",):
                    extra = ("--guides", repr(frac), "--follow", follow) if frac < 1.0 else ()
                    out.append(Case("guides", solver, s, it, n, frac, follow, extra=extra))
    for solver in plan.solvers:
        for i in plan.lra_iterations:
            for lra in (0, 1):
                out.append(Case("lra", solver, s, i, big, lra=lra, extra=_fast(plan) + (("--lra",) if lra else ())))
    for solver in plan.solvers:
        for rng in plan.sag_ranges:
            for sag in (0, 1):
                out.append(Case("sagfree", solver, s, it, small, sag_free=sag, shape_range=rng,
                                extra=_still(rng) + (("--sag-free",) if sag else ())))  # fmt: skip
        for sag in (0, 1):
            wind = _still(1.0) + ("--wind-speed", repr(plan.sag_wind), "--gust-amplitude", "0")
            out.append(Case("sagfreq", solver, s, it, small, sag_free=sag, shape_range=1.0,
                            extra=wind + (("--sag-free",) if sag else ())))  # fmt: skip
    pr = plan.lod_render_points
    for solver in plan.solvers:
        for ps in plan.lod_points:
            out.append(
                Case("lod", solver, s, it, big, points=ps, extra=("--render-points", str(pr)) if ps < pr else ())
            )
    return [c for c in out if c.study in plan.parts]


def _fast(plan):
    return ("--head-motion", "nod", "--motion-frequency", repr(plan.lra_frequency))


def _still(shape_range):
    return ("--head-motion", "still", "--wind-speed", "0", "--shape-range", repr(shape_range))


def _flags(scene, *, solver, substeps, iterations, precision, strands, frames, extra, output=None, variant=None,
           points=None, every=1):  # fmt: skip
    dyn = {**scene.dynamic, "--solver": solver, "--substeps": substeps, "--iterations": iterations}
    dyn.update({"--frames": frames, "--output-every": every})
    sc = replace(scene.with_overrides(strands=strands, precision=precision, points=points), dynamic=dyn)
    backend = "cuda" if variant and variant[0] == "cuda" else "cpu"
    flags = runner.run_flags(sc, backend, variant=variant[1] if variant else None, output=output, force=True)
    return flags + list(extra)


def timing_binaries(plan):
    """(backend, variant) pairs that time the rows: the cpu oracle, and the cuda variants
    that run simulate where a GPU is usable (each times the rows whose features it runs)."""
    out = [("cpu", "ref")]
    if _gpu(plan):
        d = variants.declared("cuda")
        out += [("cuda", v) for v in d.running("simulate") if any(d.runs_features(v, [f]) for f in STUDIED)]
    return out


def _gpu(plan):
    ok, _ = env.gpu_status()
    return plan.gpu != "no" and ok and binary_path("cuda", "default").exists()


def row_features(extra):
    """The §3.14 features a row's flags declare."""
    return variants.features_of(extra)


def guide_spacing(rest_roots, n, g):
    """The mean distance (cm) from a follower's root to its nearest guide's root; 0 without followers."""
    guides = guide_strands(n, g)
    fol = np.setdiff1d(np.arange(n), guides)
    if fol.size == 0:
        return 0.0
    r = rest_roots.astype(np.float64)
    near = [np.min(np.linalg.norm(r[guides][None] - r[fol[i : i + 2048]][:, None], axis=-1), axis=1)
            for i in range(0, fol.size, 2048)]  # fmt: skip
    return float(np.mean(np.concatenate(near)))


def lra_excess(pos, L, scale=1.0):
    """The largest |x_k − x_0| / (s_L·k·ℓ) − 1 over written frames, strands and points k ≥ 1 (≤ 0:
    every point within its bound)."""
    k = np.arange(1, pos.shape[2], dtype=np.float64)
    d = np.linalg.norm(pos[:, :, 1:] - pos[:, :, :1], axis=-1)
    return float(np.max(d / (scale * (L / (pos.shape[2] - 1)) * k) - 1.0))


class Study:
    def __init__(self, plan, work, progress):
        self.plan, self.work, self.log = plan, Path(work), progress
        self.scene = scenes.load_scene(plan.scene)
        if self.scene.model != "dynamic":
            raise HarnessError(f"reduced: scene {plan.scene} is not a dynamic scene")
        self.dt = float(self.scene.dynamic["--frame-dt"])
        self.frames = max(1, round(plan.seconds / self.dt))
        self.every = max(1, round(plan.write_every / self.dt))
        self.L = float(self.scene.hair_length)
        self.box = en.envelope_box(float(self.scene.head_radius), self.L)
        self.cpu = binary_path("cpu", "default")
        self.refs = References(plan, self.work, self.reference_build, self.dt, self.L, self.box, progress)
        self.files = {}  # Case -> its checked run's file

    def reference_build(self, points):
        """Where a GPU is usable, the strict CUDA build's fastest variant that runs the reference's
        xpbd at `points` (the C reference's arithmetic bit for bit but for the gusts' sine, docs/model.md
        §1.3), else the default build's; without a GPU the C reference."""
        if _gpu(self.plan):
            for build in ("strict", "default"):
                if not binary_path("cuda", build).exists():
                    continue
                v = variants.fastest(variants.declared("cuda", build), points, variants.features_of(self.scene.dynamic),
                                     "xpbd", bool(self.scene.groom))  # fmt: skip
                if v:
                    return variants.Runner("cuda", build, v)
        return variants.Runner("cpu", "default", variants.declared("cpu").default_variant)

    def frames_of(self, case):
        return max(1, round(self.plan.sag_seconds / self.dt)) if case.study.startswith("sag") else self.frames

    def checked(self, case):
        """The case's checked run (fp32, the oracle on every core), its file kept."""
        path = self.work / f"row{len(self.files)}.h5"
        every = 1 if case.study == "sagfreq" else self.every  # the swing's spectrum needs every frame
        flags = _flags(self.scene, solver=case.solver, substeps=case.substeps, iterations=case.iterations,
                       precision="fp32", strands=case.strands, frames=self.frames_of(case), extra=case.extra,
                       output=path, points=case.points, every=every)  # fmt: skip
        runner.run_binary(self.cpu, flags + ["--threads", str(self.plan.threads or env.usable_cores())], timeout=3600)
        self.files[case] = path
        return path

    def reference(self, case, row_cases):
        """The Reference a case is compared with (the rows that share it rank it), or None."""
        key = case.ref_key
        if key is None:
            return None
        variant, n = key
        extra = _fast(self.plan) if variant == "nod" else ()
        points = self.plan.lod_render_points if variant == "lod" else None

        def flags_for(S, out):
            return _flags(self.scene, solver="xpbd", substeps=S, iterations=1, precision="fp64", strands=n,
                          frames=self.frames, extra=extra, output=out, points=points, every=self.every)  # fmt: skip

        rows = [self.files[c] for c in row_cases if c.ref_key == key and c in self.files]
        return self.refs.get(key, flags_for, rows, self.dt * self.every, points or self.scene.points)

    def metrics(self, case, ref):
        """The row's measured columns (no timing)."""
        pos, _, rest, stretch, blown = read_positions(self.files[case])
        ell = ob.rest_lengths(rest)
        smax, sp99 = ob.stretch_stats(pos, self.L, ell)
        out = dict(stretch_max=stretch, stretch_max_k=smax, stretch_p99_k=sp99, blown_up=blown)
        sag_rms, sag_max = frame_errors(pos, np.broadcast_to(rest, pos.shape), self.L)
        out.update(rest_rms_L=float(np.nanmax(sag_rms)), rest_max_L=float(np.nanmax(sag_max)))
        if case.study == "sagfreq":
            out["tip_hz"], out["tip_damping"] = ob.swing(pos, self.dt)[:2]
        if case.guides < 1.0:
            g = guide_count(case.strands, case.guides)
            fol = np.setdiff1d(np.arange(case.strands), guide_strands(case.strands, g))
            out["guide_count"] = g
            out["guide_spacing_cm"] = guide_spacing(rest[:, 0], case.strands, g)
            out["stretch_followers"] = ob.stretch_stats(pos[:, fol], self.L, ell[fol])[0]
        if case.study == "lra":
            out["lra_excess"] = lra_excess(pos, self.L)
        if ref is not None:
            H = ref.horizon_frames
            out["horizon_s"] = H * self.dt * self.every
            if H > 0:  # else no frame is judged pointwise (the reference is not converged at the first)
                rms, mx = frame_errors(pos[:H], ref.pos[:H], self.L)
                out.update(rms_err_L=float(np.max(rms)), max_err_L=float(np.max(mx)))
            sig = en.signature(pos, self.dt * self.every, self.L, ell, self.box)
            cmp = en.compare(sig, ref.members, ref.spread)
            out.update({m: cmp[m][0] for m in en.DISTANCES})
            out["ref_substeps"] = ref.substeps
        return out

    def lra_moved(self, case, all_cases):
        """How far LRA moved the output (cm): against the same row without it."""
        off = next(c for c in all_cases if c.study == "lra" and c.solver == case.solver
                   and c.iterations == case.iterations and not c.lra)  # fmt: skip
        a, b = read_positions(self.files[case])[0], read_positions(self.files[off])[0]
        return float(np.nanmax(np.linalg.norm(a - b, axis=-1)))


def _timing_flags(plan, scene, case, backend, variant):
    """(strands, flags) of the case's timing on (backend, variant), or None where that binary does not time it."""
    p_sim = int(case.points or scene.points)
    d = variants.declared(backend)
    if backend == "cuda" and not d.runs(variant, points=p_sim):
        return None  # more points than the variant simulates (warpreg: 32)
    if not d.runs_features(variant, row_features(case.extra)):
        return None  # a feature the variant does not run (--list-variants)
    n = plan.time_gpu_strands if backend == "cuda" else plan.time_strands
    tf = _flags(scene, solver=case.solver, substeps=case.substeps, iterations=case.iterations, precision="fp32",
                strands=n, frames=2, extra=case.extra, variant=(backend, variant), points=case.points)  # fmt: skip
    return n, tf + ["--repeat", str(plan.repeat)]


def _timing_key(backend, variant, flags):
    """A timing's key in `_timings`' memo: its binary and flags."""
    return backend, variant, tuple(map(str, flags))


def _timings(plan, scene, case, timers, memo):
    """(backend, variant, strands, record) of each binary of `timers` that times the case, as each is measured;
    a timing whose binary and flags an earlier case already ran (the same settings at the timing's own
    strand count, e.g. a guide row at 1,000 and at 10,000 strands) is that case's record, from `memo`."""
    for backend, variant in timers:
        tf = _timing_flags(plan, scene, case, backend, variant)
        if tf is None:
            continue
        n, flags = tf
        key = _timing_key(backend, variant, flags)
        if key not in memo:
            memo[key] = runner.run_binary(binary_path(backend, "default"), flags)
        yield backend, variant, n, memo[key]


def _memo_from_kept(plan, scene, all_cases, kept):
    """`_timings`' memo seeded with the timings a resumed run keeps, each under its binary and flags, so that
    a case not measured yet whose twin was (a guide row at 10,000 strands, its 1,000-strand twin kept) is
    not timed again."""
    memo = {}
    for c in all_cases:
        for (backend, variant), t in kept.get(c.key, {}).items():
            tf = _timing_flags(plan, scene, c, backend, variant)
            if tf is not None:
                sim = {"stage": "simulate", "median_ms": t["median_ms"], "render_ms": t["render_ms"]}
                memo[_timing_key(backend, variant, tf[1])] = {"stages": [sim], "device": t["device"]}
    return memo


def measure(plan=Plan(), out=None, work=None, progress=print, refs_into=None, resume=False):
    """Every row (module docstring); with `out`, the CSV and references.csv beside it once every row is
    measured, the rows so far kept in OUT.partial until then; the references' rows are appended to the
    list `refs_into` when given. `resume`: the timings in OUT.partial are kept, not measured again
    (refused in one line where it is absent or not this run's: studies/reduced_partial_dynamic.py)."""
    if resume and not out:
        raise HarnessError("reduced: --resume needs --out, the CSV of the run it finishes")
    timers = timing_binaries(plan)
    partial = Partial(out, plan, timers) if out else None
    kept = partial.kept(FIELDS, TIMING_FIELDS) if partial and resume else {}
    if kept:
        n = sum(len(t) for t in kept.values())
        progress(f"reduced: resuming {display(partial.path)}: {n} timing(s) of {len(kept)} case(s) kept")
    with tempfile.TemporaryDirectory(dir=work) as tmp:
        st = Study(plan, tmp, progress)
        all_cases = cases(plan, st.scene)
        for c in all_cases:
            st.checked(c)
        done = []  # (case key, row) of every case measured
        memo = _memo_from_kept(plan, st.scene, all_cases, kept)  # a timing's record by its binary and flags

        def save(case_rows):
            if partial:
                partial.write(FIELDS, done + case_rows)

        for c in all_cases:
            ref = st.reference(c, all_cases)
            m = st.metrics(c, ref)
            if c.study == "lra" and c.lra:
                m["lra_moved_cm"] = st.lra_moved(c, all_cases)
            done += _case_rows(
                plan, st.scene, c, _base(plan, st, c, m), timers, kept.get(c.key, {}), save, progress, memo
            )
        refs = [_ref_row(st, r) for r in st.refs.cache.values()]
        if refs_into is not None:
            refs_into.extend(refs)
    rows = [row for _, row in done]
    if out:  # references.csv first: the CSV itself says the run finished
        write_csv(Path(out).with_name("references.csv"), REF_FIELDS, refs)
        write_csv(out, FIELDS, rows)
        partial.remove()
    return rows


def _case_rows(plan, scene, c, base, timers, kept, save, progress, memo):
    """The case's (key, row) pairs, one per binary of `timers` that times it, in `timers`' order: a timing
    in `kept` as it was, the others measured (or taken from `memo`: _timings), every row so far handed to
    `save` after each."""
    timed = dict(kept)

    def rows():
        return [(c.key, {**base, **timed[t]}) for t in timers if t in timed]

    for t in timers:
        if t in kept:
            _say(progress, c, base, t, kept[t]["median_ms"], " (kept)")
    todo = [t for t in timers if t not in kept]
    for backend, variant, n, rec in _timings(plan, scene, c, todo, memo) if todo else ():
        sim = next(x for x in rec["stages"] if x["stage"] == "simulate")
        values = (backend, variant, n, sim["median_ms"], sim.get("render_ms"), rec["device"])
        timed[(backend, variant)] = dict(zip(TIMING_FIELDS, values, strict=True))
        save(rows())
        _say(progress, c, base, (backend, variant), sim["median_ms"], "")
    return rows()


def _say(progress, c, base, timer, ms, how):
    progress(
        f"reduced: {c.study:7s} {c.solver:4s} N={c.strands} I={c.iterations} guides={c.guides:<4g} "
        f"{c.follow:6s} lra={c.lra} {timer[0]}/{timer[1]}: rms {base.get('rms_err_L') or math.nan:.3g} L, "
        f"{ms:.3f} ms/frame{how}"
    )


def _base(plan, st, c, m):
    p_sim = int(c.points or st.scene.points)
    return {
        **{k: None for k in FIELDS},
        "study": c.study,
        "solver": c.solver,
        "substeps": c.substeps,
        "iterations": c.iterations,
        "guides": c.guides,
        "guide_count": c.strands,
        "guide_spacing_cm": 0.0,
        "follow": c.follow,
        "lra": c.lra,
        "sag_free": c.sag_free,
        "shape_range": c.shape_range,
        "points": p_sim,
        "render_points": plan.lod_render_points if "--render-points" in c.extra else p_sim,
        "precision": "fp32",
        "strands": c.strands,
        "seconds": st.frames_of(c) * st.dt,
        **m,
    }


def _ref_row(st, r):
    return dict(
        scene=r.key[0],
        strands=r.key[1],
        build=r.build,
        substeps=r.substeps,
        converged=r.converged,
        worst_ratio=r.ladder[-1][3],
        ladder="; ".join(f"S{S}/{S2}: {d:.2e}·L ({q:.3g}×)" for S, S2, d, q in r.ladder),
        lyapunov_per_s=r.rate.lam,
        lyapunov_lower_bound=r.rate.bound,
        predictability_s=r.rate.predictability,
        converged_s=r.converged_frames * st.dt * st.every,
        horizon_s=r.horizon_frames * st.dt * st.every,
        **{f"{m}_spread": r.spread.get(m) for m in en.DISTANCES},
    )
