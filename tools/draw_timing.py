"""Time --draw on the GPU against issue #44's targets (not a test: a measurement). For each
strand count, the default dynamic scene (configs/scenes/dynamic.toml, 32 points a strand) is
simulated and drawn at 1920×1080 by build/hairsim-cuda, and the record's draw times are
printed beside the targets:

  drawing 10,000 strands ≤ 0.5 ms, 100,000 ≤ 2 ms, 1,000,000 ≤ 15 ms (GPU time of the draw);
  simulation + drawing of the default scene at 100,000 strands ≤ 3 ms a frame.

  python3 tools/draw_timing.py [--binary build/hairsim-cuda] [--frames 40] [--variant lanes]

Each line: strands, the path, the simulation, the draw, both per frame, and whether each
target is met."""

import argparse
import json
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

DRAW_TARGETS = {10_000: 0.5, 100_000: 2.0, 1_000_000: 15.0}  # ms, the draw alone
FRAME_TARGET = (100_000, 3.0)  # ms, simulation + drawing of the default scene


def measure(binary, strands, frames, variant):
    """The record's draw object: the default scene at `strands`, F = `frames` frames run, then
    F more simulated and drawn at 1920×1080 (docs/interfaces.md, "Drawing on the GPU")."""
    from harness.core import runner, scenes

    scene = scenes.with_frames(scenes.load_scene("dynamic").with_overrides(strands=strands), frames)
    cmd = [str(binary), *map(str, runner.run_flags(scene, "cuda", variant=variant))]
    cmd += ["--draw", "1920x1080", "--json", "--quiet"]
    p = subprocess.run(cmd, capture_output=True, text=True, timeout=1800)
    if p.returncode != 0:
        raise SystemExit(f"{' '.join(cmd)}: exit {p.returncode}: {p.stderr.strip()}")
    return json.loads(p.stdout)["stages"][-1]["draw"]


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--binary", default=str(ROOT / "build" / "hairsim-cuda"))
    ap.add_argument("--frames", type=int, default=40)
    ap.add_argument("--variant", default=None, help="a simulate variant (default: lanes, else the first declared)")
    args = ap.parse_args()
    if args.variant is None:
        from harness.core import variants

        running = variants.declared("cuda").running("simulate", points=32)
        args.variant = "lanes" if "lanes" in running else running[0]
    print(f"{args.binary} --variant {args.variant}, 1920x1080, {args.frames} frames drawn")
    print("strands   path     simulate_ms  draw_ms  frame_ms  targets")
    for n in (10_000, 100_000, 1_000_000):
        d = measure(args.binary, n, args.frames, args.variant)
        rows = [("compute", d["compute_ms"], d["compute_frame_ms"])]
        rows.append(("gl", d["gl_ms"], d["gl_frame_ms"]) if d["gl"] else ("gl", None, None))
        for path, draw, frame in rows:
            if draw is None:
                print(f"{n:>9,}  {path:<7}  no OpenGL path: {d['gl_missing']}")
                continue
            ok = [f"draw ≤ {DRAW_TARGETS[n]} ms: {'met' if draw <= DRAW_TARGETS[n] else 'NOT met'}"]
            if n == FRAME_TARGET[0]:
                ok.append(f"frame ≤ {FRAME_TARGET[1]} ms: {'met' if frame <= FRAME_TARGET[1] else 'NOT met'}")
            extra = f" (+ {d['gl_write_ms']:.3f} ms writing the vertex buffer)" if path == "gl" else ""
            print(f"{n:>9,}  {path:<7}  {d['simulate_ms']:>11.3f}  {draw:>7.3f}{extra}  {frame:>8.3f}  {'; '.join(ok)}")
        if d["gl"]:
            print(f"           gl: {d['gl']}")


if __name__ == "__main__":
    main()
