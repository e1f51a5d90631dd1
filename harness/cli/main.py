"""`python -m harness COMMAND …`: the command line of the hairbench harness.

Commands: run, diff, stepdiff, sweep, plot, report, report-dynamic, bench, merge, compare, accuracy, headline,
export, groom, motion, calibrate, featurecost, reduced, peer, animate, render, stability, judge, budget, hair,
docs (`--help` on each; docs/harness.md lists them). User errors print one line
`harness: error: …` and exit non-zero, never a traceback."""

import argparse
import inspect
import json
import math
import os
import sys
from pathlib import Path

from harness import HarnessError, __version__
from harness.core import interrupts
from harness.core.limits import limits
from harness.core.paths import CUDA_BUILDS
from harness.studies import peer_dynamic as peer
from harness.studies import reduced_dynamic as reduced


class OneLineParser(argparse.ArgumentParser):
    """Usage errors as the binaries print them: one line, exit 2."""

    def error(self, message):
        command = self.prog.split()[3:]  # "python -m harness run" → ["run"]
        self.exit(2, f"harness: error: {' '.join(command + [''])[:-1] + ': ' if command else ''}{message}\n")


def whole(low):
    """An argparse type: a whole number ≥ low, refused in one line otherwise."""

    def parse(text):
        try:
            value = int(text, 10)
        except ValueError:
            raise argparse.ArgumentTypeError(f"needs a whole number (got '{text}')") from None
        if value < low:
            raise argparse.ArgumentTypeError(f"must be at least {low} (got {value})")
        return value

    return parse


def block_size(text):
    """An argparse type: cuda threads per block, as the binaries' --limits allow them."""
    value = whole(1)(text)
    try:
        why = limits().block_size_error(value)
    except HarnessError as e:
        raise argparse.ArgumentTypeError(str(e)) from None
    if why:
        raise argparse.ArgumentTypeError(why)
    return value


def real(name, needs, accept, must):
    """An argparse type named `name`: a float that `accept` takes; otherwise one line, "needs
    NEEDS" for what is not a number and "MUST" for one outside the range."""

    def parse(text):
        try:
            value = float(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"needs {needs} (got '{text}')") from None
        if not accept(value):
            raise argparse.ArgumentTypeError(f"{must} (got '{text}')")
        return value

    parse.__name__ = name
    return parse


seconds = real("seconds", "a number of seconds", lambda v: 0 < v < math.inf, "must be a finite number of seconds > 0")
nonneg_seconds = real(
    "nonneg_seconds", "a number of seconds", lambda v: 0 <= v < math.inf, "must be a finite number of seconds ≥ 0"
)
unit_interval = real("unit_interval", "a number in [0, 1]", lambda v: 0.0 <= v <= 1.0, "must lie in [0, 1]")
number = real("number", "a number", math.isfinite, "needs a finite number")
positive = real("positive", "a number", lambda v: 0 < v < math.inf, "must be a finite number > 0")


def options(args, names):
    """The parsed options `names` (space-separated attribute names) as keywords of the same names."""
    return {name: getattr(args, name) for name in names.split()}


def cmd_run(args):
    """Run a scene (configs/scenes/NAME.toml or a path) on a backend binary with --json; print a summary, or the
    JSON record with --json."""
    from harness.core import runner, scenes
    from harness.core.paths import binary_path

    if args.backend == "cpu" and args.block_size is not None:
        raise HarnessError("run: --block-size is a cuda flag; the cpu backend takes --threads")
    if args.backend == "cuda" and args.threads is not None:
        raise HarnessError("run: --threads is a cpu flag; the cuda backend takes --block-size")

    scene = scenes.load_scene(args.scene).with_overrides(
        strands=args.strands,
        points=args.points,
        precision=args.precision,
        stages=scenes.parse_stages(args.stages, "run", "--stages") if args.stages else None,
    )
    if scene.model == "dynamic" and args.frames:
        scene = scenes.with_frames(scene, args.frames)
    from harness.io import grooms

    binary = binary_path(args.backend, args.build)
    # the binaries read HAIR: a USD groom passes through one, named as the user named it
    with grooms.hair_for(scene) as (scene, named):
        flags = runner.run_flags(
            scene, args.backend, **options(args, "variant block_size threads repeat warmup output force")
        )
        if scene.model == "dynamic":  # per-frame observables (harness/check/run_dynamic.py)
            from harness.check import run_dynamic

            given = options(args, "timeout every")
            return run_dynamic.run(binary, flags, args.output, as_json=args.json, named=named, **given)
        record = named(runner.run_binary(binary, flags, timeout=args.timeout))
    print(json.dumps(record, indent=1) if args.json else runner.summary(record))
    return 0


def cmd_diff(args):
    """Compare two HDF5 states frame by frame (docs/harness.md, Equivalence). Exit 0 = equivalent, 1 = not
    equivalent, 2 = could not compare."""
    from harness.check import diff, diff_dynamic

    frames = ",".join(str(k) for k in args.frame) if args.frame else args.frames
    if diff_dynamic.is_dynamic_file(args.a) or diff_dynamic.is_dynamic_file(args.b):
        # dynamic files pair frames by step: --frame K names step K
        return diff_dynamic.run(args.a, args.b, frames=frames, exact=args.exact, as_json=args.json)
    return diff.run(args.a, args.b, frames=frames, align_last=args.align_last, exact=args.exact, as_json=args.json)


