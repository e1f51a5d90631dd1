"""Frames encoded as H.264 video by ffmpeg, started through harness/core/runner.py like every
child (a signal reaching the harness reaches it, a kill leaves nothing). It encodes what it is
given and measures nothing; the renderers call it (tests/unit/test_layers.py lets them reach
the runner through here and through core.variants only)."""

import tempfile
from pathlib import Path

import numpy as np

from harness import HarnessError


def mp4(frames, path, fps, name=None):
    """`frames` (RGB arrays of one size) as an MP4 at `path` (the caller's temporary), cut to even
    sizes as yuv420p needs; the raw frames go through a temporary file beside it. `name`: how an
    error names the file."""
    from harness.core import runner

    h, w = np.shape(frames[0])[:2]
    h2, w2 = h - h % 2, w - w % 2
    with tempfile.NamedTemporaryFile(prefix=".frames-", suffix=".rgb", dir=Path(path).parent) as raw:
        for f in frames:
            raw.write(np.ascontiguousarray(np.asarray(f, np.uint8)[:h2, :w2]).tobytes())
        raw.flush()
        cmd = ["ffmpeg", "-loglevel", "error", "-y", "-f", "rawvideo", "-pix_fmt", "rgb24", "-s", f"{w2}x{h2}"]
        cmd += ["-r", str(fps), "-i", raw.name, "-pix_fmt", "yuv420p", "-c:v", "libx264", "-f", "mp4", str(path)]
        try:
            done = runner.run_command(cmd, timeout=600)
        except (OSError, runner.TimedOut) as e:
            raise HarnessError(f"render: ffmpeg could not write {name or path} ({e})") from None
    if done.returncode:
        why = done.stderr.strip().splitlines()
        raise HarnessError(f"render: ffmpeg could not write {name or path} ({why[-1] if why else done.returncode})")
    return Path(path)
