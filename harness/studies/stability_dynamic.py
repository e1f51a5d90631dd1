"""`python -m harness stability`: where the dynamic model is stable, the measuring part
(render/stability_dynamic_report.py renders it).

A map, not anecdotes: 2-D slices through the dynamic scene space (substeps against wind
speed, stretch compliance, bend compliance and points per strand; head-motion frequency
against amplitude; long-range attachments on and off against a fast nod's frequency and
against wind speed, at one iteration), each run for both solvers and both precisions, on the CPU and, where a
GPU answers, on every CUDA build that is built (on each, the fastest variant that runs the
cell: variants.fastest). Every cell is one run of a few strands over a horizon of
about one second (strands are independent, so a few show what many would); its verdict,
from the per-frame observables of the file (docs/model.md §3.8) and the bounds of
harness/core/tolerances.py:

  diverged        some frame has a blown-up strand and the run ends with a NaN or Inf
  escaped         some frame has a point farther from its root than twice the strand's hanging
                  length (`hanging_length`: L, or for a soft xpbd chain L plus its static
                  stretch under its own weight) and every number of the last frame is finite:
                  large but bounded, e.g. iteration-starved. A soft chain that settles beyond 2L
                  but within that is the physics of its springs, not an escape: it is judged
                  by its stretch like any cell (docs/model.md §3.8's blown-up count stays the
                  file's, in blown_up_frames)
  penetrating     penetration_max > STABILITY_PENETRATION_REL · R_c in some frame (a slice that
                  starts inside a collider, `settles`: in the last frame, or the last frame's
                  penetration not below the start's)
  over-stretched  stretch_max > STABILITY_STRETCH_MAX in some frame
  ok              none of these
  refused         the binary refused the scene (exit 2); timed out: it did not finish
                  within --timeout; failed: any other failure

(the first that applies). Each cell's last frame also goes through
harness.check.invariants_dynamic; its violations are recorded beside the verdict.

Writes results/stability/stability.csv and env.json, and render/stability_dynamic_report.py draws
report/stability_<slice>.png and writes report/dynamic_stability.md.
"""

import csv
import inspect
import io
import tempfile
import time
from concurrent.futures import ThreadPoolExecutor, as_completed
from dataclasses import replace
from pathlib import Path

import numpy as np

from harness import HarnessError
from harness.check import colliders_dynamic as colliders
from harness.check import invariants_dynamic
from harness.core import env, gpus, inputs, runner, scenes, tolerances, variants
from harness.core.paths import CUDA_BUILDS, RESULTS, binary_path, display
from harness.core.progress import Progress
from harness.io import files
from harness.io.files import write_json
from harness.io.trajectory import open_trajectory
from harness.studies.stability_slices_dynamic import OFF, SLICE_NAMES, SLICES, scene_slice

STRANDS = 16
FRAMES = 60  # one second at the base scenes' Δt = 1/60 s
GPU_CELLS_A_BATCH = 8  # GPU cells one process runs (runner.run_batch); the map's jobs share the GPU

COLUMNS = (
    "slice",
    "backend",
    "build",
    "variant",
    "solver",
    "precision",
    "row_key",
    "row",
    "col_key",
    "col",
    "strands",
    "points",
    "frames",
    "substeps",
    "iterations",
    "stretch_max",
    "penetration_max",
    "penetration_rel",
    "blown_up_frames",
    "first_blown_frame",
    "verdict",
    "violations",
    "wall_s",
    "message",
    "reach",  # the largest distance of a point from its root over any frame, over 2 × hanging_length
    "penetration_start",  # a settling slice's deepest point in a collider at the start (frame 0), cm
    "penetration_last",  # penetration_max of the last frame, cm
)


class Backend(variants.Runner):
    @property
    def label(self):
        return "cpu" if self.backend == "cpu" else f"cuda-{self.build}"


def hanging_length(L, points, gravity, stretch_compliance, solver):
    """The length a strand hangs at under its own weight: L, and for xpbd with a soft stretch
    compliance α_s the static stretch added (segment k carries the P − k unit masses below it, so
    it lengthens by α_s·g0·(P − k); summed, α_s·g0·P(P − 1)/2)."""
    if solver != "xpbd":
        return float(L)
    return float(L) + float(stretch_compliance) * float(gravity) * points * (points - 1) / 2


