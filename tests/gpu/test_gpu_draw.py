"""--draw on the GPU (docs/interfaces.md "Drawing on the GPU"), both paths with known answers:
two strands that stay where they are placed (no gravity, wind or head motion; segments at
their rest length) drawn at 682×682, the view 10 px a cm (E = R + h + L = 34.1 cm):

  A  along x from −12 to 12 cm at y = 15.05, z = 12 (in front): row 341 − 150.5 → 190,
     columns 341 + 10x → 221 to 461;
  B  along x at y = 0.05, z = −12 (behind the head, R = 10): row 340, hidden where the head
     covers it (|x| < 10 cm), drawn beside it.

The compute path must draw exactly those pixels; the OpenGL path the same rows, its ends within
a pixel (GL's line rule). Where EGL gives no context the GL checks skip with the binary's reason.
Marked `gpu`; conftest.py skips them where there is no usable GPU."""

import json
import math

import numpy as np
import pytest

from conftest import CUDA_BIN
from harness import HarnessError
from harness.core import variants
from support.statecheck import run
from support.synthetic import crafted_state

pytestmark = pytest.mark.gpu

P, SIZE, PX_CM = 9, 682, 10
A = [(-12.0 + 3 * k, 15.05, 12.0) for k in range(P)]
B = [(-12.0 + 3 * k, 0.05, -12.0) for k in range(P)]
STILL = ["--stages", "simulate", "--gravity", "0", "--frames", "8"]
try:  # every simulating variant: the strand variant's positions are point-major, the others' canonical
    VARIANTS = variants.declared("cuda").running("simulate", points=P)
except HarnessError:
    VARIANTS = ()


@pytest.fixture(scope="module", params=VARIANTS)
def drawn(tmp_path_factory, request):
    from PIL import Image

    work = tmp_path_factory.mktemp("gpu_draw")
    state = crafted_state(work / "two.h5", [A, B], precision="fp32", L=24.0)
    draw = ["--draw", f"{SIZE}x{SIZE}", "--draw-image", work / "img", "--json"]
    p = run(CUDA_BIN, "--input", state, "--variant", request.param, *STILL, *draw)
    record = json.loads(p.stdout)["stages"][-1]["draw"]
    images = {}
    for path in ("compute", "gl"):
        f = work / f"img-{path}.ppm"
        images[path] = np.asarray(Image.open(f).convert("RGB")).astype(int) if f.exists() else None
    return record, images, p.stderr


BACKGROUND = np.array([0xEE, 0xEE, 0xEB])  # cuda/draw/view.cuh kBackground


def hit(img, row, col):
    """A pixel that is not the background."""
    return int(np.abs(img[row, col] - BACKGROUND).max()) > 12


def over_head(img, row, col):
    """A pixel that is not the head's smooth shading two rows above it."""
    return int(np.abs(img[row, col] - img[row - 2, col]).max()) > 12


def test_the_record_times_both_paths(drawn):
    record, images, stderr = drawn
    assert record["width"] == SIZE and record["frames"] == 8
    for key in ("simulate_ms", "compute_ms", "compute_frame_ms"):
        assert math.isfinite(record[key]) and record[key] > 0, record
    if record["gl"] is None:
        assert record["gl_missing"] and "no OpenGL path" in stderr
        assert images["gl"] is None
    else:
        assert record["gl_missing"] is None
        for key in ("gl_write_ms", "gl_ms", "gl_frame_ms"):
            assert math.isfinite(record[key]) and record[key] > 0, record


@pytest.mark.parametrize("path", ["compute", "gl"])
def test_a_strand_at_known_coordinates_covers_its_pixels(drawn, path):
    record, images, _ = drawn
    img = images[path]
    if img is None:
        pytest.skip(f"no OpenGL path here: {record['gl_missing']}")
    slack = 0 if path == "compute" else 1
    row = 190
    assert all(hit(img, row, c) for c in range(221 + slack, 461 - slack)), path
    assert not any(hit(img, r, c) for r in (187, 188, 192, 193) for c in range(221, 462)), path
    assert not hit(img, row, 219) and not hit(img, row, 463)


@pytest.mark.parametrize("path", ["compute", "gl"])
def test_a_strand_behind_the_head_is_hidden(drawn, path):
    record, images, _ = drawn
    img = images[path]
    if img is None:
        pytest.skip(f"no OpenGL path here: {record['gl_missing']}")
    row = 340
    inside = [c for c in range(SIZE) if abs((c + 0.5 - 341) / PX_CM) < 9.5]
    beside = [c for c in range(SIZE) if 10.5 < abs((c + 0.5 - 341) / PX_CM) < 11.5]
    assert not any(over_head(img, row, c) for c in inside), path
    assert all(hit(img, row, c) for c in beside), path
