"""Pictures of a state: `animate`, `render`."""

import argparse

from harness.cli.options import (
    command,
    options,
    whole,
)


def cmd_animate(args):
    """Draw the frames of a dynamic HDF5 state (read through harness.io.trajectory) seen from the side and from
    the front, the head sphere drawn, as a GIF (and an MP4 beside it where ffmpeg is on PATH). Without STATE,
    runs configs/scenes/dynamic.toml on hairsim-cpu first."""
    from harness.bench import animate_dynamic as animate

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


def add_animate(sub):
    an = command(sub, cmd_animate, help="an animation of a dynamic state from the side and from the front")
    an.add_argument("state", nargs="?", default=None, help="a dynamic state file (default: run the dynamic scene)")
    an.add_argument("--out", default=None, help="the GIF to write (default results/local/report/dynamic.gif)")
    an.add_argument("--max-strands", type=whole(1), default=150, help="strands drawn at most (default 150)")
    an.add_argument("--every", type=whole(1), default=None, help="draw every K-th frame (default: about 60 frames)")
    an.add_argument("--fps", type=whole(1), default=None, help="frames per second of the GIF (default: real time)")
    an.add_argument("--strands", type=whole(1), default=300, help="without STATE: strands simulated (default 300)")
    an.add_argument("--frames", type=whole(1), default=120, help="without STATE: frames simulated (default 120)")
    an.add_argument("--force", action="store_true", help="replace existing output files")


def add_render(sub):
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
