"""OUT/report/scene.md: the report of `make bench SCENE=my.toml` (bench/scene.py), rendered from its
run folder: the host's load, the budget, the validation on the scene, its throughput over strand
counts, speed against accuracy (its own page beside this one), the frame budget's table, and the
stability map over the scene. Rendering only: every number comes from the run's files."""

import json
import os
from pathlib import Path

from harness.core import scenes
from harness.core.paths import display
from harness.io import files
from harness.render import accuracy_dynamic_report, budget_report, host_report, report_dynamic
from harness.render import frame_budget_dynamic as frame_budget
from harness.render import stability_dynamic_report as stability_report
from harness.studies.accuracy import results_name

PAGE = "scene.md"
SWEEP_DIR = "sweep"  # bench/scene.py's throughput sweep


def throughput_lines(root, out_dir):
    sweep_dir = Path(root) / SWEEP_DIR
    lines = ["## Throughput over strand counts", ""]
    if not (sweep_dir / "runs.csv").exists():
        return lines + [f"Not measured (no `{display(sweep_dir / 'runs.csv')}`).", ""]
    rows, env = report_dynamic.sim_rows(sweep_dir)
    pics = [report_dynamic.throughput_plot(rows, s, p, out_dir) for s in ("xpbd", "ftl") for p in ("fp32", "fp64")]
    lines += [
        "Time per frame of the scene's own settings (configs/sweeps/dynamic.toml's axes on it), timed by the "
        "stopping rule (core/timing.py); the best of each family per strand count:",
        "",
        *report_dynamic.best_table(rows),
        "",
    ]
    lines += [f"![{p.stem}]({os.path.relpath(p, out_dir)})" for p in pics if p] + [""]
    sess = (env.get("sessions") or [{}])[-1]
    host = sess.get("host") or sess
    where = {k: host.get(k) for k in ("cpu_model", "cpu_cores", "gpus", "git_revision") if k in host}
    return lines + [f"Sweep environment: {json.dumps(where)}", ""]


def build(root, scene_ref, report_dir):
    """Write report_dir/scene.md (and the accuracy study's page and the plots) and return its path."""
    root, out_dir = Path(root), Path(report_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    scene = scenes.load_scene(scene_ref)
    lines = [
        f"# hairbench: {scene.name}",
        "",
        f"{scene.description or 'A dynamic scene'} (`{scene.file or scene_ref}`): the dynamic model's studies on "
        f"this scene, by `make bench SCENE={scene_ref}` (`python -m harness bench --scene`) into "
        f"`{display(root)}`; rendering only. `python -m harness budget --scene {scene_ref} --run {display(root)} "
        "--strands N --frame-ms B` answers for another budget.",
        "",
        *host_report.section(root),
        *budget_report.section(root),
        "## Validation",
        "",
        *report_dynamic.validation_lines(root / SWEEP_DIR, what=f"this scene ({scene.name})"),
        "",
        *throughput_lines(root, out_dir),
        *accuracy_dynamic_report.section(root / results_name(scene_ref), out_dir, scene=scene_ref, title=scene.name),
        *frame_budget.section(root, scene_ref),
    ]
    if (root / "stability" / "stability.csv").exists():
        lines += stability_report.section(root / "stability", out_dir) + [""]
    else:
        lines += ["## Stability", "", f"Not measured (no `{display(root / 'stability' / 'stability.csv')}`).", ""]
    path = out_dir / PAGE
    return files.write_text(path, "\n".join(lines).rstrip("\n") + "\n")