def verdict(stretch_max, penetration_rel, blown_up_frames, diverged=False, reach=None, settling=None):
    """The verdict of a cell from its worst observables over the horizon (module docstring);
    `diverged`: the last frame holds a NaN or Inf; `reach`: the largest distance of a point from its
    root over twice the hanging length (None: the model's blown-up count decides, as before it);
    `settling`: (start, last frame) penetration over R_c for a cell that starts inside a collider,
    judged instead of the worst frame's."""
    escaped = blown_up_frames > 0 if reach is None else reach > 1.0
    if diverged or escaped:
        return "diverged" if diverged else "escaped"
    if settling is not None:
        start, last = settling
        if last > tolerances.STABILITY_PENETRATION_REL or (last > 0 and last >= start):
            return "penetrating"
    elif penetration_rel > tolerances.STABILITY_PENETRATION_REL:
        return "penetrating"
    if stretch_max > tolerances.STABILITY_STRETCH_MAX:
        return "over-stretched"
    return "ok"


def text(value):
    """An axis value as the CSV and the report write it."""
    return value if isinstance(value, str) else f"{value:g}"


def backends(gpu="auto", log=print):
    """The CPU oracle, and each built CUDA build where a GPU answers, with its variant that
    simulates any point count (a cell runs on the fastest that runs it: cell_backend)."""
    out = [Backend("cpu", "default", variants.declared("cpu").default_variant)]
    if gpu == "no":
        log("stability: GPU builds not run (--gpu no)")
        return out
    usable, why = env.gpu_status()
    if not usable:
        if gpu == "yes":
            raise HarnessError(f"stability: --gpu yes but {why}")
        log(f"stability: GPU builds not run: {why}")
        return out
    for build in CUDA_BUILDS:
        if binary_path("cuda", build).exists():
            out.append(Backend("cuda", build, variants.simulating("cuda", build)))
        else:
            log(f"stability: {display(binary_path('cuda', build))} not built: its cells are not run")
    if gpu == "yes" and len(out) == 1:
        raise HarnessError("stability: --gpu yes but no CUDA binary is built (run make)")
    return out


def cell_scene(slc, row, col, solver, precision, strands, frames):
    """The scene of one cell: the slice's base scene with its fixed changes and the two axis values."""
    base = scenes.load_scene(slc.scene)
    points = None
    dyn = dict(base.dynamic)
    for flag, value in (*slc.fixed, ("--solver", solver), (slc.rows.key, row), (slc.cols.key, col)):
        if flag in ("points", "strands"):
            points, strands = (value, strands) if flag == "points" else (points, value)
        elif value == OFF:  # the feature undeclared, with the flags that need it (--grid: --grid-*)
            dyn = {f: v for f, v in dyn.items() if f != flag and not f.startswith(flag + "-")}
        else:
            dyn[flag] = value
    dyn["--frames"] = frames
    dyn["--output-every"] = 1  # every frame's positions: how far a point reached
    return replace(base.with_overrides(strands=strands, precision=precision, points=points), dynamic=dyn)


def cell_backend(be, declared, slc, row, col, solver, precision, strands, frames):
    """The backend a cell runs on: `be` itself on the CPU; on a CUDA build (`declared`: its
    variants.Declared), its fastest variant that runs the cell (variants.fastest), else `be`'s."""
    if be.backend != "cuda":
        return be
    scene = cell_scene(slc, row, col, solver, precision, strands, frames)
    v = variants.fastest(declared, scene.points, variants.features_of(scene.dynamic), solver, bool(scene.groom))
    return be if v is None else replace(be, variant=v)


def run_cell(slc, row, col, solver, precision, be, strands, frames, timeout=None, gpu=None):
    """Run one cell (`gpu`: a core.gpus.Gpu its child alone sees); return its CSV row."""
    return run_cells([(slc, row, col, solver, precision, be)], strands, frames, timeout, gpu)[0]


def run_cells(jobs, strands, frames, timeout=None, gpu=None):
    """Run cells of one binary in one process (runner.run_batch); their CSV rows in
    order, each row's wall_s the time from the end of the cell before it."""
    be = jobs[0][-1]
    binary = binary_path(be.backend, be.build)
    pin = {"CUDA_VISIBLE_DEVICES": gpu.select} if gpu is not None else None
    with tempfile.TemporaryDirectory(prefix="hb-stab-") as tmp:
        cells = [_cell_run(*job, strands, frames, Path(tmp) / f"cell{k}.h5") for k, job in enumerate(jobs)]
        flags = [f for _, f, _ in cells]
        rows = []
        t0 = time.perf_counter()
        for i, _, error in runner.run_batch(binary, flags, timeout=timeout, env=pin):
            out, _, path = cells[i]
            rows.append(_cell_row(out, path, error, jobs[i][0].settles))
            out["wall_s"] = time.perf_counter() - t0
            t0 = time.perf_counter()
            path.unlink(missing_ok=True)
    return rows


