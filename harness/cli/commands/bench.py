"""`bench`: the make bench pipeline (its steps are harness/bench/'s)."""

from pathlib import Path

from harness import HarnessError
from harness.cli.options import (
    FORCE_FOLDER_HELP,
    GPU_HELP,
    case_options,
    command,
    output_options,
)


def cmd_bench(args):
    """Check the binaries, validate every GPU variant against the CPU (fail before timing), run the sweep, then
    plot and report."""
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
    from harness.render import host_report

    # one run folder (docs/decisions/bench-runs.md): the paper sweep in ROOT/sweep, the dynamic
    # bench's folders beside it, the report in ROOT/report; nothing tracked is written
    plan = budget.Budget(budget.parse_duration(args.budget), reserve=budget.REPORT_RESERVE_S) if args.budget else None
    if args.scene:  # the dynamic studies on the user's own scene, in its own folder (bench/scene.py)
        from harness.bench import scene as bench_scene

        given = [f for f, v in (("--model", args.model != "all"), ("--sweep", args.sweep != "default"),
                                ("--shard", args.shard)) if v]  # fmt: skip
        if given:
            raise HarnessError(f"bench --scene runs the dynamic studies on that scene alone: drop {', '.join(given)}")
        quick = not args.full_studies
        return bench_scene.run(args.scene, args.out, args.gpu, args.report_dir, quick_studies=quick, budget=plan)
    root = Path(args.out) if args.out else LOCAL_RUN
    report_dir = Path(args.report_dir) if args.report_dir else root / "report"
    shard = shards.parse(args.shard) if args.shard else None
    runfolder.claim(root, "bench", force=getattr(args, "force", False))  # before anything is measured or written
    sweeps = {}
    if args.model in ("all", "paper"):
        sweeps["paper"] = load_sweep(args.sweep).path
    if args.model in ("all", "dynamic"):
        sweeps["dynamic"] = load_sweep(bench_dynamic.SWEEP).path
        sweeps["dynamic-curly"] = load_sweep(bench_dynamic.CURLY_SWEEP).path
    require_binary(binary_path("cpu"))  # before the run's folder is made
    # the host's load before anything runs: the top of the run's reports says whether it was quiet
    write_json(output_dir(root) / host_report.HOST_JSON, load.host_load())
    if plan:
        print(
            f"harness: budget {plan.seconds:.0f} s: the sweeps' largest sizes and the studies are left out "
            "where they do not fit",
            flush=True,
        )
    if shard:
        command = f"bench --model {args.model} --sweep {args.sweep}" + (" --full-studies" if args.full_studies else "")
        merge.write_record(root, shard, sweeps, command)
    # both models are validated before anything is timed; under a budget the validations are
    # its fixed cost and the sweeps and studies share what they leave
    gpu_list = bench_steps.node_gpus(args.gpu)
    times = StepTimes(on_step=lambda t: bench_steps.write(root, t, gpu_list))  # the log's last line, steps.json
    if args.model in ("all", "paper"):
        times.step("validation", bench_paper.validate_first, args.sweep, out=root / "sweep", gpu=args.gpu)
    if args.model in ("all", "dynamic"):
        times.step("dynamic validation", bench_dynamic.validate_first, out=root, gpu=args.gpu)
    if plan:
        budget.say_fixed_cost(plan)
    code = 0
    if args.model in ("all", "paper"):
        code = times.step(
            f"sweep {load_sweep(args.sweep).name} and its report",
            bench_paper.run,
            args.sweep,
            out=root / "sweep",
            gpu=args.gpu,
            report_dir=report_dir,
            shard=shard,
            budget=plan,
            root=root,
            validated=True,
        )
    if args.model in ("all", "dynamic"):
        code = (
            bench_dynamic.run(
                out=root,
                gpu=args.gpu,
                report_dir=report_dir,
                quick_studies=not args.full_studies,
                shard=shard,
                budget=plan,
                validated=True,
                times=times,
            )
            or code
        )
    if plan and args.model == "all" and not (shard and shard.n > 1):
        from harness.render import report_paper

        report_paper.build(root / "sweep", report_dir)  # again: its time-budget section now lists the dynamic part too
    if shard:
        merge.finish_record(root)  # the shard finished: merge takes it, with the cases it holds
    print("\n".join([*bench_steps.gpu_lines(times, gpu_list), times.summary("bench")]), flush=True)
    return code


def add_bench(sub):
    b = command(sub, cmd_bench, help="the make bench pipeline: check, validate, sweep, report")
    b.add_argument("--sweep", default="default", help="sweep name in configs/sweeps/ or a path (default: default)")
    b.add_argument(
        "--out",
        help="the run's folder (default results/local): the paper sweep in OUT/sweep, the dynamic bench's "
        "folders (dynamic, featurecost, dynamic-accuracy, dynamic-accuracy-curly, stability, peer) beside it, the "
        "report in OUT/report",
    )
    case_options(b, gpu=GPU_HELP)
    output_options(b, report="where to write the report (default OUT/report)")
    b.add_argument(
        "--model",
        choices=("all", "paper", "dynamic"),
        default="all",
        help="all (default): the paper model's bench, then the dynamic model's; paper or dynamic: one of them",
    )
    b.add_argument(
        "--budget",
        default=None,
        help="a time for the whole bench (600, 90s, 10m, 1h30m): the sweeps run smallest size first and "
        "leave out the sizes whose time, estimated from the sizes measured before, does not fit; the studies "
        "run while time is left; what was left out is in OUT/budget.json and the report",
    )
    b.add_argument(
        "--shard",
        default=None,
        help="K/N: run the K-th of N deterministic shares of the sweeps' cases and the stability map's cells "
        "(the studies measured once dealt out round robin), record OUT/shard.json and write no report; "
        "harness merge joins them",
    )
    b.add_argument(
        "--scene",
        default=None,
        help="a dynamic scene or groom of your own (a .toml path or a name in configs/scenes/): validation, the "
        "throughput sweep, the speed/accuracy study, the frame budget's curves and the stability map on it, into "
        "its own folder (default results/scene-<name>) and report (OUT/report/scene.md); docs/user_scene.md",
    )
    b.add_argument(
        "--full-studies",
        action="store_true",
        help="dynamic: the full accuracy study and stability map (tens of minutes) instead of the "
        "bench's size (accuracy --quick, stability --quick: minutes on a 16-core + H200 node)",
    )
    b.add_argument(
        "--force",
        action="store_true",
        help=FORCE_FOLDER_HELP,
    )
