"""`python -m harness judge`: the one-frame judge's power, measured (docs/judge.md).

Two counts, each over one-frame comparisons judged exactly as `harness stepdiff` judges
(harness.check.diff_dynamic.compare with the scene's spread):

  caught / planted: every planted defect (build/planted/hairsim-cpu-plant<n>, `make planted`:
      the C reference with `#if HB_PLANT == n` compiled in) stepped from the honest
      reference's frames on the standard scenes (STANDARD), fp32 and fp64; a defect is caught
      when any of its comparisons is not equivalent. A defect that no standard scene can show
      is listed with its reason (PLANTS[n].needs);
  false alarms / honest runs: every honest build × variant × precision that simulates (the
      CPU's variants; each CUDA build's where a GPU is usable) stepped from the reference on
      the extreme scenes (EXTREME); an honest run is a false alarm when any of its frames is
      not equivalent.

Simulated-point LOD files (--render-points) are not resumable, so stepdiff cannot step them; each
LOD scene (LOD_SCENES) is judged by (a) stepdiff of the same run without LOD (the simulation), (b)
the LOD run's simulated rows against that run, bit for bit (rendering changes nothing the
simulation does), and (c) its rendered rows recomputed from its simulated rows
(harness/check/lod_dynamic.py: bit for bit for the reference build, within DYN_LOD_KERNEL_K·ε·E for the
others); the LOD plant (PLANTS, model "lod") must fail (c).

Writes <out>/judge.csv (one row per compared frame) and <out>/judge.json (the counts, what
each defect is and which scenes caught it); report/dynamic.md renders them.
"""

import shutil
import tempfile
import time
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from harness import HarnessError
from harness.check import diff, diff_dynamic, invariants_dynamic
from harness.check import lod_dynamic as lod
from harness.core import env, runner, scenes, tolerances, variants
from harness.core.paths import CUDA_BUILDS, RESULTS, binary_path, build_dir, display
from harness.core.progress import Progress
from harness.io import files, runfolder
from harness.io.files import write_json
from harness.io.trajectory import open_trajectory, simulated_view

# judge.json's record of where it was measured
ENV_KEYS = ("date", "hostname", "cpu_model", "cpu_cores", "device", "driver", "nvcc", "git_revision")

RESULTS_NAME = "judge"


@dataclass(frozen=True)
class Plant:
    what: str  # the defect, in words
    needs: str  # what a scene must have for it to show
    model: str = "dynamic"  # the model whose code it is in: dynamic (stepdiff) or paper (diff)


# The planted defects: hunk n of c_ref (`#if HB_PLANT == n`); tests/cpu/test_judge.py checks
# that this list and the C sources name the same numbers.
PLANTS = {
    1: Plant("gravity dropped from the velocity update", "gravity"),
    2: Plant("the head rotation at t instead of t + h", "a moving head"),
    3: Plant("the even stretch group before the odd", "xpbd"),
    4: Plant("the multipliers λ not reset between substeps", "a compliant constraint, S ≥ 2"),
    5: Plant("a bend rest length from the current shape instead of the rest shape", "bend"),
    6: Plant("the collider skips point P/2", "the collider, point P/2 in contact"),
    7: Plant("the gust phase one substep late", "gusts"),
    8: Plant("the root given weight 1 in its stretch constraint", "xpbd"),
    9: Plant("the ftl correction from the point's own d_k, not d_{k+1}", "ftl"),
    10: Plant("the shape range one point too long", "shape, ρ_g < 1"),
    11: Plant("the wind's blend of segment k taken at k − 1", "wind", "paper"),
    12: Plant("collide without the follow-the-leader pull after a move", "a point collide moves", "paper"),
    13: Plant("every drape step from the head circle, not the shell", "a draped strand of ≥ 3 points", "paper"),
    14: Plant("the rendered spline's root end copied, not reflected", "--render-points", "lod"),
}
# LOD scenes (configs/scenes/dynamic with P_s simulated points rendered as P_r): name → (P_s, P_r, solver)
LOD_SCENES = {"lod-dynamic": (9, 33, "xpbd"), "lod-dynamic-ftl": (5, 33, "ftl")}

