"""Closed triangle meshes the project makes itself, as Wavefront OBJ (docs/model.md §3.17):
icospheres (a sphere, or an ellipsoid by scaling) with outward, consistent winding, for the
colliders' tests and the default body's head mesh (configs/bodies/)."""

from pathlib import Path

import numpy as np

from harness import HarnessError

_T = (1.0 + 5.0**0.5) / 2.0
_ICO_V = [(-1, _T, 0), (1, _T, 0), (-1, -_T, 0), (1, -_T, 0), (0, -1, _T), (0, 1, _T),
          (0, -1, -_T), (0, 1, -_T), (_T, 0, -1), (_T, 0, 1), (-_T, 0, -1), (-_T, 0, 1)]  # fmt: skip
_ICO_F = [(0, 11, 5), (0, 5, 1), (0, 1, 7), (0, 7, 10), (0, 10, 11), (1, 5, 9), (5, 11, 4), (11, 10, 2), (10, 7, 6),
          (7, 1, 8), (3, 9, 4), (3, 4, 2), (3, 2, 6), (3, 6, 8), (3, 8, 9), (4, 9, 5), (2, 4, 11), (6, 2, 10),
          (8, 6, 7), (9, 8, 1)]  # fmt: skip


def icosphere(level, radius=1.0, center=(0.0, 0.0, 0.0), scale=(1.0, 1.0, 1.0)):
    """(vertices [V][3], faces [F][3]) of an icosphere subdivided `level` times (20·4^level faces),
    of `radius` about `center`, stretched by `scale` per axis (an ellipsoid); faces wind
    counter-clockwise seen from outside."""
    if not (isinstance(level, int) and 0 <= level <= 7):
        raise HarnessError(f"icosphere: level must be a whole number from 0 to 7 (got {level!r})")
    verts = [np.array(v, float) / np.linalg.norm(v) for v in _ICO_V]
    faces = list(_ICO_F)
    for _ in range(level):
        mid = {}

        def middle(a, b):
            key = (min(a, b), max(a, b))
            if key not in mid:
                m = verts[a] + verts[b]
                verts.append(m / np.linalg.norm(m))
                mid[key] = len(verts) - 1
            return mid[key]

        faces = [
            f
            for a, b, c in faces
            for f in ((a, middle(a, b), middle(c, a)), (b, middle(b, c), middle(a, b)),
                      (c, middle(c, a), middle(b, c)), (middle(a, b), middle(b, c), middle(c, a)))
        ]  # fmt: skip
    v = np.array(verts) * radius * np.asarray(scale, float) + np.asarray(center, float)
    return v, np.array(faces, dtype=np.int64)


def obj_text(vertices, faces, comment=""):
    """The OBJ text of a mesh: `v x y z` lines (%.17g, exact in double) and 1-based `f a b c`."""
    head = "".join(f"# {line}\n" for line in comment.splitlines())
    vs = "".join(f"v {x!r} {y!r} {z!r}\n" for x, y, z in np.asarray(vertices, float).tolist())
    fs = "".join(f"f {a + 1} {b + 1} {c + 1}\n" for a, b, c in np.asarray(faces).tolist())
    return head + vs + fs


def write_obj(path, vertices, faces, comment=""):
    """Write the mesh at path (whole or not at all)."""
    from harness.io.files import write_text

    return write_text(Path(path), obj_text(vertices, faces, comment))
