"""`harness bench` (`make bench`): the pipeline's order, the run folder it claims and what it
records beside the steps (host load, budget, shard record, steps.json); the steps are
bench/paper.py's, bench/dynamic.py's and bench/scene.py's."""

from pathlib import Path

from harness import HarnessError
from harness.bench import dynamic as bench_dynamic
from harness.bench import merge
from harness.bench import paper as bench_paper
from harness.bench import steps as bench_steps
from harness.core import budget, load, shards
from harness.core.paths import LOCAL_RUN, binary_path, output_dir
from harness.core.progress import StepTimes
from harness.core.runner import require_binary
from harness.io import runfolder
from harness.io.files import write_json
from harness.io.sweepfile import load_sweep
from harness.studies.host_verdicts import HOST_JSON


def run(
    model="all",
    sweep="default",
    out=None,
    gpu="auto",
    report_dir=None,
    budget_spec=None,
    shard_spec=None,
    full_studies=False,
    force=False,
    scene=None,
):
    """Check the binaries, validate every GPU variant against the CPU (fail before timing), run the
    sweeps and studies of `model`, then plot and report; the exit status."""
    # one run folder (docs/decisions/bench-runs.md): the paper sweep in ROOT/sweep, the dynamic
    # bench's folders beside it, the report in ROOT/report; nothing tracked is written
    plan = budget.Budget(budget.parse_duration(budget_spec), reserve=budget.REPORT_RESERVE_S) if budget_spec else None
    if scene:  # the dynamic studies on the user's own scene, in its own folder (bench/scene.py)
        from harness.bench import scene as bench_scene

        given = [f for f, v in (("--model", model != "all"), ("--sweep", sweep != "default"),
                                ("--shard", shard_spec)) if v]  # fmt: skip
        if given:
            raise HarnessError(f"bench --scene runs the dynamic studies on that scene alone: drop {', '.join(given)}")
        quick = not full_studies
        return bench_scene.run(scene, out, gpu, report_dir, quick_studies=quick, budget=plan)
    root = Path(out) if out else LOCAL_RUN
    report_dir = Path(report_dir) if report_dir else root / "report"
    shard = shards.parse(shard_spec) if shard_spec else None
    runfolder.claim(root, "bench", force=force)  # before anything is measured or written
    sweeps = {}
    if model in ("all", "paper"):
        sweeps["paper"] = load_sweep(sweep).path
    if model in ("all", "dynamic"):
        sweeps["dynamic"] = load_sweep(bench_dynamic.SWEEP).path
        sweeps["dynamic-curly"] = load_sweep(bench_dynamic.CURLY_SWEEP).path
    require_binary(binary_path("cpu"))  # before the run's folder is made
    # the host's load before anything runs: the top of the run's reports says whether it was quiet
    write_json(output_dir(root) / HOST_JSON, load.host_load())
    if plan:
        print(
            f"harness: budget {plan.seconds:.0f} s: the sweeps' largest sizes and the studies are left out "
            "where they do not fit",
            flush=True,
        )
    if shard:
        command = f"bench --model {model} --sweep {sweep}" + (" --full-studies" if full_studies else "")
        merge.write_record(root, shard, sweeps, command)
    # both models are validated before anything is timed; under a budget the validations are
    # its fixed cost and the sweeps and studies share what they leave
    gpu_list = bench_steps.node_gpus(gpu)
    times = StepTimes(on_step=lambda t: bench_steps.write(root, t, gpu_list))  # the log's last line, steps.json
    if model in ("all", "paper"):
        times.step("validation", bench_paper.validate_first, sweep, out=root / "sweep", gpu=gpu)
    if model in ("all", "dynamic"):
        times.step("dynamic validation", bench_dynamic.validate_first, out=root, gpu=gpu)
    if plan:
        budget.say_fixed_cost(plan)
    code = 0
    if model in ("all", "paper"):
        code = times.step(
            f"sweep {load_sweep(sweep).name} and its report",
            bench_paper.run,
            sweep,
            out=root / "sweep",
            gpu=gpu,
            report_dir=report_dir,
            shard=shard,
            budget=plan,
            root=root,
            validated=True,
        )
    if model in ("all", "dynamic"):
        code = (
            bench_dynamic.run(
                out=root,
                gpu=gpu,
                report_dir=report_dir,
                quick_studies=not full_studies,
                shard=shard,
                budget=plan,
                validated=True,
                times=times,
            )
            or code
        )
    if plan and model == "all" and not (shard and shard.n > 1):
        from harness.render import report_paper

        report_paper.build(root / "sweep", report_dir)  # again: its time-budget section now lists the dynamic part too
    if shard:
        merge.finish_record(root)  # the shard finished: merge takes it, with the cases it holds
    print("\n".join([*bench_steps.gpu_lines(times, gpu_list), times.summary("bench")]), flush=True)
    return code
