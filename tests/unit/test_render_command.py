"""`python -m harness render`: what it writes from a paper-model state, and what it refuses in
one line with exit 2 before writing anything (a bad file, an unknown view, an output that
exists without --force, a frame the file lacks, no EGL context)."""

import os
import subprocess
import sys

import numpy as np
import pytest

from conftest import ROOT
from harness.render.gl import context
from support.synthetic import radial_strands, write_state

REASON = context.unavailable()
needs_gl = pytest.mark.skipif(REASON is not None, reason=f"no OpenGL on EGL: {REASON}")


def harness(*args, env=None):
    return subprocess.run(
        [sys.executable, "-m", "harness", "render", *map(str, args)],
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=120,
        env={**os.environ, **(env or {})},
    )


@pytest.fixture(scope="module")
def paper_state(tmp_path_factory):
    stages = ("init", "collide", "wind", "collide")
    return write_state(tmp_path_factory.mktemp("render") / "paper.h5", radial_strands(40, 8), stages)


def one_line_error(p, words):
    assert p.returncode == 2, p.stderr
    lines = p.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("harness: error: render") and words in lines[0], p.stderr
    assert "Traceback" not in p.stderr


@needs_gl
def test_frames_and_views_are_written(paper_state, tmp_path):
    from PIL import Image

    p = harness(paper_state, "--out", tmp_path, "--frame", "0", "--frame", "-1", "--view", "all", "--size", "64x48")
    assert p.returncode == 0, p.stderr
    names = sorted(f.name for f in tmp_path.iterdir())
    assert names == sorted(f"paper-frame{k}-{v}.png" for k in (0, 3) for v in ("front", "side", "three-quarter"))
    img = np.asarray(Image.open(tmp_path / "paper-frame3-side.png"))
    assert img.shape == (48, 64, 3) and len(np.unique(img.reshape(-1, 3), axis=0)) > 10  # hair, not a blank


@needs_gl
def test_an_existing_output_is_kept_without_force(paper_state, tmp_path):
    mine = tmp_path / "paper-frame3-front.png"
    mine.write_bytes(b"the user's")
    p = harness(paper_state, "--out", tmp_path, "--size", "32x32")
    one_line_error(p, "exists (use --force")
    assert mine.read_bytes() == b"the user's" and len(list(tmp_path.iterdir())) == 1  # nothing else written
    assert harness(paper_state, "--out", tmp_path, "--size", "32x32", "--force").returncode == 0
    assert mine.read_bytes() != b"the user's"


@pytest.mark.parametrize(
    "args, words",
    [
        (("--view", "top"), "unknown view 'top'"),
        (("--frame", "9"), "has no frame 9"),
        (("--animate",), "no simulated frame to animate"),
        (("--size", "10x10"), "16…8192"),
    ],
)
def test_bad_input_is_refused_in_one_line(paper_state, tmp_path, args, words):
    p = harness(paper_state, "--out", tmp_path / "out", *args)
    one_line_error(p, words)
    assert not (tmp_path / "out").exists()


def test_a_file_that_is_not_a_state_is_refused(tmp_path):
    bad = tmp_path / "bad.h5"
    bad.write_text("not hdf5")
    p = harness(bad, "--out", tmp_path / "out")
    assert p.returncode == 2 and len(p.stderr.strip().splitlines()) == 1 and "Traceback" not in p.stderr
    assert not (tmp_path / "out").exists()


def test_no_egl_is_said_in_one_line(paper_state, tmp_path):
    """glvnd with no EGL vendor to load: no context, one line, exit 2, nothing written."""
    p = harness(paper_state, "--out", tmp_path / "out", env={"__EGL_VENDOR_LIBRARY_FILENAMES": "/nonexistent.json"})
    one_line_error(p, "render: no OpenGL" if REASON is None else "render:")
    assert not (tmp_path / "out").exists()
