"""Speed against accuracy of the world around the hair (docs/model.md §3.16, §3.17): the
hair–hair grid's size × when it is built × friction × volume on the default scene, and the
colliders' SDF resolution × friction on the body of configs/scenes/body.toml, with friction also as
contact planes (--contact-planes M) and with the collision step once a substep (--collide-once).
Measures and writes CSV; accuracy_world_verdicts_dynamic.py judges it,
harness/render/accuracy_world_dynamic_report.py renders the table and that verdict.

Each variant runs the scene's own step (S = 8, I = 2, fp32) at `strands` strands for `seconds`,
and its **converged reference**, the same features at S = `ref_substeps` in fp64 (the error is
then the step's, not the feature's), but for contact planes and colliding once the exact order's
(their error is the trade's too). Against it: the RMS and max error over all points and
frames (studies.accuracy.frame_errors, over L), and the observables the features change, the
variant's beside its reference's: the last frame's hair volume, envelope radius and close pairs
(check/hair_volume_dynamic.py), and the worst frame's penetration and stretch (§3.8). The cost is the
simulate stage's time per frame apart from the checked runs (`time_strands` strands, one thread,
`time_frames` frames), the median of `repeat` rounds that each time every variant in turn (a
shared machine's load then falls on all alike; the rounds' spread is kept), over the same scene
without the feature (the group's `off` row).
"""

import shutil
import tempfile
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from harness import HarnessError
from harness.check import hair_volume_dynamic as hair_volume
from harness.core import env, runner, scenes, variants
from harness.core.limits import limits
from harness.core.paths import RESULTS, binary_path, display
from harness.core.progress import Progress
from harness.core.scenes_dynamic import BODY_FLAGS, GRID_FLAGS
from harness.io import files
from harness.io.trajectory import open_trajectory
from harness.studies.accuracy import BODY_SCENE, WORLD_CSV_NAME, WORLD_RESULTS_NAME, frame_errors

CSV_NAME = WORLD_CSV_NAME
RESULTS_NAME = WORLD_RESULTS_NAME
# the grid's settings and the body come from BODY_SCENE's [grid] and [body]
GRID_SCENE = "dynamic"  # the grid's variants run on the default scene

COLUMNS = (
    "group",  # grid | body
    "variant",
    "grid",  # n_g, or "off"
    "rebuild",
    "friction",  # on | off
    "volume",  # on | off (grid only)
    "sdf",  # the mesh's n_s (body only)
    "planes",  # the contact planes' margin M in cm, or "off": every collider exactly (body only)
    "once",  # on: xpbd's collision step in a substep's last iteration alone (--collide-once); off (body only)
    "strands",
    "frames",
    "substeps",
    "iterations",
    "ref_substeps",
    "time_strands",
    "ms_frame",  # the median over the timing rounds of each round's median frame time
    "ms_min",  # the fastest and slowest round: the spread a shared machine put on it
    "ms_max",
    "cost_ratio",  # ms_frame over the group's off row
    "gpu_variant",  # where a GPU answers: the default cuda build's fastest variant that runs the row
    "gpu_strands",
    "gpu_ms_frame",  # its median frame time over the rounds (empty: no GPU, or no variant runs it)
    "gpu_cost_ratio",
    "rms_err_L",
    "max_err_L",
    "hair_volume",
    "hair_volume_ref",
    "envelope",
    "envelope_ref",
    "close_pairs",
    "close_pairs_ref",
    "penetration_max",
    "penetration_ref",
    "stretch_max",
    "stretch_ref",
)


@dataclass(frozen=True)
class Plan:
    strands: int = 64
    seconds: float = 1.0  # the body rises into place in 0.5 s (body.toml): the hair then lies on it
    ref_substeps: int = 64
    grid_sizes: tuple = (16, 32, 64)
    rebuilds: tuple = ("frame", "substep", "held")
    sdf_sizes: tuple = (32, 64, 128)
    contact_margins: tuple = (2.0, 5.0)  # --contact-planes M of the planes rows (each SDF size, friction on)
    time_strands: int = 1000
    time_frames: int = 3
    repeat: int = 5  # timing rounds, every variant once a round (in turn, so that a load hits them alike)
    jobs: int | None = None
    gpu: str = "auto"  # auto: the GPU's times too where one answers and hairsim-cuda is built; no
    gpu_strands: int = 1_000_000

    @classmethod
    def quick(cls, **changes):
        """Every axis still present, fewer strands and a shorter run (a minute or two on 2 cores)."""
        base = dict(strands=32, seconds=0.75, ref_substeps=32, grid_sizes=(16, 32), sdf_sizes=(32, 64),
                    contact_margins=(5.0,), time_strands=300, repeat=3)  # fmt: skip
        return cls(**{**base, **changes})


