"""Speed against accuracy and the headline numbers, of either model: `accuracy`, `headline`."""

import sys
from pathlib import Path

from harness import HarnessError
from harness.cli.options import (
    REPORT_DIR_HELP,
    block_size,
    case_options,
    command,
    nonneg_seconds,
    options,
    output_options,
    seconds,
    unit_interval,
    whole,
)

PAPER_ACCURACY = dict(
    scene="paper",
    strands=100_000,
    points=32,
    repeat=9,
    resolution=[4, 8, 16, 32, 64, 128, 256],
    resolution_strands=20_000,
)


PAPER_ONLY = ("resolution", "resolution_strands")


DYNAMIC_ONLY = (
    "quick",
    "seconds",
    "horizon",
    "substeps",
    "iterations",
    "time_strands",
    "time_frames",
    "ref_start",
    "ref_max",
    "jobs",
    "analytic",
    "gpu",
    "force",
    "ftl_damping",
    "ref_extra",
    "long_seconds",
    "long_strands",
)


DYNAMIC_SETS = ("substeps", "iterations", "ftl_damping")


DYNAMIC_PLAN = " ".join(
    ["scene", "strands", "points", "repeat", *(k for k in DYNAMIC_ONLY if k not in ("quick", "force", *DYNAMIC_SETS))]
)


def _flag(name):
    return "--" + name.replace("_", "-")


def accuracy_model(args):
    """paper | dynamic: --model, else the model of --scene, else paper; a contradiction or
    an option of the other model is refused."""
    from harness.core import scenes

    model = args.model
    if args.from_csv and model is None:
        from harness.core import inputs
        from harness.studies.accuracy import REQUIRED_COLUMNS

        inputs.regular(args.from_csv, "accuracy: --from-csv")
        try:
            with open(args.from_csv, encoding="utf-8") as fh:
                header = fh.readline().strip().split(",")
        except (OSError, UnicodeDecodeError) as e:
            raise HarnessError(f"accuracy: --from-csv {args.from_csv}: cannot read ({e})") from None
        model = "dynamic" if set(REQUIRED_COLUMNS) <= set(header) else "paper"
    if args.scene is not None and not args.from_csv:
        scene_model = scenes.load_scene(args.scene).model
        if model is not None and model != scene_model:
            raise HarnessError(f"accuracy: --model {model} but scene {args.scene} is a {scene_model}-model scene")
        model = scene_model
    model = model or "paper"
    other = PAPER_ONLY if model == "dynamic" else DYNAMIC_ONLY
    given = [_flag(k) for k in other if getattr(args, k) not in (None, False)]
    if given:
        what = "is an option" if len(given) == 1 else "are options"
        theirs = "paper" if model == "dynamic" else "dynamic"
        raise HarnessError(f"accuracy: {', '.join(given)} {what} of the {theirs} model's study, not of --model {model}")
    return model


def cmd_accuracy(args):
    """Paper model (default): run the scene in every precision/build mode available here and in several model
    resolutions, compare with hairsim-cpu --precision fp64, time each mode apart, and write results/accuracy/
    and results/local/report/accuracy.md with a Pareto plot. Dynamic model (--model dynamic, or a dynamic
    --scene): every solver x substeps x iterations x precision x build against a converged xpbd fp64 reference
    (substeps doubled until S and 2S agree to a tenth of the smallest error), time per frame measured apart,
    small steps against iterations, the analytic checks and a recommendation; writes results/dynamic-accuracy/
    and results/local/report/dynamic_accuracy.md with its plots (docs/harness.md; another --scene X:
    results/dynamic-accuracy-X/ and dynamic_accuracy_X.md). Exit 0, or 1 when the dynamic reference did not
    converge."""
    if accuracy_model(args) == "dynamic":
        return accuracy_dynamic(args)
    from harness.core.paths import RESULTS
    from harness.render import accuracy_paper_report
    from harness.studies import accuracy_paper

    if args.from_csv:
        accuracy_paper_report.report_from_csv(args.from_csv, report_dir=args.report_dir)
        return 0
    opt = {k: getattr(args, k) if getattr(args, k) is not None else v for k, v in PAPER_ACCURACY.items()}
    accuracy_paper.run_study(
        opt["scene"],
        strands=opt["strands"],
        points=opt["points"],
        repeat=opt["repeat"],
        resolution=tuple(opt["resolution"]),
        res_strands=opt["resolution_strands"],
        out_dir=args.out,
    )
    out = Path(args.out) if args.out else RESULTS / "accuracy"
    accuracy_paper_report.report_from_csv(out / "accuracy.csv", report_dir=args.report_dir)
    return 0