def _cell_run(slc, row, col, solver, precision, be, strands, frames, path):
    """(the cell's row as far as it is known before the run, its flags, its output file)."""
    scene = cell_scene(slc, row, col, solver, precision, strands, frames)
    out = {
        "slice": slc.name,
        "backend": be.backend,
        "build": be.build,
        "variant": be.variant,
        "solver": solver,
        "precision": precision,
        "row_key": slc.rows.key,
        "row": text(row),
        "col_key": slc.cols.key,
        "col": text(col),
        "strands": strands,
        "points": scene.points,
        "frames": frames,
        "substeps": scene.dynamic.get("--substeps", 1),
        "iterations": scene.dynamic.get("--iterations", 1),
        "violations": "",
        "message": "",
    }
    flags = runner.run_flags(
        scene, be.backend, variant=be.variant, threads=1 if be.backend == "cpu" else None, output=path
    )
    return out, flags, path


def _cell_row(out, path, error, settles=False):
    """The cell's row: its verdict from the run's file, or from its error (`settles`: the slice
    starts inside a collider)."""
    if error is not None:
        why = "timed out" if isinstance(error, runner.TimedOut) else "refused" if error.code == 2 else "failed"
        out.update(verdict=why, message=str(error))
        return out
    with open_trajectory(path) as t:
        obs = t.observables
        stretch = float(obs["stretch_max"].max())
        pen = float(obs["penetration_max"].max())
        blown = obs["blown_up_strands"].to_numpy() > 0
        rep = invariants_dynamic.check(t, exact=invariants_dynamic.is_reference_build(t), paper=False)
        rel = pen / t.collide_radius
        diverged = not (np.isfinite(t.frame(-1)).all() and np.isfinite(t.velocity(-1)).all())
        p = t.dynamic_params
        hang = hanging_length(t.hair_length, t.points, p.get("gravity", 981.0), p.get("stretch_compliance", 0.0),
                              t.solver)  # fmt: skip
        reach = _reach(t) / (2.0 * hang)
        last = float(obs["penetration_max"].iloc[-1])
        start = _start_depth(t) if settles else None
        settling = (start / t.collide_radius, last / t.collide_radius) if settles else None
    out.update(
        stretch_max=stretch,
        penetration_max=pen,
        penetration_rel=rel,
        blown_up_frames=int(blown.sum()),
        first_blown_frame=int(blown.argmax()) + 1 if blown.any() else "",
        reach=reach,
        penetration_start=start if settles else "",
        penetration_last=last,
        verdict=verdict(stretch, rel, int(blown.sum()), diverged, reach, settling),
        violations="+".join(sorted({v.invariant for v in rep.violations})),
    )
    return out


def _start_depth(t):
    """The deepest non-root point inside a collider of the file in its first stored state (frame 0,
    before any substep), cm; 0 where none is inside."""
    x = t.frame(0).astype(np.float64).reshape(t.n_strands, t.points, 3)[:, 1:].reshape(-1, 3)
    d = colliders.depths(t, x, float(t.time[0]))
    d = d[np.isfinite(d)]
    return max(0.0, float(d.max())) if d.size else 0.0


def _reach(t):
    """The largest distance of a non-root point from its root over the simulated frames (finite ones)."""
    worst = 0.0
    for f in t.simulated:
        x = t.frame(f).astype(np.float64)
        with np.errstate(invalid="ignore", over="ignore"):
            d = np.linalg.norm(x[:, 1:] - x[:, :1], axis=-1)
        d = d[np.isfinite(d)]
        worst = max(worst, float(d.max()) if d.size else 0.0)
    return worst


def cells(slices, quick):
    """(slice, row, col) of every cell, in the order the report draws them."""
    for slc in slices:
        rows = slc.rows.quick if quick else slc.rows.values
        cols = slc.cols.quick if quick else slc.cols.values
        for r in rows:
            for c in cols:
                yield slc, r, c