@dataclass(frozen=True)
class Variant:
    group: str
    name: str
    scene: object  # a core.scenes scene with the variant's flags
    columns: dict  # its axis values, as the CSV writes them
    ref_scene: object = None  # its converged reference's scene at S = ref_substeps (None: scene's)


def check_plan(plan):
    """Refuse a plan that cannot measure anything (HarnessError, exit 2)."""
    bad = []
    if plan.strands < 2 or plan.time_strands < 1 or plan.repeat < 1:
        bad.append("--strands must be at least 2, the timed strands and rounds at least 1")
    if not 0 < plan.seconds <= 10:
        bad.append(f"--seconds must be in (0, 10] (got {plan.seconds:g})")
    if plan.ref_substeps <= 8:
        bad.append(f"--ref-substeps {plan.ref_substeps} must exceed the scenes' S = 8")
    fewest, most = limits().grid_n
    if not plan.grid_sizes or any(not fewest <= n <= most for n in plan.grid_sizes):
        bad.append(f"--grid-sizes needs values from {fewest} to {most}")
    if not plan.sdf_sizes or any(not 8 <= n <= 512 for n in plan.sdf_sizes):
        bad.append("--sdf-sizes needs values from 8 to 512")
    if any(not 0 < m <= 100 for m in plan.contact_margins):
        bad.append("the contact planes' margins must be in (0, 100] cm")
    if not plan.rebuilds or any(r not in ("frame", "substep", "held") for r in plan.rebuilds):
        bad.append("the grid's rebuilds are frame, substep and held")
    if bad:
        raise HarnessError("accuracy-world: " + "; ".join(bad), code=2)


def _without(dyn, drop):
    """A scene's dynamic flags without those `drop` accepts."""
    return {f: v for f, v in dyn.items() if not drop(f)}


def _grid_flag(f):
    return f in GRID_FLAGS


def _body_flag(f):
    return f in BODY_FLAGS


def grid_variants(plan):
    """The default scene with no grid, then every size × rebuild × friction × volume (both off:
    the grid built and nothing applied, its cost alone)."""
    body = scenes.load_scene(BODY_SCENE).dynamic
    grid = {f: v for f, v in body.items() if _grid_flag(f)}
    base = scenes.load_scene(GRID_SCENE)
    out = [Variant("grid", "off", base, dict(grid="off", friction="off", volume="off"))]
    for n in plan.grid_sizes:
        for rebuild in plan.rebuilds:
            for fric in ("on", "off"):
                for vol in ("on", "off"):
                    flags = dict(grid, **{"--grid": n, "--grid-rebuild": rebuild})
                    flags = _without(flags, lambda f, fr=fric, vo=vol: (f == "--grid-friction" and fr == "off")
                                     or (f == "--grid-volume" and vo == "off"))  # fmt: skip
                    name = f"{n}³ {rebuild}, friction {fric}, volume {vol}"
                    cols = dict(grid=n, rebuild=rebuild, friction=fric, volume=vol)
                    out.append(Variant("grid", name, replace(base, dynamic={**base.dynamic, **flags}), cols))
    return out


def body_variants(plan, folder):
    """The body scene without its grid and colliders (off), then each SDF size of its mesh ×
    friction (on: the file's μ and the head sphere's; off: every μ removed), and with friction on its
    colliders as contact planes at each margin, against the exact order's reference. The colliders
    files are written into `folder` beside a link to each mesh."""
    body = scenes.load_scene(BODY_SCENE)
    dyn = _without(body.dynamic, _grid_flag)
    flags = body.flags()
    src = Path(flags[flags.index("--colliders") + 1])
    lines = src.read_text().splitlines()
    for line in lines:  # the meshes the file names, beside the written files
        words = line.split("#")[0].split()
        if words and words[0] == "mesh" and not (folder / words[2]).exists():
            (folder / words[2]).symlink_to((src.parent / words[2]).resolve())
    off = dict(sdf="off", friction="off", planes="off", once="off")
    out = [Variant("body", "off", replace(body, dynamic=_without(dyn, _body_flag)), off)]
    for n in plan.sdf_sizes:
        for fric in ("on", "off"):
            path = folder / f"sdf{n}-friction-{fric}.colliders"
            files.write_text(path, "\n".join(_collider_line(line, n, fric == "on") for line in lines) + "\n")
            flags = {**dyn, "--colliders": str(path)}
            if fric == "off":
                flags.pop("--friction", None)
            exact = replace(body, dynamic=flags)
            cols = dict(sdf=n, friction=fric, planes="off", once="off")
            out.append(Variant("body", f"SDF {n}³, friction {fric}", exact, cols))
            for m in plan.contact_margins if fric == "on" else ():
                planes = replace(body, dynamic={**flags, "--contact-planes": m})
                cols = dict(sdf=n, friction=fric, planes=f"{m:g}", once="off")
                out.append(Variant("body", f"SDF {n}³, friction on, planes {m:g} cm", planes, cols, ref_scene=exact))
            if fric == "on":  # the collision step once a substep, against the exact order's reference
                once = replace(body, dynamic={**flags, "--collide-once": True})
                cols = dict(sdf=n, friction=fric, planes="off", once="on")
                out.append(Variant("body", f"SDF {n}³, friction on, colliding once", once, cols, ref_scene=exact))
    return out


