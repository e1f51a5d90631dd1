"""The frame budget's throughput curves (docs/harness.md, "A frame budget"): the modes of the
speed-against-accuracy study that a budget can pick (the bench passes each device's Pareto
front), each timed at a ladder of strand counts by the stopping rule (core/rounds.py), so that a
budget's answer at N strands comes from the mode's own measured curve
(render/frame_budget_dynamic.py). Measuring only; writes <root>/budget-curves[-<scene>]/curves.csv
and env.json.

A mode is a dict of the study's columns (mode, backend, build, variant, solver, ftl_damping,
substeps, iterations, precision). The ladder: LADDER strand counts, CPU modes up to CPU_MAX,
smallest first; with a `gate` (core.budget.TierGate) a size whose estimate does not fit is
left out with every larger one, as the sweeps do.
"""

import time
from pathlib import Path

from harness.core import env, rounds, runner, scenes, timing
from harness.core.paths import binary_path, display, output_dir
from harness.core.progress import Progress
from harness.io.files import write_csv, write_json
from harness.studies.accuracy import CURVES_CSV, MODE_COLUMNS, curves_name
from harness.studies.accuracy_dynamic import configured

LADDER = (1_000, 10_000, 100_000, 1_000_000)
CPU_MAX = 100_000  # the dynamic sweep's CPU rows stop there too (a frame of about a second)
FRAMES = 1
COLUMNS = (
    *MODE_COLUMNS,
    "median_ms",
    "min_ms",
    "max_ms",
    *timing.Figure().columns(),
    "device",
    "error",
)


def _flags(scene, mode, strands, repeat):
    sc = configured(
        scene,
        solver=mode["solver"],
        substeps=mode["substeps"],
        iterations=mode["iterations"],
        precision=mode["precision"],
        frames=FRAMES,
        strands=strands,
        ftl_damping=mode.get("ftl_damping"),
    )
    return runner.run_flags(sc, mode["backend"], variant=mode["variant"], repeat=repeat)


def sizes(mode, most=None):
    """The ladder's strand counts for a mode (a groom file: up to its strands, `most`)."""
    top = CPU_MAX if mode["backend"] == "cpu" else LADDER[-1]
    out = [n for n in LADDER if n <= top and (most is None or n <= most)]
    return out or [most]


def measure(root, scene_ref, modes, rule=None, gate=None, log=print, most=None):
    """Time every mode at its ladder's sizes by `rule` (default timing.RULE); write and return the
    rows (one per mode and size)."""
    rule = rule or timing.RULE
    scene = scenes.load_scene(scene_ref)
    out = output_dir(Path(root) / curves_name(scene_ref))
    cases = [(m, n) for m in modes for n in sizes(m, most)]
    by_size = {}
    for c in cases:
        by_size.setdefault(c[1], []).append(c)
    rows = []
    with Progress(len(cases), f"budget curves {scene.name}") as bar:
        for n in sorted(by_size):
            tier = by_size[n]
            if gate is not None:
                fits, why = gate.admit(n, len(tier))
                if not fits:
                    log(f"harness: budget curves: {len(tier)} case(s) at {n} strands {why}")
                    bar.update(len(tier))
                    continue
            t0 = time.monotonic()
            timed = rounds.measure(
                tier,
                lambda c, r: _flags(scene, c[0], c[1], r),
                lambda c: binary_path(c[0]["backend"], c[0]["build"]),
                rule=rule,
                batch=1 if tier[0][0]["backend"] == "cpu" else runner.BATCH_MAX,
            )
            for (m, _), t in zip(tier, timed):
                rows.append(_row(m, n, scene, t))
                bar.update()
            if gate is not None:
                sampled = sum(f.stats["total_s"] for t in timed for f in t.figures.values())
                gate.measured(n, len(tier), time.monotonic() - t0, sampled)
    write_csv(out / CURVES_CSV, COLUMNS, rows)
    write_json(out / "env.json", {"scene": scene_ref, "rule": rule.as_dict(), "host": env.collect()})
    log(f"harness: budget curves: {len(rows)} rows in {display(out / CURVES_CSV)}")
    return rows


def _row(mode, strands, scene, t):
    row = {k: mode.get(k) for k in COLUMNS[:9]}
    row.update(strands=strands, points=scene.points)
    if t.error is not None:
        return {**row, "error": str(t.error)}
    sim = [i for i, s in enumerate(t.record["stages"]) if s.get("stage") == "simulate"]
    st = t.record["stages"][sim[0]]
    fig = t.figures.get(sim[0]) or timing.Figure(st.get("times_ms") or [])
    return {
        **row,
        "median_ms": st["median_ms"],
        "min_ms": st["min_ms"],
        "max_ms": st["max_ms"],
        **fig.columns(),
        "device": t.record.get("device"),
        "error": "",
    }