def accuracy_dynamic(args):
    from pathlib import Path

    from harness.core.paths import RESULTS, display
    from harness.render import accuracy_dynamic_report
    from harness.studies import accuracy_dynamic

    if args.from_csv:
        csv_path = Path(args.from_csv)
        for path in accuracy_dynamic_report.write(csv_path.parent, args.report_dir, csv_path=csv_path):
            print(f"wrote {display(path)}")
        return 0
    given = {k: v for k, v in options(args, DYNAMIC_PLAN).items() if v is not None}
    for k in DYNAMIC_SETS:
        if getattr(args, k) is not None:
            given[k] = tuple(sorted(set(getattr(args, k))))
    plan = accuracy_dynamic.Plan.quick(**given) if args.quick else accuracy_dynamic.Plan(**given)
    command = " ".join(["python -m harness", *sys.argv[1:]])
    status = accuracy_dynamic.run_study(plan, out_dir=args.out, force=args.force, command=command)
    for path in accuracy_dynamic_report.write(
        Path(args.out or RESULTS / accuracy_dynamic.results_name(plan.scene)), args.report_dir
    ):
        print(f"wrote {display(path)}")
    return status


def cmd_headline(args):
    """At one size, measure the copy bandwidths, every CUDA variant's init and wind+collide time and bandwidth
    fraction, and three CPU baselines (ref 1 thread, ref all cores, simd all cores); write
    results/headline/headline.json."""
    from harness.render import headline_report

    if args.model == "dynamic":
        from harness.studies import headline_dynamic

        result = headline_dynamic.run(
            strands=args.strands,
            repeat=min(args.repeat, 5),
            cpu_repeat=args.cpu_repeat,
            cpu_rounds=args.cpu_rounds,
            ncu=args.ncu,
            out_dir=args.out,
        )
        print(headline_report.dynamic_table(result))
        return 0
    from harness.studies import headline_paper

    given = options(args, "strands points repeat cpu_repeat cpu_rounds block_size")
    result = headline_paper.run(out_dir=args.out, **given)
    print(headline_report.table(result))
    return 0