# The standard scenes the planted defects are run on: configs/scenes/<name> × solver.
STANDARD = (("dynamic", "xpbd"), ("dynamic", "ftl"), ("still-dynamic", "xpbd"), ("still-dynamic", "ftl"))

# The paper model (`harness diff` of whole runs, the precision pair's rule): its planted defects
# run on these configs/scenes, and the honest variants on PAPER_EXTREME (changes to paper.toml).
PAPER_STANDARD = ("paper", "still", "breeze", "gale")
PAPER_EXTREME = {
    "paper-two-points": {"points": 2},
    "paper-long-strands": {"points": 200, "hair_length": 60.0},
    "paper-short-segments": {"points": 251, "hair_length": 30.0, "hair_offset": 0.01},
    "paper-full-wind": {"wind_strength": 1.0},
    "paper-side-wind": {"wind_strength": 1.0, "wind_angle": 1.5707963267948966},
    "paper-wind-from-behind": {"wind_strength": 0.9, "wind_angle": 0.0},
    "paper-thick-shell": {"hair_offset": 0.9, "points": 8},
    "paper-small-head": {"head_radius": 2.0, "face_margin": 0.2, "hair_length": 60.0},
}

# The extreme scenes honest builds must pass: name → (solver, scene fields, dynamic flags),
# over configs/scenes/dynamic (every feature) unless the flags say otherwise. OFF drops a flag.
OFF = None
GALE = {"--wind-speed": 3000.0, "--gust-amplitude": 1.0, "--gust-wavelength": 15.0, "--gust-frequency": 3.0}
EXTREME = {
    "long-strands": ("xpbd", {"points": 96, "hair_length": 60.0}, {}),
    "long-strands-ftl": ("ftl", {"points": 96, "hair_length": 60.0}, {}),
    "short-strands": ("xpbd", {"points": 4, "hair_length": 2.0}, {}),
    "two-points": ("xpbd", {"points": 2, "hair_length": 20.0}, {"--shape-compliance": OFF, "--shape-range": OFF}),
    "stiff": ("xpbd", {}, {"--bend-compliance": 0.0, "--shape-compliance": 1e-9, "--iterations": 8}),
    "soft": ("xpbd", {}, {"--stretch-compliance": 1e-4, "--bend-compliance": 1e-3, "--shape-compliance": 1e-2}),
    "gale": ("xpbd", {}, GALE),
    "gale-ftl": ("ftl", {}, GALE),
    "stiff-bend-ftl-gale-200": ("ftl", {"points": 200, "hair_length": 60.0}, {**GALE, "--bend-compliance": 0.0}),
    "fast-shake": ("xpbd", {}, {"--head-motion": "shake", "--motion-amplitude": 1.0, "--motion-frequency": 4.0}),
    "fast-nod-ftl": ("ftl", {}, {"--motion-amplitude": 1.0, "--motion-frequency": 4.0}),
    "fast-tilt": ("xpbd", {}, {"--head-motion": "tilt", "--motion-amplitude": 1.2, "--motion-frequency": 3.0}),
    "collider-margin": ("xpbd", {}, {"--collision-margin": 0.5, "--iterations": 3}),
    "collider-larger-than-scalp": ("xpbd", {}, {"--collision-margin": 3.0}),
    "collider-larger-than-scalp-ftl": ("ftl", {}, {"--collision-margin": 3.0}),
    "one-strand-tilt-big-collider": (
        "xpbd",
        {"strands": 1},
        {"--collision-margin": 3.0, "--head-motion": "tilt", "--motion-amplitude": 1.0, "--motion-frequency": 2.0},
    ),
    "no-collider": ("xpbd", {}, {"--no-collider": ""}),
    "one-substep": ("xpbd", {}, {"--substeps": 1, "--iterations": 1}),
    "one-substep-ftl": ("ftl", {}, {"--substeps": 1, "--iterations": 1}),
    "many-substeps": ("xpbd", {}, {"--substeps": 64, "--iterations": 1}),
    "many-iterations": ("xpbd", {}, {"--substeps": 4, "--iterations": 16}),
    "heavy-drag": ("xpbd", {}, {"--drag": 50.0, "--damping": 20.0}),
    "no-gravity-wind": ("xpbd", {}, {"--gravity": 0.0, "--wind-speed": 800.0}),
    "long-frame": ("xpbd", {}, {"--frame-dt": 1.0 / 15.0}),
    "full-shape": ("xpbd", {}, {"--shape-range": 1.0, "--shape-compliance": 1e-7}),
}


