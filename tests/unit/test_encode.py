"""Animations' MP4 through ffmpeg (harness/core/encode.py, started by the runner): ten frames of
an odd size give an MP4 beside the GIF, cut to even sizes, and nothing else is left in the
folder; skipped, saying why, where ffmpeg is not on PATH (the GIF alone is then written)."""

import shutil

import numpy as np
import pytest

from harness.render.gl import output


def test_an_animation_gets_an_mp4_beside_its_gif(tmp_path):
    if shutil.which("ffmpeg") is None:
        pytest.skip("ffmpeg is not on PATH: animations are GIFs only")
    frames = [np.full((31, 41, 3), 20 * i, np.uint8) for i in range(10)]
    written = output.write_animation(frames, tmp_path / "a.gif", 10)
    assert [p.name for p in written] == ["a.gif", "a.mp4"]
    assert (tmp_path / "a.mp4").read_bytes()[4:8] == b"ftyp"  # an ISO media file
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a.gif", "a.mp4"]  # no frames file, no temporary