def add_accuracy(sub):
    a = command(
        sub,
        cmd_accuracy,
        help="speed against accuracy: every mode against a reference (paper or dynamic model)",
    )
    a.add_argument(
        "--model", choices=("paper", "dynamic"), default=None, help="default: the --scene's model, else paper"
    )
    a.add_argument("--scene", default=None, help="scene name or .toml path (default paper, or dynamic)")
    a.add_argument("--strands", type=whole(1), default=None, help="paper 100000; dynamic 256 (--quick 16)")
    a.add_argument("--points", type=whole(2), default=None, help="default: paper 32; dynamic the scene's")
    a.add_argument("--repeat", type=whole(1), default=None, help="timed repetitions (default: paper 9, dynamic 3)")
    a.add_argument(
        "--resolution",
        type=whole(2),
        nargs="+",
        default=None,
        help="paper: points per strand of the resolution study (the largest is the reference; default 4 … 256)",
    )
    a.add_argument("--resolution-strands", type=whole(1), default=None, help="paper: default 20000")
    a.add_argument(
        "--quick",
        action="store_true",
        help="dynamic: a small study (16 strands, 0.25 s, S 1 4 16, I 1, 5 s long runs on 6 strands)",
    )
    a.add_argument("--seconds", type=seconds, default=None, help="dynamic: simulated time (default 1; --quick 0.25)")
    a.add_argument(
        "--horizon", type=seconds, default=None, help="dynamic: time over which errors are compared (default 0.5)"
    )
    a.add_argument(
        "--substeps", type=whole(1), nargs="+", default=None, help="dynamic: S values (default 1 2 4 8 16 32)"
    )
    a.add_argument(
        "--iterations", type=whole(1), nargs="+", default=None, help="dynamic: I values (default 1 2 4; --quick 1)"
    )
    a.add_argument(
        "--time-strands", type=whole(1), default=None, help="dynamic: strands of the timing runs (default 10000)"
    )
    a.add_argument("--time-frames", type=whole(1), default=None, help="dynamic: frames of a timing run (default 1)")
    a.add_argument(
        "--ref-start", type=whole(2), default=None, help="dynamic: first S of the reference (default 2 x max S)"
    )
    a.add_argument("--ref-max", type=whole(2), default=None, help="dynamic: largest S of the reference (default 16384)")
    a.add_argument(
        "--analytic", choices=("full", "quick", "none"), default=None, help="dynamic: the analytic tables to run"
    )
    case_options(
        a,
        jobs="dynamic: parallel checked runs (default: cores)",
        gpu="dynamic: GPU modes and reference if usable",
        gpu_choices=("auto", "no"),
        gpu_default=None,
    )
    a.add_argument(
        "--ftl-damping",
        type=unit_interval,
        nargs="+",
        default=None,
        help="dynamic: ftl's s values, an axis of the study (default 0 0.5 0.9 1)",
    )
    a.add_argument(
        "--ref-extra",
        type=whole(0),
        default=None,
        help="dynamic: doublings past the converged reference that measure its own error (default 2)",
    )
    a.add_argument(
        "--long-seconds",
        type=nonneg_seconds,
        default=None,
        help="dynamic: simulated time of the long runs (energy, tip motion, jitter, distributions; "
        "default 10; --quick 5; 0: none)",
    )
    a.add_argument(
        "--long-strands", type=whole(2), default=None, help="dynamic: strands of the long runs (default 8; --quick 6)"
    )
    a.add_argument("--force", action="store_true", help="dynamic: replace an existing results CSV")
    output_options(
        a,
        results="results/accuracy or results/dynamic-accuracy (another --scene X: results/dynamic-accuracy-X)",
        report=REPORT_DIR_HELP,
        from_csv="only rewrite the report from an existing CSV (results/accuracy/accuracy.csv, or with "
        "--model dynamic results/dynamic-accuracy/dynamic_accuracy.csv)",
    )


def add_headline(sub):
    h = command(
        sub,
        cmd_headline,
        help="the headline numbers: bandwidth fractions and speedups (--model dynamic: the dynamic model's targets)",
    )
    h.add_argument("--strands", type=whole(1), default=4 * 1024 * 1024)
    h.add_argument("--points", type=whole(2), default=32)
    h.add_argument("--repeat", type=whole(1), default=9, help="GPU repetitions per stage (default 9)")
    h.add_argument("--cpu-repeat", type=whole(1), default=3, help="CPU repetitions per stage (default 3)")
    h.add_argument(
        "--cpu-rounds",
        type=whole(1),
        default=5,
        help="rounds of (CPU copy bandwidth, fast CPU variant) whose median round is reported (default 5)",
    )
    h.add_argument("--block-size", type=block_size, default=256)
    h.add_argument(
        "--model",
        choices=("paper", "dynamic"),
        default="paper",
        help="paper: the paper scene (default); dynamic: the dynamic model's four targets "
        "(memory-bound case, default scene, real-time regime, CPU), results/headline/headline_dynamic.json",
    )
    h.add_argument("--ncu", action="store_true", help="dynamic: also profile the best kernel with Nsight Compute")
    output_options(h, results="results/headline")
