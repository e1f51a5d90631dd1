"""`python -m harness reduced`: what modelling less costs and saves (docs/model.md §3.14) — the
measuring part; harness/render/reduced_report.py renders it.

Rows of one dynamic scene (default `dynamic`), each run for `seconds` of simulated time:

  guides   solver × guide fraction (1, 0.5, 0.25, 0.1, 0.05) × scheme (one, blend3), at the
           scene's S and I: followers placed from the guides
  lra      solver xpbd × iterations (1, 2) × LRA off/on, at the scene's S, with the head
           nodding at `lra_frequency` Hz (fast enough to over-stretch at few iterations)
  sagfree  solver × sag-free off/on: the scene held still (no head motion, no wind, every
           point in shape) for `sag_seconds`; rest_rms_L and rest_max_L, the largest RMS and
           max displacement from the rest shape over L, say how far the groom sags
  sagfreq  solver × sag-free off/on: the same still scene hit at t = 0 by a steady wind of
           `sag_wind` cm/s (no gusts), a step load that sets every strand swinging about its
           new equilibrium for `sag_seconds`; tip_hz and tip_damping are the median over strands
           of the tip's swing frequency and damping ratio (harness/check/observables.py swing):
           sag-free must leave them as they were (it adds no stiffness)
  lod      solver × simulated points P_s (`lod_points`) written with `lod_render_points`
           points (--render-points, a spline through the simulated ones; P_s = P_r simulates
           every point), at the scene's S and I; the reference simulates P_r points

Each row's checked run (`strands` strands, fp32, every frame written) is compared frame by
frame with a reference of the same scene (the LRA rows: with their fast nod) in which every
strand is simulated, xpbd, fp64, I = 1, S = `ref_substeps`: rms_err_L and max_err_L are the
accuracy study's measures (harness/studies/accuracy.py frame_errors), their largest value over
the frames; stretch_max is the row's own largest observable. The reference is a finer run, not
the accuracy study's converged ladder: a row's error includes its S and I's own error, which
the "all simulated" rows (fraction 1, LRA off) show beside it.

Time per frame: the same settings at `time_strands` strands (no file, --repeat), on the cpu
oracle and, with a usable GPU, on each cuda variant that runs all the features (its
`--list-variants` entry lists them; `lanes` lacks guides and LRA, docs/cuda.md). Writes CSV
(one row per case and timing binary).
"""

from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from harness import HarnessError
from harness.check import observables as ob
from harness.core import env, runner, scenes, variants
from harness.core.paths import binary_path
from harness.io.files import write_csv
from harness.io.trajectory import open_trajectory
from harness.studies.accuracy import frame_errors

FIELDS = (
    "study",
    "solver",
    "substeps",
    "iterations",
    "guides",
    "follow",
    "lra",
    "sag_free",
    "points",
    "render_points",
    "precision",
    "strands",
    "rms_err_L",
    "max_err_L",
    "stretch_max",
    "rest_rms_L",
    "rest_max_L",
    "tip_hz",
    "tip_damping",
    "blown_up",
    "backend",
    "variant",
    "time_strands",
    "median_ms",
    "render_ms",
    "device",
)
FRACTIONS = (1.0, 0.5, 0.25, 0.1, 0.05)
STUDIED = ("guides", "lra", "sagfree", "lod")  # the §3.14 features the rows declare
SCHEMES = ("one", "blend3")


@dataclass(frozen=True)
class Plan:
    scene: str = "dynamic"
    strands: int = 200
    seconds: float = 0.5
    ref_substeps: int = 64
    lra_frequency: float = 6.0
    lra_iterations: tuple = (1, 2)
    sag_seconds: float = 2.0
    sag_wind: float = 600.0
    lod_render_points: int = 33
    lod_points: tuple = (33, 17, 9, 5)
    time_strands: int = 10_000
    time_gpu_strands: int = 1_000_000
    repeat: int = 3
    gpu: str = "auto"  # auto | no

    @classmethod
    def quick(cls, **changes):
        base = dict(strands=40, seconds=0.1, ref_substeps=16, time_strands=1000, sag_seconds=0.5, lod_points=(33, 9))
        # the GPU timed at 100,000 strands, not 1,000,000: on an H200 node the full size took
        # the quick study past a 10-minute job (its GPU rows at 20–40 ms a frame, 3 repeats each)
        base["time_gpu_strands"] = 100_000
        return cls(**{**base, **changes})


