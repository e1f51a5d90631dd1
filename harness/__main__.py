"""`python -m harness COMMAND …`: the command line of the hairbench harness.

Commands: run, diff, stepdiff, sweep, plot, report, bench, accuracy, headline, export, calibrate
(`--help` on each). User errors print one line `harness: error: …` and exit non-zero, never a traceback."""

import argparse
import json
import sys

from . import HarnessError, __version__


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


def seconds(text):
    """An argparse type: a finite number of seconds > 0."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"needs a number of seconds (got '{text}')") from None
    if not 0 < value < float("inf"):
        raise argparse.ArgumentTypeError(f"must be a finite number of seconds > 0 (got '{text}')")
    return value


def cmd_run(args):
    from . import runner, scenes
    from .paths import binary_path

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
    binary = binary_path(args.backend, args.build)
    flags = runner.run_flags(
        scene,
        args.backend,
        variant=args.variant,
        block_size=args.block_size,
        threads=args.threads,
        repeat=args.repeat,
        warmup=args.warmup,
        output=args.output,
        force=args.force,
    )
    if scene.model == "dynamic":  # per-frame observables (harness/dynrun.py)
        from . import dynrun, dynscene

        if args.frames:
            scene = dynscene.with_frames(scene, args.frames)
            flags = runner.run_flags(
                scene,
                args.backend,
                variant=args.variant,
                block_size=args.block_size,
                threads=args.threads,
                repeat=args.repeat,
                warmup=args.warmup,
                output=args.output,
                force=args.force,
            )
        return dynrun.run(binary, flags, args.output, timeout=args.timeout, as_json=args.json, every=args.every)
    record = runner.run_binary(binary, flags, timeout=args.timeout)
    print(json.dumps(record, indent=1) if args.json else runner.summary(record))
    return 0


def cmd_diff(args):
    from . import diff

    frames = ",".join(str(k) for k in args.frame) if args.frame else args.frames
    # dynamic files (harness/dyndiff.py) pair frames by step: --frame K names step K
    return diff.run(args.a, args.b, frames=frames, align_last=args.align_last, exact=args.exact, as_json=args.json)


def cmd_stepdiff(args):
    from . import dyndiff

    flags = args.flags[1:] if args.flags[:1] == ["--"] else args.flags
    return dyndiff.stepdiff(
        args.reference,
        args.binary,
        flags=flags,
        frames=args.frames,
        exact=args.exact,
        keep=args.keep,
        timeout=args.timeout,
    )


def cmd_sweep(args):
    from . import sweep

    _, failed = sweep.run_sweep(args.sweep, out=args.out, gpu=args.gpu)
    return 1 if failed else 0


def cmd_plot(args):
    from . import plots

    for path in plots.make_all(args.results, args.report_dir):
        print(f"wrote {path}")
    return 0


def cmd_report(args):
    from . import report

    path = report.build(args.results, args.report_dir)
    print(f"wrote {path}")
    return 0


def cmd_bench(args):
    from . import bench

    return bench.run(args.sweep, out=args.out, gpu=args.gpu, report_dir=args.report_dir)


def cmd_accuracy(args):
    from . import accuracy, accuracy_report

    if args.from_csv:
        accuracy_report.report_from_csv(args.from_csv, report_dir=args.report_dir)
        return 0
    accuracy.run_study(
        args.scene,
        strands=args.strands,
        points=args.points,
        repeat=args.repeat,
        resolution=tuple(args.resolution),
        res_strands=args.resolution_strands,
        out_dir=args.out,
        report_dir=args.report_dir,
    )
    return 0


def cmd_headline(args):
    from . import headline

    headline.run(
        strands=args.strands,
        points=args.points,
        repeat=args.repeat,
        cpu_repeat=args.cpu_repeat,
        block_size=args.block_size,
        out_dir=args.out,
    )
    return 0


def cmd_export(args):
    from . import export

    for path in export.run(args.state, xdmf=not args.usd_only, usd=args.usd or args.usd_only, out=args.out):
        print(f"wrote {path}")
    return 0


def cmd_featurecost(args):
    from . import featurecost, featurecost_report

    rows = featurecost.measure(
        scene_ref=args.scene,
        backend=args.backend,
        build=args.build,
        variant=args.variant,
        strands=args.strands,
        points=args.points,
        frames=args.frames,
        repeat=args.repeat,
        threads=args.threads,
        block_size=args.block_size,
        out=args.out,
        timeout=args.timeout,
    )
    print(featurecost_report.markdown(rows), end="")
    return 0


def cmd_calibrate(args):
    from . import calibrate

    return calibrate.run(
        strands=args.strands, points=args.points, seeds=args.seeds, other=args.other, as_json=args.json
    )


def parser():
    p = OneLineParser(
        prog="python -m harness",
        description="hairbench harness: run, diff, sweep, plot and report the hair-strand backends (docs/harness.md)",
    )
    p.add_argument("--version", action="version", version=f"hairbench harness {__version__}")
    sub = p.add_subparsers(dest="command", metavar="COMMAND", required=True)

    r = sub.add_parser(
        "run",
        help="run one scene on a backend and print its record",
        description="Run a scene (configs/scenes/NAME.toml or a path) on a backend binary "
        "with --json; print a summary, or the JSON record with --json.",
    )
    r.add_argument("scene", help="scene name in configs/scenes/ (e.g. paper) or a .toml path")
    r.add_argument("--backend", choices=("cpu", "cuda"), default="cpu")
    r.add_argument(
        "--build",
        choices=("default", "strict", "fastmath"),
        default="default",
        help="cuda build: hairsim-cuda, -strict or -fastmath (default: default)",
    )
    r.add_argument(
        "--variant",
        help="a variant the binary declares (`hairsim-* --list-variants`; default: the binary's default variant)",
    )
    r.add_argument("--precision", choices=("fp32", "fp64"), help="override the scene's precision")
    r.add_argument("--block-size", type=whole(32), help="cuda threads per block (32…1024)")
    r.add_argument("--strands", type=whole(1), help="override the scene's strand count")
    r.add_argument("--points", type=whole(2), help="override the scene's points per strand")
    r.add_argument("--stages", help="override the scene's stages (comma-separated)")
    r.add_argument("--threads", type=whole(1), help="cpu OpenMP threads (default: all cores)")
    r.add_argument("--repeat", type=whole(1), help="timed repetitions per stage")
    r.add_argument("--warmup", type=whole(0), help="untimed runs per stage before the timed ones")
    r.add_argument("--output", help="write the HDF5 state here (refused if it exists, unless --force)")
    r.add_argument("--force", action="store_true", help="allow replacing --output")
    r.add_argument("--timeout", type=seconds, default=None, help="seconds before giving up")
    r.add_argument("--json", action="store_true", help="print the binary's JSON record")
    r.add_argument("--frames", type=whole(1), default=None, help="dynamic scenes: override dynamics.frames")
    r.add_argument(
        "--every",
        type=whole(1),
        default=None,
        help="dynamic scenes: print every K-th frame's observables (default: about 30 lines)",
    )
    r.set_defaults(func=cmd_run)

    sd = sub.add_parser(
        "stepdiff",
        help="validate a dynamic backend one frame at a time (exit 0/1/2)",
        description="For each chosen simulated frame k of a reference written with "
        "--velocities all, run BINARY --input REF --input-frame k --stages "
        "simulate --frames 1 and compare its new frame with the reference's "
        "frame k+1 by the dynamic per-frame tolerance (harness/dyndiff.py). "
        "Exit 0 = equivalent, 1 = not, 2 = could not compare.",
    )
    sd.add_argument("--reference", required=True, help="dynamic state file (A)")
    sd.add_argument("--binary", required=True, help="the binary to validate (e.g. build/hairsim-cuda)")
    sd.add_argument("--frames", default="all", help="frame indices of A: all (default), K, K..L, K.., ..L")
    sd.add_argument("--exact", action="store_true", help="require bit-identical frames")
    sd.add_argument("--keep", help="keep the binary's outputs in this directory")
    sd.add_argument("--timeout", type=seconds, default=None, help="seconds per binary run")
    sd.add_argument(
        "flags", nargs=argparse.REMAINDER, help="further flags for the binary (after the options, e.g. -- --threads 1)"
    )
    sd.set_defaults(func=cmd_stepdiff)

    d = sub.add_parser(
        "diff",
        help="compare two state files frame by frame (exit 0/1/2)",
        description="Compare two HDF5 states frame by frame (DESIGN §6). Exit 0 = "
        "equivalent, 1 = not equivalent, 2 = could not compare.",
    )
    d.add_argument("a", help="first state file (e.g. the CPU reference)")
    d.add_argument("b", help="second state file")
    d.add_argument(
        "--frames",
        default="all",
        help="'all' (default; frame counts must match), 'last' (the last frame of "
        "each), or frame numbers like '3' or '1,3'",
    )
    d.add_argument(
        "--frame", type=int, action="append", help="compare only frame K (repeatable; negative counts from the end)"
    )
    d.add_argument(
        "--align-last", action="store_true", help="with different frame counts, compare the last min(F_A, F_B) frames"
    )
    d.add_argument("--exact", action="store_true", help="require bit-identical positions")
    d.add_argument("--json", action="store_true", help="print the comparison as JSON")
    d.set_defaults(func=cmd_diff)

    s = sub.add_parser(
        "sweep",
        help="run a sweep file, appending rows to results/NAME/runs.csv",
        description="Run every case of a sweep (configs/sweeps/NAME.toml), one row per "
        "(case, stage) in results/NAME/runs.csv; a killed sweep resumes.",
    )
    s.add_argument("sweep", help="sweep name in configs/sweeps/ (e.g. quick) or a .toml path")
    s.add_argument("--out", help="results directory (default results/<sweep name>)")
    s.add_argument(
        "--gpu",
        choices=("auto", "yes", "no"),
        default="auto",
        help="run cuda cases: auto (if a GPU is usable), yes (fail without), no",
    )
    s.set_defaults(func=cmd_sweep)

    for name, helptext, fn in (
        ("plot", "draw the PNG plots of a results directory", cmd_plot),
        ("report", "write report/report.md (and its plots)", cmd_report),
    ):
        q = sub.add_parser(name, help=helptext, description=helptext[0].upper() + helptext[1:] + ".")
        q.add_argument(
            "results",
            nargs="?",
            default="results/default",
            help="results directory with runs.csv and env.json (default results/default)",
        )
        q.add_argument("--report-dir", default=None, help="where to write (default report/)")
        q.set_defaults(func=fn)

    b = sub.add_parser(
        "bench",
        help="the make bench pipeline: check, validate, sweep, report",
        description="Check the binaries, validate every GPU variant against the CPU "
        "(fail before timing), run the sweep, then plot and report.",
    )
    b.add_argument("--sweep", default="default", help="sweep name in configs/sweeps/ or a path (default: default)")
    b.add_argument("--out", help="results directory (default results/<sweep name>)")
    b.add_argument("--gpu", choices=("auto", "yes", "no"), default="auto")
    b.add_argument("--report-dir", default=None, help="where to write the report (default report/)")
    b.set_defaults(func=cmd_bench)

    a = sub.add_parser(
        "accuracy",
        help="speed against accuracy: every mode against the fp64 reference",
        description="Run the scene in every precision/build mode available here and in "
        "several model resolutions, compare with hairsim-cpu --precision "
        "fp64, time each mode apart, and write results/accuracy/ and "
        "report/accuracy.md with a Pareto plot.",
    )
    a.add_argument("--scene", default="paper", help="scene name or .toml path (default paper)")
    a.add_argument("--strands", type=whole(1), default=100_000)
    a.add_argument("--points", type=whole(2), default=32)
    a.add_argument("--repeat", type=whole(1), default=9, help="timed repetitions per stage (default 9)")
    a.add_argument(
        "--resolution",
        type=whole(2),
        nargs="+",
        default=[4, 8, 16, 32, 64, 128, 256],
        help="points per strand of the resolution study (the largest is the reference)",
    )
    a.add_argument("--resolution-strands", type=whole(1), default=20_000)
    a.add_argument("--out", default=None, help="results directory (default results/accuracy)")
    a.add_argument("--report-dir", default=None, help="where to write (default report/)")
    a.add_argument(
        "--from-csv",
        default=None,
        help="only rewrite the table and plot from an existing accuracy.csv (e.g. results/accuracy/accuracy.csv)",
    )
    a.set_defaults(func=cmd_accuracy)

    h = sub.add_parser(
        "headline",
        help="the issues' headline numbers: bandwidth fractions and speedups",
        description="At one size, measure the copy bandwidths, every CUDA variant's init and "
        "wind+collide time and bandwidth fraction, and three CPU baselines "
        "(ref 1 thread, ref all cores, simd all cores); write "
        "results/headline/headline.json.",
    )
    h.add_argument("--strands", type=whole(1), default=4 * 1024 * 1024)
    h.add_argument("--points", type=whole(2), default=32)
    h.add_argument("--repeat", type=whole(1), default=9, help="GPU repetitions per stage (default 9)")
    h.add_argument("--cpu-repeat", type=whole(1), default=3, help="CPU repetitions per stage (default 3)")
    h.add_argument("--block-size", type=whole(32), default=256)
    h.add_argument("--out", default=None, help="results directory (default results/headline)")
    h.set_defaults(func=cmd_headline)

    e = sub.add_parser(
        "export",
        help="sidecars that ParaView/VisIt (XDMF) and Blender/Houdini/usdview (USD) open",
        description="Write STATE.xdmf + STATE.topo.h5 (polylines over time, positions "
        "referenced in STATE) and, with --usd, STATE.usdc (BasisCurves, one "
        "time sample per frame; needs usd-core).",
    )
    e.add_argument("state", help="an HDF5 state written by a hairsim binary")
    e.add_argument("--usd", action="store_true", help="also write the USD file")
    e.add_argument("--usd-only", action="store_true", help="write only the USD file")
    e.add_argument("--out", help="output prefix (default: the state's path)")
    e.set_defaults(func=cmd_export)

    c = sub.add_parser(
        "calibrate",
        help="measure fp32-vs-fp64 errors behind tolerances.py",
        description="Run the cpu binary at fp32 and fp64 on the paper scene and print "
        "the errors and invariant residuals that tolerances.py is set from.",
    )
    c.add_argument("--strands", type=whole(1), default=20000)
    c.add_argument("--points", type=whole(2), nargs="+", default=[8, 32, 128])
    c.add_argument("--seeds", type=whole(0), nargs="+", default=[1, 2, 3])
    c.add_argument(
        "--other",
        help="a second binary to compare with the cpu reference at each "
        "precision (e.g. build/hairsim-cuda on a GPU node)",
    )
    c.add_argument("--json", action="store_true")
    c.set_defaults(func=cmd_calibrate)

    fc = sub.add_parser(
        "featurecost",
        help="the dynamic model's time per frame with each feature undeclared, alone, and the full scene",
        description="Run a dynamic scene with every feature undeclared, each alone, the full scene "
        "less each, and the full scene (features are removed by their flags, so the binary compiles "
        "them out); print a Markdown table and, with --out, write the rows as CSV.",
    )
    fc.add_argument("--scene", default="dynamic", help="a dynamic scene (default dynamic)")
    fc.add_argument("--backend", choices=("cpu", "cuda"), default="cpu")
    fc.add_argument("--build", default="default", help="cuda build: default | strict | fastmath")
    fc.add_argument("--variant", default=None)
    fc.add_argument("--strands", type=whole(1), default=100_000)
    fc.add_argument("--points", type=whole(2), default=None)
    fc.add_argument("--frames", type=whole(1), default=3, help="frames per case (default 3)")
    fc.add_argument("--repeat", type=whole(1), default=3, help="timed repeats of each frame (default 3)")
    fc.add_argument("--threads", type=whole(1), default=None, help="cpu threads (default: all cores)")
    fc.add_argument("--block-size", type=whole(32), default=None)
    fc.add_argument("--timeout", type=seconds, default=None)
    fc.add_argument("--out", default=None, help="CSV file to write")
    fc.set_defaults(func=cmd_featurecost)
    return p


def main(argv=None):
    args = parser().parse_args(argv)
    try:
        return args.func(args)
    except HarnessError as e:
        print(f"harness: error: {e}", file=sys.stderr)
        return e.code if e.code else 2
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
    except BrokenPipeError:
        return 1


if __name__ == "__main__":
    sys.exit(main())