def cmd_stepdiff(args):
    """For each chosen simulated frame k of a reference written with --velocities all, run BINARY --input REF
    --input-frame k --stages simulate --frames 1 and compare its new frame with the reference's frame k+1 by the
    dynamic per-frame tolerance: max(DYN_STEP_K·ε·E·S·I, DYN_SPREAD_K × the scene's spread, measured by
    build/hairsim-cpu-contract from the same input) (harness/check/diff_dynamic.py, docs/judge.md). Exit 0 =
    equivalent, 1 = not, 2 = could not compare."""
    from harness.check import diff_dynamic

    flags = args.flags[1:] if args.flags[:1] == ["--"] else args.flags
    given = options(args, "frames exact keep timeout")
    return diff_dynamic.stepdiff(args.reference, args.binary, flags=flags, spread=not args.no_spread, **given)


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


def compare_parser(sub):
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


# the options accuracy_dynamic.Plan takes as given (substeps, iterations and ftl_damping as sets)
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


def cmd_export(args):
    """Write STATE.xdmf + STATE.topo.h5 (polylines over time, positions referenced in STATE); with --usd,
    STATE.usdc (BasisCurves, one time sample per frame; needs usd-core); with --hair, STATE.hair (one frame, the
    last or --frame K, as a groom that --groom reads). A dynamic state's times are in seconds.
    Existing sidecars are replaced only with --force; every refusal comes before anything is written."""
    from harness.io import export

    usd = args.usd or args.usd_only
    only = args.usd_only or args.hair_only
    for path in export.run(
        args.state,
        xdmf=not only,
        usd=usd,
        out=args.out,
        force=args.force,
        hair=args.hair or args.hair_only,
        frame=args.frame,
    ):
        print(f"wrote {path}")
    return 0


def cmd_groom(args):
    from harness.io import grooms

    n = grooms.convert(args.src, args.dst, force=args.force)
    print(f"wrote {args.dst}: {n} strands")
    return 0


def cmd_budget(args):
    """For a scene, a strand count and a frame budget: on each device a run measured (or the GPU --gpu names),
    the most accurate mode whose time a frame at --strands, predicted from its own measured throughput curve,
    fits --frame-ms; its predicted time (said where it is extrapolated beyond the measured sizes, or within timing
    noise of the budget) and its RMS error over the accuracy study's horizon (docs/harness.md, "A frame budget").
    Reads RUN/dynamic-accuracy[-SCENE]/ and RUN/budget-curves[-SCENE]/ (make bench, or make bench SCENE=...)."""
    from harness.core.paths import LOCAL_RUN
    from harness.render import frame_budget_dynamic as frame_budget

    data = frame_budget.load(args.run or LOCAL_RUN, args.scene)
    if args.json:
        print(json.dumps(frame_budget.answer(data, args.strands, args.frame_ms, args.gpu), indent=1, default=float))
        return 0
    print("\n".join(frame_budget.lines(data, args.strands, args.frame_ms, args.gpu, scene=args.scene)))
    return 0


def cmd_hair(args):
    """Map a hair fibre (a preset, or radius, Young's modulus and density) to the dynamic model's point mass,
    stiffnesses and per-unit-mass compliances on a strand of --length cm and --points points (docs/hair_physics.md),
    and print the [fibre] table that puts it in a scene."""
    from harness.core import hair_physics, scenes
    from harness.render import fibre_dynamic_report as fibre_report

    try:
        fibre = hair_physics.fibre(
            args.preset, args.radius_um, args.youngs_gpa, args.density, "given on the command line"
        )
    except ValueError as e:
        raise HarnessError(f"hair: {e}") from None
    curvature = args.curvature or 1.0 / (scenes.Scene.head_radius + scenes.Scene.hair_offset)
    try:
        m = hair_physics.mapped(fibre, args.length, args.points, curvature)
    except ValueError as e:
        raise HarnessError(f"hair: {e}") from None
    print(fibre_report.text(args.preset, fibre, m))
    return 0


def cmd_motion(args):
    from harness.io import motion_tracks

    n = motion_tracks.convert(
        args.src,
        args.dst,
        prim_path=args.prim,
        relative=args.relative,
        rotation_only=args.rotation_only,
        force=args.force,
    )
    print(f"wrote {args.dst}: {n} samples")
    return 0


def cmd_featurecost(args):
    """Run a dynamic scene with every feature undeclared, each alone, the full scene less each, and the full
    scene (features are removed by their flags, so the binary compiles them out); print a Markdown table and,
    with --out, write the rows as CSV."""
    from harness.render import featurecost_dynamic_report as featurecost_report
    from harness.studies import featurecost_dynamic as featurecost

    given = options(
        args, "backend build variant strands points frames repeat threads block_size out timeout instructions"
    )
    rows = featurecost.measure(scene_ref=args.scene, **given)
    print(featurecost_report.markdown(rows), end="")
    return 0


