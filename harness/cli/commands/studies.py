"""The studies' commands: `budget`, `hair`, `calibrate`, `analytic`, `featurecost`, `world`, `reduced`, `peer`,
`stability`, `judge`."""

import argparse
import json
import sys

from harness import HarnessError
from harness.cli.options import (
    REPORT_DIR_HELP,
    binary_options,
    case_options,
    command,
    number,
    options,
    output_options,
    positive,
    seconds,
    whole,
)
from harness.studies import peer_dynamic as peer
from harness.studies import reduced_dynamic as reduced


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


def cmd_world(args):
    """The grid's and the colliders' variants against their converged references (studies/accuracy_world_dynamic.py):
    write world.csv into --out and print the report's section."""
    from harness.render import accuracy_world_dynamic_report as accuracy_world_report
    from harness.studies import accuracy_world_dynamic as accuracy_world

    plan = accuracy_world.Plan.quick(gpu=args.gpu) if args.quick else accuracy_world.Plan(gpu=args.gpu)
    path = accuracy_world.run_study(plan, out_dir=args.out)
    print("\n".join(accuracy_world_report.section(path.parent)))
    return 0


def cmd_reduced(args):
    """Run a dynamic scene at 1,000 and 10,000 strands (--quick: 200 and 1,000) with guide fractions 100 … 1%
    x scheme (one, blend3), LRA off/on at few iterations under a fast nod, and P_s simulated points written as
    P_r = 33 (--render-points); compare each with a converged reference in which every strand and point is
    simulated (xpbd, fp64, S doubled until it is ten times closer than the rows it ranks) up to the scene's
    predictability time, and with the reference ensemble's statistics over the whole run; time it on the cpu
    oracle and, with a usable GPU, the cuda variants that run it (each distinct timing once: a setting shared by
    both strand counts is timed at the timing's own size once; docs/model.md §3.14); and the still scene with
    and without sag-free rest at two shape ranges: how far it sags, and the tip's swing under a wind step.
    Prints Markdown; --out writes the rows as CSV and references.csv beside it once every row is measured, the
    rows so far kept in OUT.partial until then; --resume finishes a stopped run, its timings kept."""
    from harness.render import reduced_dynamic_report as reduced_report
    from harness.studies import reduced_partial_dynamic as reduced_partial

    base = reduced.Plan.quick if args.quick else reduced.Plan
    changes = {k: v for k, v in (("scene", args.scene), ("seconds", args.seconds)) if v}
    if args.strands:
        changes["strands"] = tuple(args.strands)
    if args.parts:
        changes["parts"] = tuple(args.parts)
    if args.solvers:
        changes["solvers"] = tuple(s for s in reduced.SOLVERS if s in args.solvers)
    if args.out and not args.resume:
        reduced_partial.refuse_unfinished(args.out)
    refs = []
    rows = reduced.measure(base(gpu=args.gpu, **changes), out=args.out, refs_into=refs, resume=args.resume)
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
        add=args.add,
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


def cmd_analytic(args):
    """The analytic checks of docs/model.md §4 swept over S on the C reference, printed as
    docs/analytic.md's Markdown tables."""
    from pathlib import Path

    from harness.core.paths import binary_path, display
    from harness.render import analytic_dynamic_report
    from harness.studies import analytic_table_dynamic

    binary = Path(args.binary) if args.binary else binary_path("cpu")
    if not binary.is_file():
        raise HarnessError(f"{display(binary)} is not built (run make cpu)")
    sweeps = analytic_table_dynamic.measure(str(binary), args.quick)
    print("\n".join(analytic_dynamic_report.lines(sweeps)))
    return 0


def add_budget(sub):
    bu = command(sub, cmd_budget, help="a frame budget's answer: the most accurate mode that fits, from measured data")
    bu.add_argument("--strands", type=whole(1), required=True, help="strands simulated a frame")
    bu.add_argument("--frame-ms", type=positive, required=True, help="the simulation's budget, ms a frame")
    bu.add_argument("--scene", default="dynamic", help="the scene whose data to use (default dynamic)")
    bu.add_argument("--gpu", default=None, help="only the GPU whose name holds this (e.g. H200); default: every device")
    bu.add_argument("--run", default=None, help="the run folder (default results/local, make bench's)")
    bu.add_argument("--json", action="store_true", help="print the answer as JSON")


def add_hair(sub):
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


def add_calibrate(sub):
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


def add_analytic(sub):
    a = command(sub, cmd_analytic, help="the dynamic model's analytic checks swept over S, as Markdown tables")
    a.add_argument("--binary", default=None, help="the C reference to run (default build/hairsim-cpu)")
    a.add_argument("--quick", action="store_true", help="fewer S (a smoke run)")


def add_featurecost(sub):
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


def add_world(sub):
    wd = command(sub, cmd_world, help="the hair-hair grid and the colliders: cost against effect against the "
                 "converged reference")  # fmt: skip
    wd.add_argument("--quick", action="store_true", help="fewer strands, sizes and seconds (a minute on 2 cores)")
    wd.add_argument("--out", default=None, help="results folder (default results/accuracy-world)")
    wd.add_argument("--gpu", choices=("auto", "no"), default="auto", help="time each variant on the GPU too (auto)")


def add_reduced(sub):
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
    rd.add_argument(
        "--solvers",
        nargs="+",
        choices=reduced.SOLVERS,
        default=None,
        help="whose rows to measure (default both: xpbd ftl); the two solvers share no timing, so a study split "
        "by solver times each setting once",
    )
    rd.add_argument("--quick", action="store_true", help="the small version (CI, a first look)")
    case_options(rd, gpu="the cuda variants too, where a GPU is usable", gpu_choices=("auto", "no"))
    rd.add_argument(
        "--out", default=None, help="CSV file to write (OUT.partial keeps the rows while they are measured)"
    )
    rd.add_argument(
        "--resume",
        action="store_true",
        help="finish a stopped run with the same options: the timings in OUT.partial are kept, the rest measured "
        "again (refused where they were timed on another device, plan or revision)",
    )


def add_peer(sub):
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


def add_stability(sub):
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
    sb.add_argument(
        "--add",
        action="store_true",
        help="the slices replace or join those of the map already in --out (same revision, machine and size): a "
        "map measured over several calls",
    )
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


def add_judge(sub):
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
