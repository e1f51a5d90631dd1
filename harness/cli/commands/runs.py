"""Running one scene and comparing states: `run`, `stepdiff`, `diff`."""

import argparse
import json

from harness import HarnessError
from harness.cli.options import (
    binary_options,
    case_options,
    command,
    options,
    whole,
)


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


def add_run(sub):
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


def add_stepdiff(sub):
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


def add_diff(sub):
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
