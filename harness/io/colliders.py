"""The colliders a dynamic state file holds (docs/interfaces.md: /parameters/colliders and each
mesh's /parameters/collider_sdf_<i>), as the binaries wrote them (docs/model.md §3.17)."""

from dataclasses import dataclass

import numpy as np

from harness.io.states import StateError, as_text

KINDS = ("sphere", "capsule", "plane", "mesh")
FRAMES = ("head", "body")
ROW = 13  # kind, frame, geometry[7], μ_s, μ_k, SDF nodes a side, band


@dataclass
class Collider:
    kind: str  # sphere | capsule | plane | mesh
    frame: str  # head | body
    geometry: np.ndarray  # at rest: sphere c, r; capsule a, b, r; plane o, n
    mu_s: float
    mu_k: float
    sdf: np.ndarray = None  # a mesh's field [n][n][n] (z, y, x), double
    sdf_lo: np.ndarray = None
    sdf_spacing: float = 0.0
    source: str = ""


def read_colliders(f, path, n):
    """The n colliders of the open h5py file f; a StateError naming `path` when they do not fit."""
    p = f["parameters"]
    if "colliders" not in p or p["colliders"].shape != (n, ROW):
        raise StateError(f"{path}: /parameters/colliders is not a [{n}][{ROW}] dataset")
    rows = p["colliders"][()]
    out = []
    for i, r in enumerate(rows):
        kind, frame = int(r[0]), int(r[1])
        if not (0 <= kind < len(KINDS) and 0 <= frame < len(FRAMES)):
            raise StateError(f"{path}: /parameters/colliders row {i} has kind {kind} or frame {frame} out of range")
        c = Collider(KINDS[kind], FRAMES[frame], np.array(r[2:9], float), float(r[9]), float(r[10]))
        if c.kind == "mesh":
            name = f"collider_sdf_{i}"
            nodes = int(r[11])
            if name not in p or p[name].shape != (nodes**3,):
                raise StateError(f"{path}: /parameters/{name} is not a [{nodes}³] dataset")
            d = p[name]
            c.sdf = d[()].reshape(nodes, nodes, nodes)
            c.sdf_lo = np.array(d.attrs["lo"], float)
            c.sdf_spacing = float(d.attrs["spacing"])
            c.source = as_text(d.attrs.get("source", ""))
        out.append(c)
    return out
