"""Cameras: the named views and their matrices (row-major numpy; the renderer transposes
them for GL). docs/model.md §1.1: y up, the face looks along +z, x from side to side.

  front          the viewer faces the face (stands on +z)
  side           the head's profile with the face to the right (the viewer stands on −x),
                 as the paper's figures show it
  three-quarter  between the two, a little from above
"""

import math
from dataclasses import dataclass

import numpy as np

from harness import HarnessError

# where the viewer stands, as a direction from what is looked at
VIEWS = {
    "front": (0.0, 0.08, 1.0),
    "side": (-1.0, 0.08, 0.0),
    "three-quarter": (-0.72, 0.3, 0.72),
}
FOV_DEG = 30.0  # the vertical field of view (or the horizontal one, if narrower)
MARGIN = 1.04  # the fitted sphere's radius is enlarged by this much


def parse_views(text):
    """'front,side' → ('front', 'side'); 'all' → every view; an unknown name is refused."""
    names = tuple(VIEWS) if text == "all" else tuple(v.strip() for v in text.split(","))
    bad = [v for v in names if v not in VIEWS]
    if bad or not names:
        raise HarnessError(f"render: unknown view '{','.join(bad)}' (known: {', '.join(VIEWS)}, all)")
    return names


def look_at(eye, target, up=(0.0, 1.0, 0.0)):
    """The world → camera matrix (4×4) of a camera at `eye` looking at `target`."""
    eye, target = np.asarray(eye, float), np.asarray(target, float)
    f = target - eye
    f /= np.linalg.norm(f)
    r = np.cross(f, up)
    r /= np.linalg.norm(r)
    u = np.cross(r, f)
    m = np.eye(4)
    m[0, :3], m[1, :3], m[2, :3] = r, u, -f
    m[:3, 3] = -m[:3, :3] @ eye
    return m


def perspective(fov_y, aspect, near, far):
    """OpenGL's perspective projection (fov_y in radians)."""
    t = 1.0 / math.tan(fov_y / 2)
    m = np.zeros((4, 4))
    m[0, 0], m[1, 1] = t / aspect, t
    m[2, 2], m[2, 3] = (far + near) / (near - far), 2 * far * near / (near - far)
    m[3, 2] = -1.0
    return m


def orthographic(half_w, half_h, near, far):
    """OpenGL's orthographic projection of a box centred on the view axis."""
    m = np.eye(4)
    m[0, 0], m[1, 1] = 1.0 / half_w, 1.0 / half_h
    m[2, 2], m[2, 3] = -2.0 / (far - near), -(far + near) / (far - near)
    return m


@dataclass(frozen=True)
class Camera:
    view: np.ndarray  # world → camera
    projection: np.ndarray
    eye: np.ndarray  # world position

    @property
    def mvp(self):
        return self.projection @ self.view

    def to_pixels(self, points, width, height):
        """World points [n][3] → pixel (column, row) [n][2], row 0 at the top of the image."""
        p = np.c_[np.asarray(points, float), np.ones(len(points))] @ self.mvp.T
        ndc = p[:, :2] / p[:, 3:4]
        return np.c_[(ndc[:, 0] + 1) / 2 * width, (1 - ndc[:, 1]) / 2 * height]


def bounding_sphere(points):
    """(centre, radius) of an axis-aligned box around the finite points [n][3]."""
    p = np.asarray(points, float).reshape(-1, 3)
    p = p[np.all(np.isfinite(p), axis=1)]
    if not len(p):
        return np.zeros(3), 1.0
    lo, hi = p.min(axis=0), p.max(axis=0)
    return (lo + hi) / 2, max(float(np.linalg.norm(hi - lo)) / 2, 1e-6)


def fitted(view, points, aspect):
    """The perspective camera of a named view that holds every finite point [n][3], each
    side of the image MARGIN wider than the points reach."""
    if view not in VIEWS:
        raise HarnessError(f"render: unknown view '{view}' (known: {', '.join(VIEWS)})")
    p = np.asarray(points, float).reshape(-1, 3)
    p = p[np.all(np.isfinite(p), axis=1)]
    if not len(p):
        p = np.zeros((1, 3))
    back = np.asarray(VIEWS[view], float)
    basis = look_at(back / np.linalg.norm(back), (0.0, 0.0, 0.0))[:3, :3]  # rows: right, up, toward the viewer
    local = p @ basis.T
    lo, hi = local.min(axis=0), local.max(axis=0)
    mx, my = (lo[:2] + hi[:2]) / 2
    tan_y = math.tan(math.radians(FOV_DEG) / 2)
    tan_x = tan_y * aspect
    # the eye's distance along the view axis at which every point lies inside the frustum
    need = local[:, 2] + MARGIN * np.maximum(np.abs(local[:, 0] - mx) / tan_x, np.abs(local[:, 1] - my) / tan_y)
    size = max(float(np.max(hi - lo)), 1e-6)
    z_eye = max(float(need.max()), float(hi[2]) + 0.05 * size)
    near, far = 0.9 * (z_eye - hi[2]), 1.1 * (z_eye - lo[2]) + 1e-6
    eye = basis.T @ np.array([mx, my, z_eye])
    target = basis.T @ np.array([mx, my, (lo[2] + hi[2]) / 2])
    return Camera(look_at(eye, target), perspective(2 * math.atan(tan_y), aspect, near, far), eye)


def light_camera(direction, centre, radius):
    """The orthographic camera of a directional light (toward the light: `direction`) that
    holds the sphere (centre, radius); its depth range is 2·radius."""
    d = np.asarray(direction, float)
    d /= np.linalg.norm(d)
    up = (0.0, 0.0, 1.0) if abs(d[1]) > 0.99 else (0.0, 1.0, 0.0)
    eye = np.asarray(centre, float) + d * 2 * radius
    return Camera(look_at(eye, centre, up), orthographic(radius, radius, radius, 3 * radius), eye)