def measure(
    slices=SLICE_NAMES,
    scene=None,
    quick=False,
    strands=STRANDS,
    frames=FRAMES,
    jobs=None,
    gpu="auto",
    timeout=None,
    log=print,
    shard=None,
):
    """Run the map; return (rows, backends run, seconds)."""
    unknown = [s for s in slices if s not in SLICE_NAMES]
    if unknown:
        raise HarnessError(f"stability: unknown slice(s) {', '.join(unknown)} (known: {', '.join(SLICE_NAMES)})")
    chosen = [s for s in SLICES if s.name in slices]
    if scene is not None:  # a user's scene: its own substeps × iterations slice instead
        base = scenes.load_scene(scene)
        if base.model != "dynamic":
            raise HarnessError(f"stability: --scene {scene} is not a dynamic scene", code=2)
        chosen = [scene_slice(scene)]
    bes = backends(gpu, log)
    declared = {be: variants.declared(be.backend, be.build) for be in bes}  # solvers, precisions
    todo = [
        (slc, r, c, solver, precision, cell_backend(be, declared[be], slc, r, c, solver, precision, strands, frames))
        for be in bes
        for slc, r, c in cells(chosen, quick)
        for solver in declared[be].dynamic_solvers
        for precision in declared[be].precisions
    ]
    if shard is not None:  # a share of the cells (harness merge joins the shards' rows)
        todo = shard.share(todo)
    jobs = jobs or env.usable_cores()
    log(
        f"stability: {len(todo)} cells ({len(chosen)} slice(s) × solvers × precisions × {len(bes)} backend(s)), "
        f"{strands} strands, {frames} frames, {jobs} jobs"
    )
    # nothing here is timed: with several GPUs the GPU cells take them in turn
    spread = gpus.visible() if any(job[-1].backend == "cuda" for job in todo) else []

    def gpu_for(i, job):
        return spread[i % len(spread)] if len(spread) > 1 and job[-1].backend == "cuda" else None

    if len(spread) > 1:
        log(f"stability: GPU cells spread over {len(spread)} GPUs")

    def counted(cells, strands, frames, timeout, gpu):
        """run_cells, its time counted as work of the GPU it ran on (the first where not spread)."""
        on = gpu or (spread[0] if spread and cells[0][-1].backend == "cuda" else None)
        with gpus.working(on):
            return run_cells(cells, strands, frames, timeout, gpu)

    t0 = time.perf_counter()
    weight = [cell_weight(job, strands, frames) for job in todo]
    bar = Progress(len(todo), "stability", work=sum(weight))  # the estimate by the cells' weights
    # the heaviest cells (most substep iterations a frame, GPU before CPU) start first, so that
    # none is left running alone at the end; the rows keep the order of `todo`. A GPU cell runs
    # with others of its binary and GPU in one process (a context made once a batch).
    order = sorted(range(len(todo)), key=lambda i: -weight[i])
    units = [[i] for i in order if todo[i][-1].backend != "cuda"]
    gpu_cells = [i for i in order if todo[i][-1].backend == "cuda"]
    units += runner.batches(gpu_cells, lambda i: (todo[i][-1], gpu_for(i, todo[i])), GPU_CELLS_A_BATCH)
    units.sort(key=lambda u: -weight[u[0]])
    rows = [None] * len(todo)
    with ThreadPoolExecutor(max_workers=jobs) as pool:
        futures = {}
        for u in units:
            f = pool.submit(counted, [todo[i] for i in u], strands, frames, timeout, gpu_for(u[0], todo[u[0]]))
            futures[f] = u
        for f in as_completed(futures):
            u = futures[f]
            for i, row in zip(u, f.result()):
                rows[i] = row
            bar.update(len(u), work=sum(weight[i] for i in u))
    bar.close()
    return rows, bes, time.perf_counter() - t0


def cell_weight(job, strands, frames):
    """A cell's expected cost, for the order the map starts its cells in: substeps ×
    iterations × points × strands (GPU cells count double: they share one device)."""
    slc, r, c, solver, precision, be = job
    scene = cell_scene(slc, r, c, solver, precision, strands, frames)

    def number(flag):
        try:
            return float(scene.dynamic.get(flag, 1))
        except (TypeError, ValueError):
            return 1.0

    work = number("--substeps") * number("--iterations") * scene.points * scene.strands / strands
    return work * (2.0 if be.backend == "cuda" else 1.0)