@dataclass(frozen=True)
class Plan:
    strands: int = 32  # per scene (a scene that sets its own keeps it)
    frames: int = 3  # simulated frames of each reference
    stepped: int = 2  # frames stepped from: the last `stepped` candidates of the reference
    precisions: tuple = ("fp32", "fp64")
    standard: tuple = STANDARD
    extreme: tuple = tuple(EXTREME)
    plants: tuple = tuple(PLANTS)
    paper_standard: tuple = PAPER_STANDARD
    paper_extreme: tuple = tuple(PAPER_EXTREME)
    lod: tuple = tuple(LOD_SCENES)
    gpu: str = "auto"  # auto | yes | no: the CUDA builds' honest runs

    @classmethod
    def quick(cls, **kw):
        return cls(**{"strands": 8, "frames": 2, "stepped": 1, **kw})


def planted_binary(n):
    return build_dir() / "planted" / f"hairsim-cpu-plant{n}"


def standard_scene(name, solver, plan):
    base = scenes.load_scene(name)
    scene = base.with_overrides(strands=plan.strands)
    return replace(scene, name=f"{name} {solver}", dynamic={**base.dynamic, "--solver": solver})


def extreme_scene(name, plan):
    solver, fields, flags = EXTREME[name]
    base = scenes.load_scene("dynamic")
    dyn = {**base.dynamic, "--solver": solver}
    for flag, value in flags.items():
        if value is OFF:
            dyn.pop(flag, None)
        else:
            dyn[flag] = value
    scene = base.with_overrides(**{"strands": plan.strands, **fields})
    return replace(scene, name=name, dynamic=dyn)


def lod_scene(name, plan):
    """A LOD scene without its --render-points (lod_flags adds them)."""
    ps, _, solver = LOD_SCENES[name]
    base = scenes.load_scene("dynamic")
    return replace(base.with_overrides(strands=plan.strands, points=ps), name=name,
                   dynamic={**base.dynamic, "--solver": solver})  # fmt: skip


def paper_scene(name, plan):
    if name in PAPER_EXTREME:
        return replace(
            scenes.load_scene("paper").with_overrides(strands=plan.strands, **PAPER_EXTREME[name]), name=name
        )
    return scenes.load_scene(name).with_overrides(strands=plan.strands)


def honest_runners(gpu, log):
    """(label, binary, flags) of every honest build × variant that simulates."""
    out = []
    cpu = variants.declared("cpu")
    out += [(f"cpu {v}", binary_path("cpu"), ["--variant", v]) for v in cpu.running("simulate")]
    if gpu == "no":
        return out, "--gpu no"
    usable, why = env.gpu_status()
    if not usable:
        if gpu == "yes":
            raise HarnessError(f"judge: --gpu yes but {why}")
        return out, why
    for build in CUDA_BUILDS:
        if not binary_path("cuda", build).exists():
            log(f"judge: {display(binary_path('cuda', build))} not built: its honest runs are not made")
            continue
        d = variants.declared("cuda", build)
        out += [(f"cuda {build} {v}", binary_path("cuda", build), ["--variant", v]) for v in d.running("simulate")]
    return out, ""