def _collider_line(line, sdf, friction):
    """A line of a colliders file with a mesh's n_s set to `sdf` and, without `friction`, its μ removed."""
    code, _, comment = line.partition("#")
    words = code.split()
    if not words:
        return line
    if words[0] == "mesh":
        words[3] = str(sdf)
    if not friction:
        keep, i = [], 0
        while i < len(words):
            if words[i] in ("mu_s", "mu_k"):
                i += 2
                continue
            keep.append(words[i])
            i += 1
        words = keep
    return " ".join(words) + (f"   # {comment.strip()}" if comment.strip() else "")


def _run(scene, path, plan, precision, substeps):
    """One checked run of a variant into `path` (one thread: the runs go on in parallel)."""
    s = scene.with_overrides(strands=plan.strands, precision=precision)
    frames = max(1, round(plan.seconds / float(s.dynamic.get("--frame-dt", 1 / 60))))
    s = replace(s, dynamic={**s.dynamic, "--frames": frames, "--substeps": substeps, "--output-every": 1})
    runner.run_binary(binary_path("cpu"), runner.run_flags(s, "cpu", threads=1, output=path), timeout=600)
    return path


def _time(scene, plan):
    """The simulate stage's median ms a frame at time_strands strands, one thread (no output file)."""
    s = scene.with_overrides(strands=plan.time_strands)
    s = replace(s, dynamic={**s.dynamic, "--frames": plan.time_frames})
    rec = runner.run_binary(binary_path("cpu"), runner.run_flags(s, "cpu", threads=1, repeat=1), timeout=600)
    return float(next(st for st in rec["stages"] if st["stage"] == "simulate")["median_ms"])


def _gpu_time(scene, plan, variant):
    """The simulate stage's median ms a frame on the default cuda build's `variant`, gpu_strands strands."""
    s = scene.with_overrides(strands=plan.gpu_strands)
    s = replace(s, dynamic={**s.dynamic, "--frames": plan.time_frames})
    rec = runner.run_binary(binary_path("cuda"), runner.run_flags(s, "cuda", variant=variant, repeat=1), timeout=600)
    return float(next(st for st in rec["stages"] if st["stage"] == "simulate")["median_ms"])


def gpu_variants(todo, plan, log=print):
    """Per variant, the default cuda build's fastest variant that runs it (None: not timed on a GPU)."""
    if plan.gpu == "no":
        return [None] * len(todo)
    usable, why = env.gpu_status()
    if not usable or not binary_path("cuda").exists():
        log(f"accuracy-world: no GPU rows: {why if not usable else 'hairsim-cuda is not built'}")
        return [None] * len(todo)
    decl = variants.declared("cuda")
    return [variants.fastest(decl, v.scene.points, variants.features_of(v.scene.dynamic)) for v in todo]


def timed(todo, plan, tick=lambda: None, on_gpu=None):
    """([variant][round] ms a frame on the CPU, the same on the GPU where `on_gpu` names a variant):
    `plan.repeat` rounds, each timing every variant once in turn."""
    on_gpu = on_gpu or [None] * len(todo)
    times, gpu = [[] for _ in todo], [[] for _ in todo]
    for _ in range(plan.repeat):
        for k, v in enumerate(todo):
            times[k].append(_time(v.scene, plan))
            if on_gpu[k]:
                gpu[k].append(_gpu_time(v.scene, plan, on_gpu[k]))
            tick()
    return times, gpu


def _observed(path):
    """(positions of every simulated frame [F][N][P][3], L, the last frame's volume observables,
    the worst frame's penetration and stretch)."""
    with open_trajectory(path) as t:
        x = np.stack([t.frame(f).astype(np.float64).reshape(t.n_strands, t.points, 3) for f in t.simulated])
        vol = hair_volume.frame_volume(t, t.simulated[-1])
        obs = t.observables
        worst = float(obs["penetration_max"].max()), float(obs["stretch_max"].max())
        return x, float(t.hair_length), vol, worst