def write_csv(rows, path):
    """rows → CSV, written beside and renamed, so no partial file is left."""
    return files.write_csv(path, COLUMNS, rows, extrasaction="ignore")


# what a map measured in several calls (run_study's `add`) must share with the map it adds to
SAME_MAP = ("git_revision", "device", "cpu_model", "quick", "strands", "frames", "backends")


def _earlier(out_dir, info):
    """(rows, env) of the map in out_dir that a call with `info` (env.json's fields) adds slices to;
    refused in one line where there is none or it was measured otherwise."""
    csv_path, env_path = out_dir / "stability.csv", out_dir / "env.json"
    if not (csv_path.exists() and env_path.exists()):
        raise HarnessError(
            f"stability: --add: no map in {display(out_dir)} to add to (stability.csv, env.json)", code=2
        )
    old = inputs.read_json(env_path, "stability: --add:")
    if not isinstance(old, dict):
        raise HarnessError(f"stability: --add: {display(env_path)} is not a map's env.json", code=2)
    differ = [k for k in SAME_MAP if old.get(k) != info.get(k)]
    if differ:
        raise HarnessError(
            f"stability: --add: {display(out_dir)} was measured with another {', '.join(differ)}", code=2
        )
    rows = list(csv.DictReader(io.StringIO(inputs.read_text(csv_path, "stability: --add:"))))
    if any("slice" not in r for r in rows[:1]):
        raise HarnessError(f"stability: --add: {display(csv_path)} is not a map's stability.csv", code=2)
    return rows, old


def _joined(earlier, rows, slices, old_env, info):
    """The earlier map's rows of the slices not measured again (`slices`), then the new rows, in
    SLICES' order; env.json with every call's slices, revision, date and seconds under `parts`."""
    names = {r["slice"] for r in rows} | set(slices)
    order = {s.name: i for i, s in enumerate(SLICES)}
    kept = [r for r in earlier if r["slice"] not in names]
    joined = sorted(kept + rows, key=lambda r: order.get(r["slice"], len(order)))  # stable within a slice
    parts = old_env.get("parts") or [
        {k: old_env.get(k) for k in ("date", "git_revision", "seconds")}
        | {"slices": sorted({r["slice"] for r in earlier})}
    ]
    parts = [dict(p, slices=[s for s in p["slices"] if s not in names]) for p in parts]
    parts = [p for p in parts if p["slices"]]
    parts.append({"slices": sorted(names), **{k: info[k] for k in ("date", "git_revision", "seconds")}})
    return joined, dict(info, seconds=round(sum(p["seconds"] or 0 for p in parts), 1), parts=parts)


def run_study(out_dir=None, add=False, **options):
    """Measure the slices (`options`: those of measure()); write stability.csv and env.json into
    out_dir (the renderer, render/stability_dynamic_report.py, draws them) and return the CSV's path.
    `add`: the slices replace or join those of the map already in out_dir (measured at the same
    revision, machine and size), so a map can be measured over several calls."""
    out_dir = Path(out_dir or RESULTS / "stability")
    bound = inspect.signature(measure).bind(**options)
    bound.apply_defaults()
    opt = bound.arguments
    if add:  # refuse before measuring
        _earlier(out_dir, _info(opt, backends(opt["gpu"], lambda _: None), 0.0))
    rows, bes, seconds = measure(**opt)
    info = _info(opt, bes, seconds)
    if add:
        earlier, old_env = _earlier(out_dir, info)
        rows, info = _joined(earlier, rows, () if opt["scene"] else opt["slices"], old_env, info)
    csv_path = write_csv(rows, out_dir / "stability.csv")
    env_path = out_dir / "env.json"
    write_json(env_path, info)
    opt["log"](
        f"stability: {len(rows)} cells in {info['seconds']:.1f} s; wrote {display(csv_path)} and {display(env_path)}"
    )
    return csv_path


def _info(opt, bes, seconds):
    """env.json's fields of a call."""
    return dict(
        env.collect(),
        quick=opt["quick"],
        strands=opt["strands"],
        frames=opt["frames"],
        jobs=opt["jobs"] or env.usable_cores(),
        seconds=round(seconds, 1),
        backends=[b.label for b in bes],
        stretch_bound=tolerances.STABILITY_STRETCH_MAX,
        penetration_bound_rel=tolerances.STABILITY_PENETRATION_REL,
        shard=str(opt["shard"]) if opt["shard"] else None,
    )