def cmd_reduced(args):
    """Run a dynamic scene at 1,000 and 10,000 strands (--quick: 200 and 1,000) with guide fractions 100 … 1%
    x scheme (one, blend3), LRA off/on at few iterations under a fast nod, and P_s simulated points written as
    P_r = 33 (--render-points); compare each with a converged reference in which every strand and point is
    simulated (xpbd, fp64, S doubled until it is ten times closer than the rows it ranks) up to the scene's
    predictability time, and with the reference ensemble's statistics over the whole run; time it on the cpu
    oracle and, with a usable GPU, the cuda variants that run it (docs/model.md §3.14); and the still scene with
    and without sag-free rest at two shape ranges: how far it sags, and the tip's swing under a wind step.
    Prints Markdown; --out writes the rows as CSV and references.csv beside it."""
    from harness.render import reduced_dynamic_report as reduced_report

    base = reduced.Plan.quick if args.quick else reduced.Plan
    changes = {k: v for k, v in (("scene", args.scene), ("seconds", args.seconds)) if v}
    if args.strands:
        changes["strands"] = tuple(args.strands)
    if args.parts:
        changes["parts"] = tuple(args.parts)
    refs = []
    rows = reduced.measure(base(gpu=args.gpu, **changes), out=args.out, refs_into=refs)
    print(reduced_report.markdown(rows, refs), end="")
    return 0


def setting(text):
    """An argparse type: a setting 'SxI' (substeps × iterations), each a whole number ≥ 1."""
    parts = text.lower().split("x")
    try:
        s, i = (int(v, 10) for v in parts)
    except ValueError:
        raise argparse.ArgumentTypeError(f"needs SxI, e.g. 8x1 (got '{text}')") from None
    if s < 1 or i < 1:
        raise argparse.ArgumentTypeError(f"S and I must be at least 1 (got '{text}')")
    return (s, i)


def cmd_peer(args):
    """Run chains released from rest in hairsim-cpu and in pypbd (XPBD distance constraints, the parameters
    mapped as docs/decisions.md says), against our converged fp64 reference: error, stretch and time per frame
    at several strand counts. Writes results/peer/ and results/local/report/peer.md. Needs pypbd (optional):
    without it, one line says it is skipped, nothing is written, and the exit status is 0."""
    from harness.render import peer_dynamic_report as peer_report

    if not args.report_only:
        fields = peer.Plan.__dataclass_fields__
        plan = peer.Plan(**{k: getattr(args, k) for k in fields if k != "argv"})
        plan.argv = sys.argv[2:] if len(sys.argv) > 2 and sys.argv[1] == "peer" else None
        try:
            peer.run_study(plan)
        except peer.PeerUnavailable as e:  # an optional dependency: skipped, not failed
            print(f"harness: peer: skipped: {e}", file=sys.stderr)
            return 0
    path = peer_report.write(args.out, args.report_dir)
    print(f"wrote {path}")
    return 0


def cmd_animate(args):
    """Draw the frames of a dynamic HDF5 state (read through harness.io.trajectory) seen from the side and from
    the front, the head sphere drawn, as a GIF (and an MP4 beside it where ffmpeg is on PATH). Without STATE,
    runs configs/scenes/dynamic.toml on hairsim-cpu first."""
    from harness.studies import animate_dynamic as animate

    for path in animate.run(args.state, **options(args, "out max_strands every fps force strands frames")):
        print(f"wrote {path}")
    return 0


def size_of(text):
    """An argparse type: 'WxH' → (W, H), each 16…8192 pixels."""
    try:
        w, h = (int(v, 10) for v in text.lower().split("x"))
    except ValueError:
        raise argparse.ArgumentTypeError(f"needs WIDTHxHEIGHT in pixels, e.g. 960x720 (got '{text}')") from None
    if not (16 <= w <= 8192 and 16 <= h <= 8192):
        raise argparse.ArgumentTypeError(f"each side must lie in 16…8192 pixels (got '{text}')")
    return w, h


def cmd_render(args):
    """Render a state file (paper or dynamic) as shaded hair with OpenGL on EGL (no display needed): strands as
    camera-facing ribbons with Kajiya–Kay shading and an opacity shadow map, the head sphere turning with the
    head motion, 4× MSAA. Writes OUT/STEM-frameK-VIEW.png for each frame and view, and with --animate
    OUT/STEM-VIEW.gif (and .mp4 where ffmpeg is on PATH). No EGL context: one line, exit 2."""
    from harness.core.paths import REPORT, display
    from harness.render.gl import camera, command

    views = camera.parse_views(args.view)
    out = args.out if args.out else REPORT.parent / "render"
    written = command.run(
        args.state,
        out,
        views=views,
        frames=args.frame,
        size=args.size,
        animate=args.animate,
        force=args.force,
        shadows=not args.no_shadows,
        max_strands=args.max_strands,
    )
    for path in written:
        print(f"wrote {display(path)}")
    return 0


