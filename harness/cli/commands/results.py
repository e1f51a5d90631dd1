"""Results folders: `sweep`, `plot`, `report`, `report-dynamic`, `merge`, `compare`."""

import json
import math
import sys
from pathlib import Path

from harness import HarnessError
from harness.cli.options import (
    FORCE_FOLDER_HELP,
    GPU_HELP,
    REPORT_DIR_HELP,
    case_options,
    command,
    output_options,
    real,
)


def cmd_sweep(args):
    """Run every case of a sweep (configs/sweeps/NAME.toml), one row per (case, stage) in results/NAME/runs.csv;
    a killed sweep resumes."""
    from harness.bench import merge
    from harness.core import shards
    from harness.io.sweepfile import load_sweep
    from harness.studies import sweep

    shard = shards.parse(args.shard) if args.shard else None
    if shard:
        from harness.core.paths import RESULTS
        from harness.io import runfolder

        spec = load_sweep(args.sweep)
        out = runfolder.claim(
            args.out if args.out else RESULTS / spec.name, f"sweep {spec.name}", force=getattr(args, "force", False)
        )
        merge.write_record(out, shard, {"sweep": spec.path}, f"sweep {spec.name}")
    out_dir, failed = sweep.run_sweep(
        args.sweep, out=args.out, gpu=args.gpu, shard=shard, force=getattr(args, "force", False)
    )
    if shard:
        merge.finish_record(out_dir)  # the shard finished: merge takes it, with the cases it holds
    return 1 if failed else 0


def cmd_plot(args):
    from harness.render import plots_paper as plots

    for path in plots.make_all(args.results, args.report_dir):
        print(f"wrote {path}")
    return 0


def cmd_report(args):
    from harness.render import report_paper

    path = report_paper.build(args.results, args.report_dir)
    print(f"wrote {path}")
    return 0


def cmd_report_dynamic(args):
    """Write results/local/report/dynamic.md and its plots from the results of the dynamic bench (ROOT/dynamic/,
    featurecost/, dynamic-accuracy/, dynamic-accuracy-curly/, stability/, peer/, headline/): rendering only."""
    from harness.core.paths import display
    from harness.render import report_dynamic

    root = Path(args.root)
    if not root.is_dir():
        raise HarnessError(f"{args.root}: not a directory (a dynamic bench root: dynamic/, featurecost/, ...)", code=2)
    print(f"wrote {display(report_dynamic.build(root, args.report_dir))}")
    return 0


def cmd_merge(args):
    """Join the folders of one run's N shards (bench or sweep --shard K/N) into OUT: the rows of every CSV, the
    sweeps' sessions, every shard's validation. Refused in one line (exit 2), writing nothing, when the shards
    differ in revision, machine, sweep files or command, or one is missing or given twice. Render the result
    with make report REPORT_FROM=OUT."""
    from harness.bench import merge

    merge.merge(args.out, args.shards)
    return 0


def cmd_compare(args):
    """Compare two runs' timings case by case: two run folders (every runs.csv, headline/*.json and the bench's
    steps.json in each) or two files of one kind. Each figure's ratio B/A, and a verdict by the noise rule of
    harness/core/timing.py: within noise when the two figures' bands overlap, else slower or faster. Prints the
    table; --out writes compare.md, .csv, .json and .png. Exit 0, or 1 when a figure is slower beyond
    --fail-above; 2 when nothing could be compared."""
    from harness.check import compare_runs
    from harness.core.paths import display
    from harness.render import compare_report

    comp = compare_runs.compare(args.a, args.b, fail_above=args.fail_above)
    if args.out:
        from harness.io import runfolder

        out = runfolder.claim(args.out, "compare", force=args.force)
        for path in compare_report.write(comp, out):
            print(f"wrote {display(path)}", file=sys.stderr)
    print(json.dumps(comp.record(), indent=1) if args.json else compare_report.markdown(comp), end="")
    return 1 if comp.failed else 0


def add_sweep(sub):
    s = command(sub, cmd_sweep, help="run a sweep file, appending rows to results/NAME/runs.csv")
    s.add_argument("sweep", help="sweep name in configs/sweeps/ (e.g. quick) or a .toml path")
    output_options(s, results="results/<sweep name>")
    case_options(s, gpu=GPU_HELP)
    s.add_argument(
        "--shard",
        default=None,
        help="K/N: run the K-th of N deterministic shares of the cases (harness merge joins them)",
    )
    s.add_argument(
        "--force",
        action="store_true",
        help=FORCE_FOLDER_HELP,
    )


def add_plot_and_report(sub):
    for name, helptext, fn in (
        ("plot", "draw the PNG plots of a results directory", cmd_plot),
        ("report", "write results/local/report/report.md (and its plots)", cmd_report),
    ):
        description = (
            helptext[0].upper()
            + helptext[1:]
            + " (rendering only: Fig. 1/2 come from the hair "
            + ("state the bench leaves in RESULTS/states/, when it is there).")
        )
        q = command(sub, fn, help=helptext, description=description)
        q.add_argument(
            "results",
            nargs="?",
            default="results/local/sweep",
            help="results directory with runs.csv and env.json (default results/local/sweep, the paper "
            "sweep of make bench's run)",
        )
        output_options(q, report=REPORT_DIR_HELP)


def add_report_dynamic(sub):
    rd = command(
        sub,
        cmd_report_dynamic,
        help="write results/local/report/dynamic.md (and its plots) from a dynamic bench root",
    )
    rd.add_argument("root", nargs="?", default="results/local", help="the bench root (default results/local)")
    output_options(rd, report=REPORT_DIR_HELP)


def add_merge(sub):
    mg = command(sub, cmd_merge, help="join shard folders (bench --shard K/N) into one results folder")
    mg.add_argument("out", help="the merged folder to write (must not exist, or be empty)")
    mg.add_argument("shards", nargs="+", help="the shard folders")


def add_compare(sub):
    cp = command(
        sub, cmd_compare, help="is B faster than A, and by more than the noise? (exit 1: slower beyond a ratio)"
    )
    cp.add_argument("a", help="the run before: a run folder (make bench's), a runs.csv or a headline JSON")
    cp.add_argument("b", help="the run after, of the same kind as A")
    cp.add_argument(
        "--fail-above",
        type=real("ratio", "a ratio", lambda v: 1.0 <= v < math.inf, "must be a finite ratio ≥ 1"),
        default=1.05,
        help="exit 1 when a figure slower beyond its noise has B/A above this (default 1.05)",
    )
    cp.add_argument("--out", default=None, help="write compare.md, compare.csv, compare.json, compare.png here")
    cp.add_argument("--json", action="store_true", help="print the comparison as JSON instead of the table")
    cp.add_argument("--force", action="store_true", help=FORCE_FOLDER_HELP)
