"""The renderer (harness/render/gl) on whatever EGL gives here (Mesa's llvmpipe in CI) with
known answers: a strand at known coordinates covers the pixels it should; a strand behind
the head is hidden by it and one in front is not; the hair's brightness follows
Kajiya–Kay's sin(T, L) against the light's angle; capsules and meshes land where they are
placed; a fixed small scene matches its committed image (tests/data/render_small_scene.png,
`python tests/unit/test_render.py` writes it again) within tolerances.RENDER_REFERENCE.
Skipped, with the reason, where no OpenGL context can be made on EGL."""

import math
import sys
from pathlib import Path

import numpy as np
import pytest

from harness.core import tolerances
from harness.render.gl import bodies, context
from harness.render.gl.camera import Camera, look_at, orthographic
from harness.render.gl.renderer import Renderer
from harness.render.gl.shading import Shading
from harness.render.gl.shadows import ShadowSettings

REASON = context.unavailable()
pytestmark = pytest.mark.skipif(REASON is not None, reason=f"no OpenGL on EGL: {REASON}")
REFERENCE = Path(__file__).resolve().parents[1] / "data" / "render_small_scene.png"
W, H = 200, 100
BACKGROUND = np.round(255 * np.asarray(Shading().background)).astype(int)


def front_camera(half_w=10.0, half_h=5.0):
    """Orthographic, from +z toward the origin: world (x, y) → pixel (100 + 10x, 50 − 10y)."""
    return Camera(look_at((0, 0, 50), (0, 0, 0)), orthographic(half_w, half_h, 1.0, 100.0), np.array([0, 0, 50.0]))


def covered(image):
    """Pixels that are not the background."""
    return np.any(np.abs(image.astype(int) - BACKGROUND) > 8, axis=2)


def straight(a, b, points=8):
    return np.linspace(a, b, points)[None]


def test_a_strand_covers_the_pixels_under_it():
    """x from −5 to 5 at y = 0.95, 3 px wide: the ribbon spans rows 39.0–42.0 and columns
    50.0–150.0 of the image (pixel edges), so exactly rows 39–41 × columns 50–149 are drawn."""
    with Renderer(W, H, shading=Shading(width_px=3.0)) as r:
        img = r.draw(straight((-5, 0.95, 0), (5, 0.95, 0)), [], front_camera())
    want = np.zeros((H, W), bool)
    want[39:42, 50:150] = True
    assert np.array_equal(covered(img), want), np.argwhere(covered(img) != want)[:5]


def test_a_strand_behind_the_head_is_hidden_and_one_in_front_is_not():
    head = bodies.Sphere((0.0, 0.0, 0.0), 4.0)
    behind = straight((-2, 0, -6), (2, 0, -6))
    front = straight((-2, 1, 6), (2, 1, 6))
    with Renderer(W, H, shading=Shading(width_px=3.0)) as r:
        alone = r.draw(behind, [], front_camera())
        hidden = r.draw(behind, [head], front_camera())
        head_only = r.draw(np.zeros((0, 2, 3)), [head], front_camera())
        over = r.draw(front, [head], front_camera())
    strand = covered(alone)
    assert strand[50, 85:115].all()  # drawn alone, the strand is there ...
    assert np.array_equal(hidden[strand], head_only[strand])  # ... and behind the head, not a pixel of it shows
    assert np.abs(over[40, 85:115].astype(int) - head_only[40, 85:115].astype(int)).max() > 40