def cmd_stability(args):
    """Run 2-D slices of the dynamic scene space (substeps against wind, stretch and bend compliance, points and
    iterations, iterations on curly hair; head-motion frequency against amplitude; long-range attachments on and
    off under fast nods and gales) for both solvers and precisions, on the CPU and every built CUDA build where
    a GPU answers; judge each cell ok, over-stretched, penetrating, escaped (a point past twice its hanging
    length) or diverged (NaN/Inf); write results/stability/, results/local/report/stability_*.png and
    results/local/report/dynamic_stability.md."""
    from harness.render import stability_dynamic_report as stability_report
    from harness.studies import stability_dynamic as stability

    if args.from_csv:
        stability_report.report_from_csv(args.from_csv, report_dir=args.report_dir)
        return 0
    if args.scene and args.slice:
        raise HarnessError("stability: --scene runs its own slice (substeps against iterations): drop --slice", code=2)
    csv_path = stability.run_study(
        slices=tuple(args.slice or stability.SLICE_NAMES),
        scene=args.scene,
        out_dir=args.out,
        **options(args, "quick strands frames jobs gpu timeout"),
    )
    stability_report.report_from_csv(csv_path, report_dir=args.report_dir)
    return 0


def cmd_judge(args):
    """Step every planted defect (build/planted/, make planted) from the C reference's frames on the standard
    scenes, and every honest build × variant × precision on the extreme scenes, judging each frame as stepdiff
    does (the rule and the scene's spread); the paper model's planted defects and variants likewise by whole
    runs judged as harness diff does; simulated-point LOD runs (not resumable) by stepdiff of the same run without
    LOD, their simulated rows against it and their rendered rows recomputed; print caught / planted and false
    alarms / honest runs, write
    results/judge/judge.csv and judge.json (docs/judge.md). Exit 0 when every defect is caught and no honest run
    fails, else 1."""
    from harness.studies import judge

    plan = judge.Plan.quick(gpu=args.gpu) if args.quick else judge.Plan(gpu=args.gpu)
    if args.strands:
        plan = judge.replace(plan, strands=args.strands)
    if args.extreme:
        known = [*judge.EXTREME, *judge.PAPER_EXTREME, *judge.LOD_SCENES]
        unknown = [n for n in args.extreme if n not in known]
        if unknown:
            raise HarnessError(f"judge: unknown extreme scene(s) {', '.join(unknown)} (known: {', '.join(known)})")
        plan = judge.replace(
            plan,
            extreme=tuple(n for n in args.extreme if n in judge.EXTREME),
            paper_extreme=tuple(n for n in args.extreme if n in judge.PAPER_EXTREME),
            lod=tuple(n for n in args.extreme if n in judge.LOD_SCENES),
        )
    if args.plant:
        plan = judge.replace(plan, plants=tuple(args.plant))
    summary = judge.run(plan, out_dir=args.out, jobs=args.jobs)
    print(judge.format_summary(summary))
    return 0 if summary["caught"] == summary["planted"] and summary["false_alarms"] == 0 else 1


def cmd_calibrate(args):
    """Run the cpu binary at fp32 and fp64 on the paper scene and print the errors and invariant residuals that
    tolerances.py is set from."""
    from harness.studies import calibrate_paper as calibrate

    return calibrate.run(
        strands=args.strands, points=args.points, seeds=args.seeds, other=args.other, as_json=args.json
    )


def cmd_docs(args):
    """Remake the command and module reference of docs/harness.md from this parser and the modules' docstrings
    (what `make docs` runs); --check only says whether it is current (exit 1 if not)."""
    from harness.cli import docs

    return docs.run(parser(), check=args.check)


FORCE_FOLDER_HELP = "write into a folder that holds files but is not a hairbench run folder (no .hairbench-run.json)"
REPORT_DIR_HELP = "where to write (default results/local/report/)"
GPU_CHOICES = ("auto", "yes", "no")
GPU_HELP = "run cuda cases: auto (if a GPU is usable), yes (fail without), no"


def output_options(p, results=None, report=None, from_csv=None):
    """The output options the commands share, each where its text is given: --out (a results
    directory, `results` its default), --report-dir (`report`: its help) and --from-csv (its help)."""
    if results:
        p.add_argument("--out", default=None, help=f"results directory (default {results})")
    if report:
        p.add_argument("--report-dir", default=None, help=report)
    if from_csv:
        p.add_argument("--from-csv", default=None, help=from_csv)


def case_options(p, jobs=None, gpu=None, timeout=None, gpu_choices=GPU_CHOICES, gpu_default="auto"):
    """How a command runs its cases, each option where its help is given: --jobs (at once),
    --gpu (whether GPU cases run) and --timeout (seconds per binary run)."""
    if jobs:
        p.add_argument("--jobs", type=whole(1), default=None, help=jobs)
    if gpu:
        p.add_argument("--gpu", choices=gpu_choices, default=gpu_default, help=gpu)
    if timeout:
        p.add_argument("--timeout", type=seconds, default=None, help=timeout)