def cases(plan, scene):
    """(study, solver, S, I, guides, follow, lra, extra flags, points) for every row (points:
    the simulated points a strand, None for the scene's)."""
    s, it = int(scene.dynamic["--substeps"]), int(scene.dynamic["--iterations"])
    out = []
    for solver in ("xpbd", "ftl"):
        for frac in FRACTIONS:
            for follow in SCHEMES if frac < 1.0 else ("",):
                extra = ["--guides", repr(frac), "--follow", follow] if frac < 1.0 else []
                out.append(("guides", solver, s, it, frac, follow, 0, extra, None))
    fast = ["--head-motion", "nod", "--motion-frequency", repr(plan.lra_frequency)]
    for i in plan.lra_iterations:
        for lra in (0, 1):
            out.append(("lra", "xpbd", s, i, 1.0, "", lra, fast + (["--lra"] if lra else []), None))
    still = ["--head-motion", "still", "--wind-speed", "0", "--shape-range", "1"]
    wind = ["--head-motion", "still", "--wind-speed", repr(plan.sag_wind), "--gust-amplitude", "0"]
    wind += ["--shape-range", "1"]
    for study, flags in (("sagfree", still), ("sagfreq", wind)):
        for solver in ("xpbd", "ftl"):
            for sag in (0, 1):
                out.append((study, solver, s, it, 1.0, "", 0, flags + (["--sag-free"] if sag else []), None))
    pr = plan.lod_render_points
    for solver in ("xpbd", "ftl"):
        for ps in plan.lod_points:
            out.append(("lod", solver, s, it, 1.0, "", 0, ["--render-points", str(pr)] if ps < pr else [], ps))
    return out


def _flags(
    scene, *, solver, substeps, iterations, precision, strands, frames, extra, output=None, variant=None, points=None
):
    dyn = {**scene.dynamic, "--solver": solver, "--substeps": substeps, "--iterations": iterations}
    dyn.update({"--frames": frames, "--output-every": 1})
    sc = replace(scene.with_overrides(strands=strands, precision=precision, points=points), dynamic=dyn)
    backend = "cuda" if variant and variant[0] == "cuda" else "cpu"
    flags = runner.run_flags(sc, backend, variant=variant[1] if variant else None, output=output, force=True)
    return flags + list(extra)


def _positions(path):
    with open_trajectory(path) as t:
        sim = t.simulated
        pos = np.stack([t.frame(f).reshape(t.n_strands, t.points, 3) for f in sim]).astype(np.float64)
        obs = t.observables.set_index("step").reindex(t.step[sim])
        rest = t.rest.astype(np.float64)
        return pos, float(np.nanmax(obs["stretch_max"])), int(np.max(obs["blown_up_strands"])), rest


def timing_binaries(plan):
    """(backend, variant) pairs that time the rows: the cpu oracle, and the cuda variants
    that run simulate where a GPU is usable (each times the rows whose features it runs)."""
    out = [("cpu", "ref")]
    ok, _ = env.gpu_status()
    if plan.gpu != "no" and ok and binary_path("cuda", "default").exists():
        d = variants.declared("cuda")
        out += [("cuda", v) for v in d.running("simulate") if any(d.runs_features(v, [f]) for f in STUDIED)]
    return out


def row_features(extra):
    """The §3.14 features a row's flags declare."""
    return variants.features_of(extra)