@pytest.mark.parametrize("degrees", [0, 20, 45, 70, 90])
def test_hair_brightness_follows_kajiya_kay(degrees):
    """A fibre along x, lit from an angle θ to it: colour = albedo·kd·sin θ (no ambient,
    specular or shadow; gamma 1)."""
    albedo, kd = 0.8, 1.0
    shading = Shading(
        root_color=(albedo,) * 3,
        tip_color=(albedo,) * 3,
        tint_amount=0.0,
        ambient=0.0,
        kd=kd,
        ks=0.0,
        gamma=1.0,
        width_px=5.0,
    )
    theta = math.radians(degrees)
    light = (math.cos(theta), 0.0, math.sin(theta))
    with Renderer(W, H, shading=shading, shadows=ShadowSettings(enabled=False)) as r:
        img = r.draw(straight((-5, 0, 0), (5, 0, 0)), [], front_camera(), light=light)
    got = img[50, 60:140].astype(float) / 255
    want = albedo * kd * math.sin(theta)
    assert np.abs(got - want).max() <= tolerances.RENDER_QUANTUM * 1.5, (got.min(), got.max(), want)


def test_a_capsule_and_a_mesh_land_where_they_are_placed():
    """Each pixel whose centre lies inside the capsule's or the square's outline by more than
    a pixel is drawn, and none that lies outside by more than a pixel."""
    capsule = bodies.Capsule((-6.0, -2.0, 0.0), (-2.0, -2.0, 0.0), 1.0)
    square = bodies.Mesh(
        np.array([[0, 0, 0], [2, 0, 0], [2, 2, 0], [0, 2, 0]], float),
        np.array([[0, 1, 2], [0, 2, 3]]),
        transform=bodies.placement(None, (4.0, 1.0, 0.0)),
    )
    with Renderer(W, H) as r:
        img = r.draw(np.zeros((0, 2, 3)), [capsule, square], front_camera())
    rows, cols = np.mgrid[0:H, 0:W]
    x, y = (cols + 0.5 - 100) / 10, (50 - rows - 0.5) / 10  # pixel centres in the world (front_camera)
    to_capsule = np.hypot(x - np.clip(x, -6, -2), y + 2) - 1.0  # signed distance to the outline
    to_square = np.maximum(np.abs(x - 5) - 1, np.abs(y - 2) - 1)
    inside = np.minimum(to_capsule, to_square)
    hit = covered(img)
    pixel = 0.1
    assert hit[inside < -pixel].all()
    assert not hit[inside > pixel].any()


def small_scene():
    """60 strands hanging from a head of radius 4, a capsule for a neck; three-quarter view."""
    rng = np.random.default_rng(7)
    v = rng.normal(size=(60, 3))
    v[:, 1] = np.abs(v[:, 1])
    roots = 4.0 * v / np.linalg.norm(v, axis=1, keepdims=True)
    k = np.linspace(0, 1, 12)[None, :, None]
    out = roots / 4.0 * 3.0
    strands = roots[:, None] + k * (out[:, None] + np.array([0, -9.0, 0]) * k)
    head = bodies.Sphere((0.0, 0.0, 0.0), 4.0, face_marks=True)
    neck = bodies.Capsule((0.0, -7.0, 0.0), (0.0, -3.0, 0.0), 1.5)
    return strands, [head, neck]


def draw_small_scene():
    strands, solids = small_scene()
    with Renderer(160, 120) as r:
        return r.draw(strands, solids, r.camera("three-quarter", strands, solids))


def image_difference(a, b):
    """(fraction of pixels differing by more than RENDER_REFERENCE['level'] in a channel, mean |Δ|)."""
    d = np.abs(a.astype(int) - b.astype(int))
    return float(np.mean(d.max(axis=2) > tolerances.RENDER_REFERENCE["level"])), float(d.mean())


def test_a_small_scene_matches_its_committed_image():
    from PIL import Image

    want = np.asarray(Image.open(REFERENCE).convert("RGB"))
    got = draw_small_scene()
    assert got.shape == want.shape
    fraction, mean = image_difference(got, want)
    assert fraction <= tolerances.RENDER_REFERENCE["fraction"], (fraction, mean, context.describe())
    assert mean <= tolerances.RENDER_REFERENCE["mean"], (fraction, mean, context.describe())


if __name__ == "__main__":  # write the committed image again (after a deliberate change of the renderer)
    from PIL import Image

    sys.exit(Image.fromarray(draw_small_scene()).save(REFERENCE) or print(f"wrote {REFERENCE} on {context.describe()}"))
