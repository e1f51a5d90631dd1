"""`harness render --animate` on a dynamic state of the C reference: the animation holds the
rest shape and every simulated frame, and the head drawn at each frame is turned by the Q(t)
that carried the strands' roots there (x_0(t) = Q(t)·X̄_0, docs/model.md §3.2)."""

import subprocess
import sys

import numpy as np
import pytest

from conftest import ROOT
from harness.io.trajectory import open_trajectory
from harness.render.gl import bodies, context
from support.statecheck import run

REASON = context.unavailable()


@pytest.fixture(scope="module")
def nodding(cpu_bin, tmp_path_factory):
    out = tmp_path_factory.mktemp("render-dyn") / "nod.h5"
    run(
        cpu_bin,
        "--strands", 30, "--points", 8, "--stages", "init,collide,simulate", "--frames", 12,
        "--head-motion", "shake", "--motion-amplitude", 0.6, "--motion-frequency", 2, "--precision", "fp64",
        "--output", out,
    )  # fmt: skip
    return out


def test_the_head_turns_with_the_roots(nodding):
    with open_trajectory(nodding) as t:
        rest_roots = t.rest[:, 0].astype(float)
        turned = 0
        for f in t.simulated:
            q = bodies.head(t, f).rotation
            roots = t.frame(f).reshape(t.n_strands, t.points, 3)[:, 0]
            assert np.abs(rest_roots @ q.T - roots).max() <= 1e-12 * 10
            turned += not np.allclose(q, np.eye(3))
        assert turned >= len(t.simulated) - 1  # it did turn
        assert np.array_equal(bodies.head(t, t.paper_frames - 1).rotation, np.eye(3))


@pytest.mark.skipif(REASON is not None, reason=f"no OpenGL on EGL: {REASON}")
def test_the_animation_holds_every_frame(nodding, tmp_path):
    from PIL import Image

    p = subprocess.run(
        [sys.executable, "-m", "harness", "render", nodding, "--out", tmp_path, "--animate", "--view", "front"]
        + ["--size", "80x60"],
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert p.returncode == 0, p.stderr
    gif = Image.open(tmp_path / "nod-front.gif")
    assert gif.n_frames == 13 and gif.size == (80, 60)  # the rest shape, then 12 simulated frames
    firsts = []
    for k in (0, 6):
        gif.seek(k)
        firsts.append(np.asarray(gif.convert("RGB")))
    assert np.abs(firsts[0].astype(int) - firsts[1].astype(int)).max() > 40  # the hair moved