def measure(plan=Plan(), out=None, work=None, progress=print):
    import tempfile

    scene = scenes.load_scene(plan.scene)
    if scene.model != "dynamic":
        raise HarnessError(f"reduced: scene {plan.scene} is not a dynamic scene")
    frame_dt = float(scene.dynamic["--frame-dt"])
    frames = max(1, round(plan.seconds / frame_dt))
    L = float(scene.hair_length)
    cpu = binary_path("cpu", "default")
    rows = []
    with tempfile.TemporaryDirectory(dir=work) as tmp:
        refs = {}

        def reference(fast, points=None):
            key = (tuple(fast), points)
            if key not in refs:
                path = Path(tmp) / f"ref{len(refs)}.h5"
                flags = _flags(scene, solver="xpbd", substeps=plan.ref_substeps, iterations=1, precision="fp64",
                               strands=plan.strands, frames=frames, extra=fast, output=path,
                               points=points)  # fmt: skip
                runner.run_binary(cpu, flags)
                refs[key] = _positions(path)[0]
            return refs[key]

        def reference_for(study, extra):
            if study in ("sagfree", "sagfreq"):
                return None
            if study == "lod":
                return reference([], plan.lod_render_points)
            return reference([] if study == "guides" else extra[:4])

        timers = timing_binaries(plan)
        for study, solver, s, it, frac, follow, lra, extra, points in cases(plan, scene):
            ref = reference_for(study, extra)
            path = Path(tmp) / "row.h5"
            n_frames = max(1, round(plan.sag_seconds / frame_dt)) if study.startswith("sag") else frames
            flags = _flags(scene, solver=solver, substeps=s, iterations=it, precision="fp32", strands=plan.strands,
                           frames=n_frames, extra=extra, output=path, points=points)  # fmt: skip
            runner.run_binary(cpu, flags)
            pos, stretch, blown, rest = _positions(path)
            rms, mx = frame_errors(pos, ref, L) if ref is not None else (np.nan, np.nan)
            sag_rms, sag_max = frame_errors(pos, np.broadcast_to(rest, pos.shape), L)
            tip_hz, tip_zeta = ob.swing(pos, frame_dt)[:2] if study == "sagfreq" else (np.nan, np.nan)
            p_sim = int(points or scene.points)
            base = {
                "study": study,
                "solver": solver,
                "substeps": s,
                "iterations": it,
                "guides": frac,
                "follow": follow,
                "lra": lra,
                "sag_free": int("--sag-free" in extra),
                "points": p_sim,
                "render_points": plan.lod_render_points if "--render-points" in extra else p_sim,
                "precision": "fp32",
                "strands": plan.strands,
                "rms_err_L": float(np.max(rms)),  # NaN where there is no reference (sagfree) or a run blew up
                "max_err_L": float(np.max(mx)),
                "stretch_max": stretch,
                "rest_rms_L": float(np.nanmax(sag_rms)),
                "rest_max_L": float(np.nanmax(sag_max)),
                "tip_hz": tip_hz,
                "tip_damping": tip_zeta,
                "blown_up": blown,
            }
            for backend, variant in timers:
                d = variants.declared(backend)
                if backend == "cuda" and not d.runs(variant, points=p_sim):
                    continue  # more points than the variant simulates (warpreg: 32)
                if not d.runs_features(variant, row_features(extra)):
                    continue  # a feature the variant does not run (--list-variants)
                n = plan.time_gpu_strands if backend == "cuda" else plan.time_strands
                tf = _flags(scene, solver=solver, substeps=s, iterations=it, precision="fp32", strands=n, frames=2,
                            extra=extra, variant=(backend, variant), points=points)  # fmt: skip
                rec = runner.run_binary(binary_path(backend, "default"), tf + ["--repeat", str(plan.repeat)])
                st = next(x for x in rec["stages"] if x["stage"] == "simulate")
                row = {**base, "backend": backend, "variant": variant, "time_strands": n}
                row.update(median_ms=st["median_ms"], render_ms=st.get("render_ms"), device=rec["device"])
                rows.append(row)
                progress(
                    f"reduced: {study:6s} {solver:4s} I={it} guides={frac:<4g} {follow:6s} lra={lra} "
                    f"{backend}/{variant}: rms {base['rms_err_L']:.3g} L, {st['median_ms']:.3f} ms/frame"
                )
    if out:
        write_csv(out, FIELDS, rows)
    return rows
