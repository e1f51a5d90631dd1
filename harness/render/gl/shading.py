"""The light and the shading parameters of a frame.

Hair (Kajiya and Kay, 1989): with T the fibre's unit tangent, L the unit direction toward
the light, V toward the eye and H = (L + V)/|L + V|,

  colour = albedo·(ambient + kd·sin(T, L)·s) + ks·sin(T, H)^p·s·specular_color,

sin(T, X) = √(1 − (T·X)²), s the transmittance of the shadow (1 without shadows), then
each channel raised to 1/gamma. albedo runs from root_color at the root to tip_color at
the tip, scaled by 1 + tint_amount·u with u in [−1, 1] drawn once a strand. Bodies are
Lambert-shaded with the same light, ambient and gamma."""

from dataclasses import dataclass

import numpy as np

# the light's direction in camera space (x right, y up, z toward the viewer): up and to the left
CAMERA_LIGHT = (-0.45, 0.75, 0.5)


@dataclass(frozen=True)
class Shading:
    root_color: tuple = (0.07, 0.035, 0.018)
    tip_color: tuple = (0.26, 0.15, 0.075)
    specular_color: tuple = (1.0, 0.9, 0.78)
    tint_amount: float = 0.18
    ambient: float = 0.18
    kd: float = 0.95
    ks: float = 0.22
    shininess: float = 48.0
    gamma: float = 2.2
    width_px: float = 1.25  # the ribbon's width on the screen
    background: tuple = (0.93, 0.93, 0.92)  # as written, not gamma-corrected


def world_light(camera, direction=None):
    """The unit direction toward the light in world space: `direction` as given (world), or
    CAMERA_LIGHT turned with the camera."""
    if direction is not None:
        d = np.asarray(direction, float)
    else:
        d = camera.view[:3, :3].T @ np.asarray(CAMERA_LIGHT, float)
    return d / np.linalg.norm(d)
