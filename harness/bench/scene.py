"""`make bench SCENE=my.toml` (`python -m harness bench --scene my.toml`): the dynamic bench's
studies on the user's own scene or groom, in its own run folder (default results/scene-<name>),
with its own report (docs/user_scene.md):

  1. validation: the user's scene on every CPU variant and, with a usable GPU, every CUDA build
     × variant × precision × block size one frame from the CPU's state (bench/dynamic.py's
     DynValidator); nothing is timed unless all are equivalent;
  2. the throughput sweep: configs/sweeps/dynamic.toml's axes on this scene (a groom file's
     strand axis cut at its strand count), timed by the stopping rule;
  3. the speed-against-accuracy study of this scene (accuracy --quick, or the full one);
  4. the frame budget's throughput curves: each backend's Pareto front of (3) timed at a ladder
     of strand counts (studies/budget_curves_dynamic.py), from which `harness budget` answers;
  5. the stability map over this scene (substeps against iterations, studies/stability_dynamic.py);
  6. OUT/report/scene.md (render/report_scene.py).
With --budget the sweep and the curves fit their shares of the time left, and each study runs
while any is left and is stopped when it runs out (core/budget.py), as the default bench does.
"""

from pathlib import Path

from harness import HarnessError
from harness.bench import dynamic as bench_dynamic
from harness.bench.validation import gpu_plan
from harness.core import budget as budgets
from harness.core import load, runner, scenes
from harness.core.budget import TierGate, run_study
from harness.core.paths import binary_path, display, output_dir
from harness.core.progress import StepTimes
from harness.io import grooms, runfolder
from harness.io.files import write_json
from harness.io.sweepfile import load_sweep
from harness.render import accuracy_dynamic_report, report_scene
from harness.render import stability_dynamic_report as stability_report
from harness.studies import budget_curves_dynamic as budget_curves
from harness.studies import stability_dynamic as stability
from harness.studies.accuracy import curves_name, results_name
from harness.studies.host_verdicts import HOST_JSON
from harness.studies.sweep import run_sweep

SWEEP_DIR = "sweep"  # OUT/sweep: the throughput sweep on the scene


def default_out(scene_ref):
    """results/scene-<the scene file's stem>."""
    from harness.core.paths import RESULTS

    return RESULTS / f"scene-{Path(str(scene_ref)).stem}"


def check(scene_ref):
    """The scene, refused in one line where the bench cannot run it: not dynamic, a USD groom
    (convert it: python -m harness groom convert). Returns (scene, its file groom's strands or None)."""
    scene = scenes.load_scene(scene_ref)
    if scene.model != "dynamic":
        raise HarnessError(f"bench --scene {scene_ref}: a paper-model scene; the studies here are the dynamic model's")
    if scene.groom_file and grooms.is_usd(scene.groom_file):
        raise HarnessError(
            f"bench --scene {scene_ref}: its groom is a USD file: convert it first (python -m harness groom convert "
            f"{scene.groom} GROOM.hair) and name the HAIR file in the scene"
        )
    most = grooms.hair_strand_count(scene.groom_file) if scene.groom_file else None
    if scene.groom_file and most is None:
        raise HarnessError(f"bench --scene {scene_ref}: {scene.groom_file} is not a HAIR file")
    return scene, most


def run(scene_ref, out=None, gpu="auto", report_dir=None, quick_studies=True, budget=None, log=None):
    """The bench on one scene (the module's steps) into `out`; 0, or 1 when a sweep case failed."""
    say = log or (lambda m: print(m, flush=True))
    times = StepTimes()
    scene, most = check(scene_ref)
    root = runfolder.claim(Path(out) if out else default_out(scene_ref), f"bench --scene {scene_ref}")
    report_dir = Path(report_dir) if report_dir else root / "report"
    runner.require_binary(binary_path("cpu"))
    write_json(output_dir(root) / HOST_JSON, load.host_load())  # the report's first line
    builds, gpu_note = gpu_plan(gpu)
    if gpu_note:
        say(f"harness: GPU rows skipped: {gpu_note}")
    gpu_use = "auto" if builds else "no"
    strands = min(bench_dynamic.VALIDATION_STRANDS, most) if most else bench_dynamic.VALIDATION_STRANDS
    times.step(
        "validation", bench_dynamic.validate, root / SWEEP_DIR, builds, gpu_note, say, scene=scene_ref, strands=strands
    )
    if budget:
        budgets.say_fixed_cost(budget)
    sweep = load_sweep(bench_dynamic.SWEEP, scene=scene_ref)
    sweep = sweep.at_most(most) if most else sweep
    gate = TierGate(budget.allowance("dynamic sweep")) if budget else None
    _, failed = times.step(
        "sweep", run_sweep, sweep, out=root / SWEEP_DIR, gpu=gpu_use, log=say, announce_skips=False, gate=gate
    )
    if gate and gate.summary():
        budget.leave_out("sweep", gate.summary(), gate.closed)
    acc_dir = root / results_name(scene_ref)

    def measure_accuracy():
        bench_dynamic.accuracy(root, scene_ref, gpu_use, quick_studies, say)
        accuracy_dynamic_report.write(acc_dir, report_dir, title=scene.name)

    if _study(budget, times, say, "accuracy", acc_dir, measure_accuracy):
        curves_gate = TierGate(budget.allowance("budget curves")) if budget else None
        _study(budget, times, say, "budget curves", root / curves_name(scene_ref), lambda: budget_curves.measure(
            root, scene_ref, bench_dynamic.budget_modes(acc_dir), gate=curves_gate, log=say, most=most))  # fmt: skip

    def measure_stability():
        csv_path = stability.run_study(scene=scene_ref, quick=quick_studies, gpu=gpu_use, out_dir=root / "stability")
        stability_report.report_from_csv(csv_path, report_dir=report_dir, log=say)

    _study(budget, times, say, "stability", root / "stability", measure_stability)
    if budget:
        write_json(root / "budget.json", budget.record())
    path = report_scene.build(root, scene_ref, report_dir)
    say(f"harness: report of {scene.name} in {display(path)}")
    say(times.summary("bench"))
    return 1 if failed else 0


def _study(budget, times, say, name, outputs, fn):
    """fn() as a step; under a budget left out when none is left, stopped when it runs out.
    Whether it ran to its end."""
    if budget is not None and budget.left() <= 0:
        budget.leave_out(name, "the whole study", "left out to fit the budget: no time left when it was due")
        say(f"harness: {name}: left out to fit the budget (no time left)")
        return False
    if budget is None:
        times.step(name, fn)
        return True
    return times.step(name, run_study, budget, name, fn, [outputs], say)