def binary_options(p):
    """Which binary runs and how: --backend, --build, --variant, --threads (cpu) and
    --block-size (cuda), as `run` and `featurecost` take them."""
    p.add_argument("--backend", choices=("cpu", "cuda"), default="cpu")
    p.add_argument(
        "--build",
        choices=tuple(CUDA_BUILDS),
        default="default",
        help="cuda build: hairsim-cuda, -strict or -fastmath (default: default)",
    )
    p.add_argument(
        "--variant",
        help="a variant the binary declares (`hairsim-* --list-variants`; default: the binary's default variant)",
    )
    p.add_argument("--threads", type=whole(1), help="cpu OpenMP threads (default: all cores)")
    p.add_argument("--block-size", type=block_size, help="cuda threads per block, as the binaries' --limits allow")


def command(sub, func, help, description=None, name=None):  # noqa: A002 (argparse's own name)
    """A subcommand's parser that runs func(args): named `name`, else as func (cmd_report_dynamic:
    report-dynamic), and described by `description`, else by func's docstring."""
    name = name or func.__name__.removeprefix("cmd_").replace("_", "-")
    p = sub.add_parser(name, help=help, description=description or inspect.cleandoc(func.__doc__ or "") or None)
    p.set_defaults(func=func)
    return p


def parser():
    p = OneLineParser(
        prog="python -m harness",
        description="hairbench harness: run, diff, sweep, plot and report the hair-strand backends (docs/harness.md)",
    )
    p.add_argument("--version", action="version", version=f"hairbench harness {__version__}")
    sub = p.add_subparsers(dest="command", metavar="COMMAND", required=True)

    r = command(sub, cmd_run, help="run one scene on a backend and print its record")
    r.add_argument("scene", help="scene name in configs/scenes/ (e.g. paper) or a .toml path")
    binary_options(r)
    r.add_argument("--precision", choices=("fp32", "fp64"), help="override the scene's precision")
    r.add_argument("--strands", type=whole(1), help="override the scene's strand count")
    r.add_argument("--points", type=whole(2), help="override the scene's points per strand")
    r.add_argument("--stages", help="override the scene's stages (comma-separated)")
    r.add_argument("--repeat", type=whole(1), help="timed repetitions per stage")
    r.add_argument("--warmup", type=whole(0), help="untimed runs per stage before the timed ones")
    r.add_argument("--output", help="write the HDF5 state here (refused if it exists, unless --force)")
    r.add_argument("--force", action="store_true", help="allow replacing --output")
    case_options(r, timeout="seconds before giving up")
    r.add_argument("--json", action="store_true", help="print the binary's JSON record")
    r.add_argument("--frames", type=whole(1), default=None, help="dynamic scenes: override dynamics.frames")
    r.add_argument(
        "--every",
        type=whole(1),
        default=None,
        help="dynamic scenes: print every K-th frame's observables (default: about 30 lines)",
    )

    sd = command(sub, cmd_stepdiff, help="validate a dynamic backend one frame at a time (exit 0/1/2)")
    sd.add_argument("--reference", required=True, help="dynamic state file (A)")
    sd.add_argument("--binary", required=True, help="the binary to validate (e.g. build/hairsim-cuda)")
    sd.add_argument(
        "--frames",
        default="all",
        help="frame indices of A: all (default), K, K..L, K.., ..L (comma-separated); every frame named or "
        "spanned must be one to step from (a simulated frame or the last paper frame, with velocities), "
        "else exit 2",
    )
    sd.add_argument("--exact", action="store_true", help="require bit-identical frames")
    sd.add_argument("--keep", help="keep the binary's outputs in this directory")
    case_options(sd, timeout="seconds per binary run")
    sd.add_argument(
        "--no-spread",
        action="store_true",
        help="judge by the DYN_STEP_K rule alone, without the scene's spread (measured by build/hairsim-cpu-contract)",
    )
    sd.add_argument(
        "flags", nargs=argparse.REMAINDER, help="further flags for the binary (after the options, e.g. -- --threads 1)"
    )

    d = command(sub, cmd_diff, help="compare two state files frame by frame (exit 0/1/2)")
    d.add_argument("a", help="first state file (e.g. the CPU reference)")
    d.add_argument("b", help="second state file")
    d.add_argument(
        "--frames",
        default="all",
        help="'all' (default; frame counts must match: dynamic files must run to the same step, "
        "and be of one solver), 'last' (the last frame of each), or frame numbers like '3' or '1,3' "
        "(dynamic files: steps)",
    )
    d.add_argument(
        "--frame", type=int, action="append", help="compare only frame K (repeatable; negative counts from the end)"
    )
    d.add_argument(
        "--align-last", action="store_true", help="with different frame counts, compare the last min(F_A, F_B) frames"
    )
    d.add_argument("--exact", action="store_true", help="require bit-identical positions")
    d.add_argument("--json", action="store_true", help="print the comparison as JSON")

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

    rd = command(
        sub,
        cmd_report_dynamic,
        help="write results/local/report/dynamic.md (and its plots) from a dynamic bench root",
    )
    rd.add_argument("root", nargs="?", default="results/local", help="the bench root (default results/local)")
    output_options(rd, report=REPORT_DIR_HELP)

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

    mg = command(sub, cmd_merge, help="join shard folders (bench --shard K/N) into one results folder")
    mg.add_argument("out", help="the merged folder to write (must not exist, or be empty)")
    mg.add_argument("shards", nargs="+", help="the shard folders")
    compare_parser(sub)

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

    e = command(sub, cmd_export, help="sidecars that ParaView/VisIt (XDMF) and Blender/Houdini/usdview (USD) open")
    e.add_argument("state", help="an HDF5 state written by a hairsim binary")
    e.add_argument("--usd", action="store_true", help="also write the USD file")
    e.add_argument("--usd-only", action="store_true", help="write only the USD file")
    e.add_argument("--hair", action="store_true", help="also write STATE.hair: one frame as a groom (--groom reads it)")
    e.add_argument("--hair-only", action="store_true", help="write only the HAIR file")
    e.add_argument("--frame", type=int, default=-1, help="the HAIR file's frame (default -1, the last; 0 the first)")
    e.add_argument("--out", help="output prefix (default: the state's path)")
    e.add_argument("--force", action="store_true", help="replace sidecars that exist (else refused, nothing written)")

    gr = sub.add_parser(
        "groom",
        help="convert a USD groom (BasisCurves) to the HAIR file the binaries read",
        description="groom convert IN.usd OUT.hair: every BasisCurves prim of IN in world space, scaled by its "
        "metersPerUnit to cm and turned Y-up, written as a HAIR file for --groom (docs/model.md §3.15). "
        'Needs usd-core; refused in one line without it. A scene\'s groom = "x.usd" is converted the same way '
        "by `run`.",
    )
    gsub = gr.add_subparsers(dest="groom_command", required=True)
    gc = command(gsub, cmd_groom, help="USD BasisCurves → HAIR", name="convert")
    gc.add_argument("src", help="a USD file (.usd, .usda, .usdc, .usdz)")
    gc.add_argument("dst", help="the HAIR file to write")
    gc.add_argument("--force", action="store_true", help="replace dst if it exists")
    bu = command(sub, cmd_budget, help="a frame budget's answer: the most accurate mode that fits, from measured data")
    bu.add_argument("--strands", type=whole(1), required=True, help="strands simulated a frame")
    bu.add_argument("--frame-ms", type=positive, required=True, help="the simulation's budget, ms a frame")
    bu.add_argument("--scene", default="dynamic", help="the scene whose data to use (default dynamic)")
    bu.add_argument("--gpu", default=None, help="only the GPU whose name holds this (e.g. H200); default: every device")
    bu.add_argument("--run", default=None, help="the run folder (default results/local, make bench's)")
    bu.add_argument("--json", action="store_true", help="print the answer as JSON")

    from harness.core.hair_physics import PRESETS

    hp = command(sub, cmd_hair, help="physical hair: a fibre's point mass, stiffness and compliances")
    hp.add_argument("--preset", choices=tuple(PRESETS), default=None, help="a measured hair type")
    hp.add_argument("--radius-um", type=positive, default=None, help="fibre radius r, µm (replaces the preset's)")
    hp.add_argument("--youngs-gpa", type=positive, default=None, help="Young's modulus E, GPa (replaces the preset's)")
    hp.add_argument("--density", type=positive, default=None, help="density ρ, g/cm³ (replaces the preset's)")
    hp.add_argument("--length", type=positive, default=30.0, help="strand length L, cm (default 30)")
    hp.add_argument("--points", type=whole(3), default=32, help="points per strand (default 32)")
    hp.add_argument(
        "--curvature",
        type=positive,
        default=None,
        help="the strand's rest curvature κ where it bends, 1/cm (default 1/(R + h) of the default head: 1/10.1)",
    )

    mo = sub.add_parser(
        "motion",
        help="convert a USD xform's time samples to the CSV head track the binaries read",
        description="motion convert IN.usd OUT.csv: the world transform of a prim (--prim, else the first xformable "
        "prim with time samples) at each of its time samples, as the CSV of --head-motion track --motion-track "
        '(docs/interfaces.md, "Motion tracks"): seconds from the stage\'s timeCodesPerSecond, unit quaternions '
        "turned Y-up, translations in cm. The binaries refuse a non-zero translation (head translation is not "
        "modelled yet): --rotation-only drops it. Needs usd-core; refused in one line without it.",
    )
    msub = mo.add_subparsers(dest="motion_command", required=True)
    mc = command(msub, cmd_motion, help="USD xform time samples → CSV track", name="convert")
    mc.add_argument("src", help="a USD file (.usd, .usda, .usdc, .usdz)")
    mc.add_argument("dst", help="the CSV track to write")
    mc.add_argument("--prim", default=None, help="the animated prim's path (default: the first with time samples)")
    mc.add_argument("--relative", action="store_true", help="each rotation relative to the first sample's")
    mc.add_argument("--rotation-only", action="store_true", help="write zero translation (the rotation alone)")
    mc.add_argument("--force", action="store_true", help="replace dst if it exists")
    c = command(sub, cmd_calibrate, help="measure fp32-vs-fp64 errors behind tolerances.py")
    c.add_argument("--strands", type=whole(1), default=20000)
    c.add_argument("--points", type=whole(2), nargs="+", default=[8, 32, 128])
    c.add_argument("--seeds", type=whole(0), nargs="+", default=[1, 2, 3])
    c.add_argument(
        "--other",
        help="a second binary to compare with the cpu reference at each "
        "precision (e.g. build/hairsim-cuda on a GPU node)",
    )
    c.add_argument("--json", action="store_true")

    fc = command(
        sub,
        cmd_featurecost,
        help="the dynamic model's time per frame with each feature undeclared, alone, and the full scene",
    )
    fc.add_argument("--scene", default="dynamic", help="a dynamic scene (default dynamic)")
    binary_options(fc)
    fc.add_argument("--strands", type=whole(1), default=100_000)
    fc.add_argument("--points", type=whole(2), default=None)
    fc.add_argument("--frames", type=whole(1), default=3, help="frames per case (default 3)")
    fc.add_argument("--repeat", type=whole(1), default=3, help="timed repeats of each frame (default 3)")
    case_options(fc, timeout="seconds per case before giving up")
    fc.add_argument("--out", default=None, help="CSV file to write")
    fc.add_argument(
        "--instructions",
        action="store_true",
        help="cpu oracle: also count, under valgrind's callgrind, the instructions per point-substep of "
        "the frame function (deterministic where times are noisy)",
    )

    rd = command(
        sub,
        cmd_reduced,
        help="the dynamic model with guides and followers, long-range attachments, sag-free rest and "
        "simulated-point LOD: error and time",
    )
    rd.add_argument("--scene", default=None, help="a dynamic scene (default dynamic)")
    rd.add_argument(
        "--strands", type=whole(1), nargs="+", default=None, help="strand counts of the checked runs (1000 10000)"
    )
    rd.add_argument("--seconds", type=seconds, default=None, help="simulated time of each run")
    rd.add_argument(
        "--parts",
        nargs="+",
        choices=reduced.PARTS,
        default=None,
        help="which rows to measure (default all: guides lra sagfree sagfreq lod)",
    )
    rd.add_argument("--quick", action="store_true", help="the small version (CI, a first look)")
    case_options(rd, gpu="the cuda variants too, where a GPU is usable", gpu_choices=("auto", "no"))
    rd.add_argument("--out", default=None, help="CSV file to write")

    peer_plan = peer.Plan()
    pe = command(sub, cmd_peer, help="the same chain scenes in Bender's PositionBasedDynamics (pypbd) beside ours")
    pe.add_argument(
        "--points", type=whole(2), default=peer_plan.points, help="points per chain, root included (default 32)"
    )
    pe.add_argument("--length", type=number, default=peer_plan.length, help="chain length L, cm (default 30)")
    pe.add_argument(
        "--tilts",
        type=number,
        nargs="+",
        default=list(peer_plan.tilts),
        help="degrees from the downward vertical (30 60)",
    )
    pe.add_argument(
        "--frames", type=whole(1), default=peer_plan.frames, help="accuracy horizon in frames (default 30: 0.5 s)"
    )
    pe.add_argument("--frame-dt", type=number, default=peer_plan.frame_dt, help="frame length Δt, s (default 1/60)")
    pe.add_argument("--gravity", type=number, default=peer_plan.gravity, help="g0, cm/s² (default 981)")
    pe.add_argument(
        "--compliance", type=number, default=peer_plan.compliance, help="stretch compliance α (default 0: rigid)"
    )
    pe.add_argument(
        "--settings", type=setting, nargs="+", default=list(peer_plan.settings), help="SxI pairs (8x1 32x1 8x4)"
    )
    pe.add_argument(
        "--strands", type=whole(1), nargs="+", default=list(peer_plan.strands), help="chains timed (1 100 1000 10000)"
    )
    pe.add_argument("--threads", type=whole(1), default=peer_plan.threads, help="threads for both solvers (default 1)")
    pe.add_argument(
        "--time-frames", type=whole(1), default=peer_plan.time_frames, help="frames per timing run (default 5)"
    )
    pe.add_argument(
        "--repeat", type=whole(1), default=peer_plan.repeat, help="our --repeat; the peer steps frames × repeat"
    )
    pe.add_argument(
        "--ref-start", type=whole(1), default=peer_plan.ref_start, help="first S of the reference doubling (64)"
    )
    pe.add_argument("--ref-max", type=whole(2), default=peer_plan.ref_max, help="largest S of the reference (16384)")
    case_options(pe, timeout="seconds per binary run")
    output_options(pe, results="results/peer", report="where peer.md goes (default results/local/report/)")
    pe.add_argument("--report-only", action="store_true", help="only re-render results/local/report/peer.md from --out")

    an = command(sub, cmd_animate, help="an animation of a dynamic state from the side and from the front")
    an.add_argument("state", nargs="?", default=None, help="a dynamic state file (default: run the dynamic scene)")
    an.add_argument("--out", default=None, help="the GIF to write (default results/local/report/dynamic.gif)")
    an.add_argument("--max-strands", type=whole(1), default=150, help="strands drawn at most (default 150)")
    an.add_argument("--every", type=whole(1), default=None, help="draw every K-th frame (default: about 60 frames)")
    an.add_argument("--fps", type=whole(1), default=None, help="frames per second of the GIF (default: real time)")
    an.add_argument("--strands", type=whole(1), default=300, help="without STATE: strands simulated (default 300)")
    an.add_argument("--frames", type=whole(1), default=120, help="without STATE: frames simulated (default 120)")
    an.add_argument("--force", action="store_true", help="replace existing output files")

    rd = command(sub, cmd_render, help="shaded hair from a state file: PNG frames and animations (OpenGL on EGL)")
    rd.add_argument("state", help="a state file (paper or dynamic model)")
    rd.add_argument("--out", default=None, help="the folder written into (default results/local/render)")
    rd.add_argument(
        "--view", default="front,side,three-quarter", help="views, comma-separated: front, side, three-quarter, all"
    )
    rd.add_argument(
        "--frame", type=int, action="append", help="a frame to draw (repeatable; negative from the end; default -1)"
    )
    rd.add_argument("--size", type=size_of, default=(960, 720), help="image size WxH in pixels (default 960x720)")
    rd.add_argument("--animate", action="store_true", help="also animate the simulated frames from each view")
    rd.add_argument("--max-strands", type=whole(1), default=None, help="strands drawn at most (default all)")
    rd.add_argument("--no-shadows", action="store_true", help="no self-shadowing (the opacity shadow map)")
    rd.add_argument("--force", action="store_true", help="replace existing output files")

    from harness.studies.stability_dynamic import FRAMES, SLICE_NAMES, STRANDS

    sb = command(
        sub,
        cmd_stability,
        help="the dynamic model's stability map: verdicts over 2-D slices of the scene space",
    )
    sb.add_argument("--quick", action="store_true", help="a coarser grid (about a quarter of the cells)")
    sb.add_argument("--slice", action="append", choices=SLICE_NAMES, help="run only this slice (repeatable)")
    sb.add_argument(
        "--scene",
        help="a dynamic scene (name or .toml path, e.g. a groom's): substeps against iterations over it instead of "
        "the slices",
    )
    sb.add_argument("--strands", type=whole(1), default=STRANDS, help=f"strands per cell (default {STRANDS})")
    sb.add_argument("--frames", type=whole(1), default=FRAMES, help=f"frames per cell (default {FRAMES}: 1 s)")
    case_options(
        sb,
        jobs="cells run at once (default: all cores)",
        gpu="run the CUDA builds too",
        timeout="seconds per cell before giving up",
    )
    output_options(
        sb,
        results="results/stability",
        report=REPORT_DIR_HELP,
        from_csv="only redraw the report from an existing stability.csv",
    )

    from harness.studies.judge import EXTREME, PAPER_EXTREME, PLANTS

    jg = command(
        sub,
        cmd_judge,
        help="the one-frame judge's power: planted defects caught, false alarms on extreme scenes",
    )
    jg.add_argument("--quick", action="store_true", help="fewer strands and frames (the tests' size)")
    jg.add_argument("--strands", type=whole(1), default=None, help="strands per scene")
    jg.add_argument(
        "--extreme",
        action="append",
        metavar="NAME",
        help=f"only this extreme scene (repeatable; {len(EXTREME)} dynamic, {len(PAPER_EXTREME)} paper declared)",
    )
    jg.add_argument("--plant", action="append", type=int, choices=sorted(PLANTS), help="only this planted defect")
    case_options(jg, jobs="scenes run at once (default: all cores)", gpu="honest runs of the CUDA builds too")
    output_options(jg, results="results/judge")

    dc = command(sub, cmd_docs, help="remake docs/harness.md's command and module reference")
    dc.add_argument("--check", action="store_true", help="write nothing; exit 1 when the page is out of date")
    return p