def measure_variant(v, plan, scratch):
    """A variant's CSV row but its cost (ms_frame, cost_ratio: measure times the variants one after
    another, once every checked run is done, so that no timed run shares the cores)."""
    mode = _run(v.scene, scratch / "mode.h5", plan, "fp32", int(v.scene.dynamic.get("--substeps", 1)))
    ref = _run(v.ref_scene or v.scene, scratch / "ref.h5", plan, "fp64", plan.ref_substeps)
    x, L, vol, (pen, stretch) = _observed(mode)
    xr, _, vol_r, (pen_r, stretch_r) = _observed(ref)
    rms, mx = frame_errors(x, xr, L)
    return {
        "group": v.group,
        "variant": v.name,
        **{k: v.columns.get(k, "") for k in ("grid", "rebuild", "friction", "volume", "sdf", "planes", "once")},
        "strands": plan.strands,
        "frames": len(x),
        "substeps": v.scene.dynamic.get("--substeps", 1),
        "iterations": v.scene.dynamic.get("--iterations", 1),
        "ref_substeps": plan.ref_substeps,
        "time_strands": plan.time_strands,
        "rms_err_L": float(np.nanmean(rms)),
        "max_err_L": float(np.nanmax(mx)),
        "hair_volume": vol["hair_volume"],
        "hair_volume_ref": vol_r["hair_volume"],
        "envelope": vol["envelope_radius"],
        "envelope_ref": vol_r["envelope_radius"],
        "close_pairs": vol["close_pairs"],
        "close_pairs_ref": vol_r["close_pairs"],
        "penetration_max": pen,
        "penetration_ref": pen_r,
        "stretch_max": stretch,
        "stretch_ref": stretch_r,
    }


def measure(plan, log=print):
    """Every variant's row, in the order of grid_variants then body_variants."""
    check_plan(plan)
    runner.require_binary(binary_path("cpu"))
    with tempfile.TemporaryDirectory(prefix="hb-world-") as tmp:
        tmp = Path(tmp)
        todo = grid_variants(plan) + body_variants(plan, tmp)
        log(f"accuracy-world: {len(todo)} variants, {plan.strands} strands, {plan.seconds:g} s, "
            f"reference S = {plan.ref_substeps} fp64; cost at {plan.time_strands} strands")  # fmt: skip

        def one(k):
            d = tmp / f"v{k}"
            d.mkdir()
            try:
                return measure_variant(todo[k], plan, d)
            finally:
                shutil.rmtree(d, ignore_errors=True)

        rows = []
        with Progress((1 + plan.repeat) * len(todo), "accuracy-world") as bar:
            with ThreadPoolExecutor(plan.jobs or env.usable_cores()) as pool:
                for row in pool.map(one, range(len(todo))):
                    rows.append(row)
                    bar.update()
            on_gpu = gpu_variants(todo, plan, log)
            cpu_ms, gpu_ms = timed(todo, plan, bar.update, on_gpu)
            for row, ms, g, v in zip(rows, cpu_ms, gpu_ms, on_gpu):
                row.update(ms_frame=float(np.median(ms)), ms_min=min(ms), ms_max=max(ms))
                if g:
                    row.update(gpu_variant=v, gpu_strands=plan.gpu_strands, gpu_ms_frame=float(np.median(g)))
    for r in rows:  # the cost over the same scene without the feature
        off = next(o for o in rows if o["group"] == r["group"] and o["variant"] == "off")
        r["cost_ratio"] = r["ms_frame"] / off["ms_frame"] if off["ms_frame"] > 0 else float("nan")
        if r.get("gpu_ms_frame") and off.get("gpu_ms_frame"):
            r["gpu_cost_ratio"] = r["gpu_ms_frame"] / off["gpu_ms_frame"]
    return rows


def run_study(plan, out_dir=None, log=print):
    """Measure; write world.csv and env.json into out_dir (results/accuracy-world); the CSV's path."""
    out_dir = Path(out_dir or RESULTS / RESULTS_NAME)
    if out_dir.exists() and not out_dir.is_dir():
        raise HarnessError(f"accuracy-world: --out {out_dir} is not a directory", code=2)
    check_plan(plan)
    rows = measure(plan, log)
    path = files.write_csv(out_dir / CSV_NAME, COLUMNS, rows)
    files.write_json(out_dir / "env.json", dict(env.collect(), plan={k: getattr(plan, k) for k in COLUMNS_PLAN}))
    log(f"accuracy-world: wrote {display(path)}")
    return path


COLUMNS_PLAN = ("strands", "seconds", "ref_substeps", "grid_sizes", "rebuilds", "sdf_sizes", "contact_margins",
                "time_strands", "time_frames", "repeat", "gpu", "gpu_strands")  # fmt: skip