class Judge:
    def __init__(self, plan, work, log):
        self.plan, self.work, self.log = plan, Path(work), log
        self.rows = []
        self.count = 0

    def reference(self, scene, precision):
        """The honest reference's file: init,collide,simulate for plan.frames, every velocity."""
        self.count += 1
        out = self.work / f"ref{self.count}-{scene.name.replace(' ', '-')}-{precision}.h5"
        s = scenes.with_frames(scene.with_overrides(precision=precision), self.plan.frames)
        flags = runner.run_flags(s, "cpu", output=out) + ["--velocities", "all"]
        runner.run_binary(binary_path("cpu"), flags, timeout=600)
        with open_trajectory(out) as t:
            cand = diff_dynamic.step_candidates(t)
        return out, cand[-self.plan.stepped :]

    def step(self, ref, frames, binary, flags, points):
        """One frame from each of `frames` of `ref` by `binary`; the compared frames' rows.
        A variant that refuses the scene (exit 2: e.g. over its most points) gives no row."""
        rows = []
        for k in frames:
            self.count += 1
            out = self.work / f"step{self.count}.h5"
            cmd = ["--input", ref, "--input-frame", k, "--stages", "simulate", "--frames", 1, *flags, "--output", out]
            try:
                runner.run_binary(binary, cmd, timeout=600)
            except runner.BackendError as e:
                if e.code == 2:
                    return rows
                rows.append({"frame": k, "equivalent": False, "failures": str(e)})
                continue
            with open_trajectory(out) as t:
                step = int(t.step[-1])
            r = diff_dynamic.compare(ref, out, frames=[step], check_paper=False, spread=True)
            f = r.frames[0]
            rows.append(
                {
                    "frame": k,
                    "step": step,
                    "max_abs": f.max_abs,
                    "rule": tolerances.DYN_STEP_K[diff_dynamic.diff_key(*r.pair.split("↔"))] * r.unit,
                    "spread": getattr(f, "spread", float("nan")),
                    "limit": getattr(f, "limit", float("nan")),
                    "velocity_max_abs": getattr(f, "velocity_max_abs", float("nan")),
                    "velocity_limit": getattr(f, "velocity_limit", float("nan")),
                    "over": f.over,
                    "equivalent": r.equivalent,
                    "failures": "; ".join(r.failures()[:2]),
                }
            )
            out.unlink()
        return rows

    def lod_rows(self, scene, precision, binary, flags):
        """One row for a LOD run of `binary`: its simulated rows against the same run without LOD (bit
        for bit) and its rendered rows recomputed (lod.check_rendered). A refusal gives no row."""
        self.count += 1
        plain, rendered = self.work / f"plain{self.count}.h5", self.work / f"lod{self.count}.h5"
        s = scenes.with_frames(scene.with_overrides(precision=precision), self.plan.frames)
        base = runner.run_flags(s, "cpu") + ["--velocities", "all", *flags]
        try:
            runner.run_binary(binary, base + ["--output", plain], timeout=600)
            runner.run_binary(binary, base + ["--render-points", LOD_SCENES[scene.name][1], "--output", rendered],
                              timeout=600)  # fmt: skip
        except runner.BackendError as e:
            return [] if e.code == 2 else [{"frame": "all", "equivalent": False, "failures": str(e)}]
        with open_trajectory(plain) as a, open_trajectory(rendered) as b:
            exact = invariants_dynamic.is_reference_build(b)
            bad, worst = lod.check_rendered(b, exact)
            view = simulated_view(b)
            same = all(np.array_equal(a.frame(f), view.frame(f)) for f in range(a.n_frames))
            unit = tolerances.EPS[tolerances.kind_of(b.precision, b.fast_math)] * (b.collide_radius + 2 * b.hair_length)
        failures = [v.message for v in bad[:2]] + (
            [] if same else ["the simulated rows differ from the run without LOD"]
        )
        return [
            {
                "frame": "all",
                "max_abs": worst * unit,
                "rule": (0.0 if exact else tolerances.DYN_LOD_KERNEL_K) * unit,
                "spread": float("nan"),
                "limit": (0.0 if exact else tolerances.DYN_LOD_KERNEL_K) * unit,
                "over": sum(v.count for v in bad),
                "equivalent": same and not bad,
                "failures": "; ".join(failures),
            }
        ]

    def paper_run(self, scene, precision, binary=None, flags=()):
        """A whole paper-model run of `scene`; its file."""
        self.count += 1
        out = self.work / f"paper{self.count}.h5"
        s = scene.with_overrides(precision=precision)
        runner.run_binary(
            binary or binary_path("cpu"), runner.run_flags(s, "cpu", output=out) + list(flags), timeout=600
        )
        return out

    def paper_diff(self, ref, scene, precision, binary, flags):
        """`harness diff` of `binary`'s run against the reference run: one row (every frame judged)."""
        try:
            out = self.paper_run(scene, precision, binary, flags)
        except runner.BackendError as e:
            return [] if e.code == 2 else [{"frame": "all", "equivalent": False, "failures": str(e)}]
        r = diff.compare(ref, out)
        worst = max(r.frames, key=lambda f: f.max_abs)
        out.unlink()
        return [
            {
                "frame": "all",
                "max_abs": worst.max_abs,
                "rule": r.limit_range[1],
                "spread": float("nan"),
                "limit": r.limit_range[1],
                "over": sum(f.over for f in r.frames),
                "equivalent": r.equivalent,
                "failures": "; ".join(r.failures()[:2]),
            }
        ]

    def add(self, kind, who, scene, precision, rows):
        for r in rows:
            self.rows.append(
                {
                    "kind": kind,
                    "who": who,
                    "scene": scene.name,
                    "solver": scene.dynamic.get("--solver", "xpbd") if scene.model == "dynamic" else "",
                    "points": scene.points,
                    "precision": precision,
                    **r,
                }
            )
        return any(not r["equivalent"] for r in rows)