def main(argv=None):
    args = parser().parse_args(argv)
    from harness.core import gpus, runner
    from harness.io import runfolder

    try:
        gpus.wanted()  # a bad HB_GPUS is refused on every machine, with or without a GPU
        with runner.forwarding(), interrupts.redelivered():
            rc = args.func(args)
            sys.stdout.flush()  # a closed pipe shows here, inside the handlers below
        return rc
    except runner.Stopped as e:  # forwarded to every child, each waited for: nothing runs on
        runfolder.abandon_unused()
        print(f"harness: stopped by {e}", file=sys.stderr)
        return 128 + e.signum
    except HarnessError as e:  # one line, whatever a library's text it quotes holds
        runfolder.abandon_unused()  # a refused command creates nothing
        print(f"harness: error: {' '.join(str(e).split(chr(10)))}", file=sys.stderr)
        return e.code if e.code else 2
    except BrokenPipeError:  # the reader went away (`| head`): quiet, as other tools
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())  # no second error at exit
        return 141
    except OSError as e:  # a path given that cannot be read or written, or a full disk: no traceback
        where = f"{e.filename}: " if e.filename else ""
        print(f"harness: error: {where}{e.strerror or e}", file=sys.stderr)
        return (
            2
            if isinstance(
                e, (FileNotFoundError, FileExistsError, IsADirectoryError, NotADirectoryError, PermissionError)
            )
            else 4
        )
    except KeyboardInterrupt:
        print("harness: interrupted", file=sys.stderr)
        return 130
