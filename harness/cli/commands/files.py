"""Files other tools open, and files from them: `export`, `groom convert`, `motion convert`."""

from harness.cli.options import (
    command,
)


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


def add_export(sub):
    e = command(sub, cmd_export, help="sidecars that ParaView/VisIt (XDMF) and Blender/Houdini/usdview (USD) open")
    e.add_argument("state", help="an HDF5 state written by a hairsim binary")
    e.add_argument("--usd", action="store_true", help="also write the USD file")
    e.add_argument("--usd-only", action="store_true", help="write only the USD file")
    e.add_argument("--hair", action="store_true", help="also write STATE.hair: one frame as a groom (--groom reads it)")
    e.add_argument("--hair-only", action="store_true", help="write only the HAIR file")
    e.add_argument("--frame", type=int, default=-1, help="the HAIR file's frame (default -1, the last; 0 the first)")
    e.add_argument("--out", help="output prefix (default: the state's path)")
    e.add_argument("--force", action="store_true", help="replace sidecars that exist (else refused, nothing written)")


def add_groom(sub):
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


def add_motion(sub):
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