CSV_FIELDS = (
    "kind who scene solver points precision frame step max_abs rule spread limit velocity_max_abs "
    "velocity_limit over equivalent failures"
).split()


def write_csv(rows, path):
    """The compared frames, one a row, written whole or not at all."""
    files.write_csv(path, CSV_FIELDS, rows)


def run(plan=None, out_dir=None, log=print, jobs=None):
    """Measure both counts; write judge.csv and judge.json under out_dir; return the summary.
    `jobs` scenes at once (default: every core); each scene's runs are one after another."""
    plan = plan or Plan()
    runner.require_binary(binary_path("cpu"))
    if not diff_dynamic.spread_binary().exists():
        raise HarnessError(f"judge: {display(diff_dynamic.spread_binary())} is not built (run make cpu)")
    missing = [n for n in plan.plants if not planted_binary(n).exists()]
    if missing:
        raise HarnessError(
            f"judge: planted build(s) {', '.join(map(str, missing))} missing under {display(build_dir() / 'planted')} "
            "(run make planted)"
        )
    honest, gpu_note = honest_runners(plan.gpu, log)  # --gpu yes without a GPU: refused before a folder is made
    out_dir = runfolder.claim(out_dir or RESULTS / RESULTS_NAME, "judge", force=True)
    if gpu_note:
        log(f"judge: GPU builds not run: {gpu_note}")
    oracle = variants.declared("cpu").default_variant
    t0 = time.perf_counter()
    work = Path(tempfile.mkdtemp(prefix="hb-judge-"))
    dynamic_plants = [n for n in plan.plants if PLANTS[n].model == "dynamic"]
    units = (
        [("planted", standard_scene(name, solver, plan), p) for name, solver in plan.standard for p in plan.precisions]
        if dynamic_plants
        else []
    )
    units += [("honest", extreme_scene(name, plan), p) for name in plan.extreme for p in plan.precisions]
    paper_plants = [n for n in plan.plants if PLANTS[n].model == "paper"]
    if paper_plants:
        units += [("planted", paper_scene(n, plan), p) for n in plan.paper_standard for p in plan.precisions]
    units += [("honest", paper_scene(n, plan), p) for n in plan.paper_extreme for p in plan.precisions]
    lod_plants = [n for n in plan.plants if PLANTS[n].model == "lod"]
    units += [(kind, lod_scene(n, plan), p) for kind in ("planted",) * bool(lod_plants) + ("honest",)
              for n in plan.lod for p in plan.precisions]  # fmt: skip
    cpu_honest = [(f"cpu {v}", binary_path("cpu"), ["--variant", v]) for v in variants.declared("cpu").running("init")]

    def one(i, kind, scene, precision):
        """One scene at one precision: its reference, then every planted or honest run from it."""
        j = Judge(plan, work / f"u{i}", log)
        j.work.mkdir()
        flagged: list = []
        runs = 0
        if scene.model == "paper":
            ref = j.paper_run(scene, precision)
            if kind == "planted":
                for n in paper_plants:
                    rows = j.paper_diff(ref, scene, precision, planted_binary(n), ["--variant", oracle])
                    flagged += [n] if j.add(kind, f"plant {n}", scene, precision, rows) else []
            else:
                for label, binary, flags in cpu_honest:
                    rows = j.paper_diff(ref, scene, precision, binary, flags)
                    runs += bool(rows)
                    flagged += [label] if rows and j.add(kind, label, scene, precision, rows) else []
            shutil.rmtree(j.work, ignore_errors=True)
            return j.rows, flagged, runs
        if scene.name in LOD_SCENES:
            return lod_unit(j, kind, scene, precision)
        ref, frames = j.reference(scene, precision)
        if kind == "planted":
            for n in dynamic_plants:
                rows = j.step(ref, frames, planted_binary(n), ["--variant", oracle], scene.points)
                flagged += [n] if j.add(kind, f"plant {n}", scene, precision, rows) else []
        else:
            for label, binary, flags in honest:
                rows = j.step(ref, frames, binary, flags, scene.points)
                runs += bool(rows)
                flagged += [label] if rows and j.add(kind, label, scene, precision, rows) else []
        shutil.rmtree(j.work, ignore_errors=True)
        return j.rows, flagged, runs

    def lod_unit(j, kind, scene, precision):
        """A LOD scene: each plant's LOD run, or each honest run's stepdiff and LOD run."""
        flagged, runs = [], 0
        if kind == "planted":
            for n in lod_plants:
                rows = j.lod_rows(scene, precision, planted_binary(n), ["--variant", oracle])
                flagged += [n] if j.add(kind, f"plant {n}", scene, precision, rows) else []
        else:
            ref, frames = j.reference(scene, precision)
            for label, binary, flags in honest:
                rows = j.lod_rows(scene, precision, binary, flags)
                if rows:
                    rows += j.step(ref, frames, binary, flags, scene.points)
                runs += bool(rows)
                flagged += [label] if rows and j.add(kind, label, scene, precision, rows) else []
        shutil.rmtree(j.work, ignore_errors=True)
        return j.rows, flagged, runs

    caught_by = {n: [] for n in plan.plants}
    false_alarms, honest_runs, rows = [], {"dynamic": 0, "paper": 0, "lod": 0}, []
    bar = Progress(len(units), "judge")
    try:
        with ThreadPoolExecutor(max_workers=jobs or env.usable_cores()) as pool:
            futures = [pool.submit(one, i, *u) for i, u in enumerate(units)]
            for (kind, scene, precision), fut in zip(units, futures):
                unit_rows, flagged, runs = fut.result()
                rows += unit_rows
                honest_runs[_model(scene)] += runs
                for who in flagged:
                    if kind == "planted":
                        caught_by[who].append(f"{scene.name} {precision}")
                    else:
                        false_alarms.append(f"{who} {scene.name} {precision}")
                bar.update()
    finally:
        bar.close()
        shutil.rmtree(work, ignore_errors=True)
    caught = [n for n in plan.plants if caught_by[n]]
    summary = {
        "caught": len(caught),
        "planted": len(plan.plants),
        "false_alarms": len(false_alarms),
        "honest_runs": sum(honest_runs.values()),
        "by_model": {
            m: {
                "caught": sum(1 for n in caught if PLANTS[n].model == m),
                "planted": sum(1 for n in plan.plants if PLANTS[n].model == m),
                "false_alarms": sum(1 for r in false_alarms if _alarm_model(r) == m),
                "honest_runs": honest_runs[m],
            }
            for m in ("dynamic", "paper", "lod")
        },
        "spread_k": tolerances.DYN_SPREAD_K,
        "rule_k": tolerances.DYN_STEP_K[("fp64", "fp64")],
        "plan": {k: list(v) if isinstance(v, tuple) else v for k, v in plan.__dict__.items()},
        "gpu_note": gpu_note,
        "plants": {
            str(n): {
                "what": PLANTS[n].what,
                "needs": PLANTS[n].needs,
                "model": PLANTS[n].model,
                "caught_on": caught_by[n],
            }
            for n in plan.plants
        },
        "missed": [n for n in plan.plants if not caught_by[n]],
        "false_alarm_runs": false_alarms,
        "honest": [label for label, _, _ in honest],
        "seconds": round(time.perf_counter() - t0, 1),
        "env": {k: v for k, v in env.collect().items() if k in ENV_KEYS},  # where it was measured
    }
    write_csv(rows, out_dir / "judge.csv")
    write_json(out_dir / "judge.json", summary)
    return summary


