"""`bench`: the make bench pipeline (its steps are harness/bench/'s)."""

from harness.cli.options import (
    FORCE_FOLDER_HELP,
    GPU_HELP,
    case_options,
    command,
    options,
    output_options,
)


def cmd_bench(args):
    """Check the binaries, validate every GPU variant against the CPU (fail before timing), run the sweep, then
    plot and report."""
    from harness.bench import pipeline

    given = options(args, "model sweep out gpu report_dir full_studies scene")
    return pipeline.run(budget_spec=args.budget, shard_spec=args.shard, force=getattr(args, "force", False), **given)


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