def _model(scene):
    """The judged model of a unit's scene: paper, lod (a LOD scene) or dynamic."""
    return "lod" if scene.name in LOD_SCENES else scene.model


def _alarm_model(alarm):
    """The model of a false alarm's 'who scene precision' line."""
    scene = alarm.rsplit(" ", 1)[0]
    if any(scene.endswith(name) for name in LOD_SCENES):
        return "lod"
    return "paper" if any(scene.endswith(name) for name in PAPER_EXTREME) else "dynamic"


def _lod(by_model):
    """The LOD counts of a summary (zeros in one written before LOD was judged)."""
    return by_model.get("lod", {"caught": 0, "planted": 0, "false_alarms": 0, "honest_runs": 0})


def format_summary(s):
    bm = s["by_model"]
    lines = [
        f"judge: caught {s['caught']} / {s['planted']} planted defects on the standard scenes "
        f"(dynamic {bm['dynamic']['caught']} / {bm['dynamic']['planted']} by stepdiff's judge, "
        f"paper {bm['paper']['caught']} / {bm['paper']['planted']} by diff's, "
        f"LOD {_lod(bm)['caught']} / {_lod(bm)['planted']} by the rendered rows' recomputation)",
        f"judge: false alarms {s['false_alarms']} / {s['honest_runs']} honest runs on the extreme scenes "
        f"({', '.join(s['honest'])}; dynamic {bm['dynamic']['false_alarms']} / {bm['dynamic']['honest_runs']}, "
        f"paper {bm['paper']['false_alarms']} / {bm['paper']['honest_runs']}, "
        f"LOD {_lod(bm)['false_alarms']} / {_lod(bm)['honest_runs']})",
        f"judge: limit max({s['rule_k']:g}·ε·E·S·I, {s['spread_k']:g} × spread); {s['seconds']} s",
    ]
    for n, p in s["plants"].items():
        if p["caught_on"]:
            seen = f"caught on {len(p['caught_on'])} scene(s) (it needs {p['needs']}): {', '.join(p['caught_on'])}"
        else:
            seen = f"NOT CAUGHT: it needs {p['needs']}, which no standard scene run showed"
        lines.append(f"  plant {n:>2} ({p['what']}): {seen}")
    for r in s["false_alarm_runs"]:
        lines.append(f"  false alarm: {r}")
    return "\n".join(lines)
