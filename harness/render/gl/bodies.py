"""Solid bodies drawn with the hair: spheres, capsules (two end points and a radius) and
triangle meshes, each with its transform of the frame. `head(traj, frame)` is the head
sphere of a state (docs/model.md §3.2: R = head_radius about the origin, turned by Q(t) of
the file's head motion); `of_frame(traj, frame)` lists every body of a frame, and
renderer.Renderer.draw(strands, bodies, camera) draws any list of them.

Every body becomes (vertices, normals, triangles) in its own space and a 4×4 model matrix
(a rotation and a translation, no scale) that places it in the world."""

from dataclasses import dataclass, field

import numpy as np

from harness.check.invariants_dynamic import frame_end_time, head_rotation
from harness.render.gl import geometry

SKIN = (0.80, 0.62, 0.50)


def placement(rotation=None, translation=(0.0, 0.0, 0.0)):
    """The 4×4 model matrix of a rotation (3×3, default none) then a translation."""
    m = np.eye(4)
    if rotation is not None:
        m[:3, :3] = np.asarray(rotation, float).reshape(3, 3)
    m[:3, 3] = translation
    return m


@dataclass(frozen=True)
class Sphere:
    centre: tuple
    radius: float
    rotation: object = None  # 3×3, the body's turn this frame (shows through its face marks)
    color: tuple = SKIN
    face_marks: bool = False  # two eyes on its +z side

    def mesh(self):
        return geometry.sphere_mesh(self.radius)

    def model(self):
        return placement(self.rotation, self.centre)


@dataclass(frozen=True)
class Capsule:
    a: tuple
    b: tuple
    radius: float
    color: tuple = SKIN
    face_marks: bool = False

    def mesh(self):
        return geometry.capsule_mesh(float(np.linalg.norm(np.subtract(self.b, self.a))), self.radius)

    def model(self):
        """The rotation that takes +y onto b − a, then a."""
        axis = np.subtract(self.b, self.a, dtype=float)
        n = np.linalg.norm(axis)
        y = axis / n if n > 0 else np.array([0.0, 1.0, 0.0])
        helper = np.array([1.0, 0.0, 0.0]) if abs(y[0]) < 0.9 else np.array([0.0, 0.0, 1.0])
        x = np.cross(y, helper)
        x /= np.linalg.norm(x)
        z = np.cross(x, y)
        return placement(np.stack([x, y, z], axis=1), self.a)


@dataclass(frozen=True)
class Mesh:
    vertices: np.ndarray  # [n][3], the body's own space
    triangles: np.ndarray  # [m][3] vertex indices
    transform: np.ndarray = field(default_factory=lambda: np.eye(4))  # rotation + translation
    color: tuple = SKIN
    face_marks: bool = False

    def mesh(self):
        v = np.asarray(self.vertices, float)
        return v, geometry.vertex_normals(v, self.triangles), np.asarray(self.triangles, np.int64)

    def model(self):
        return np.asarray(self.transform, float)


def head_rotation_at(traj, frame):
    """Q(t) of frame `frame` of a state (3×3, double): the identity for the paper frames
    and a still head, else §3.2's rotation at the frame's end time."""
    params = getattr(traj, "dynamic_params", {}) or {}
    if not getattr(traj, "is_dynamic", False) or traj.head_motion == "still" or frame < traj.paper_frames:
        return np.eye(3)
    q = head_rotation(
        traj.head_motion,
        float(params["motion_amplitude"]),
        float(params["motion_frequency"]),
        frame_end_time(traj, frame),
        getattr(traj, "motion_track", None),
    )
    return np.asarray(q).reshape(3, 3)


def head(traj, frame):
    """The head sphere of frame `frame`: radius head_radius about the origin, turned by Q(t)."""
    return Sphere((0.0, 0.0, 0.0), float(traj.params["head_radius"]), head_rotation_at(traj, frame), face_marks=True)


BODY = (0.55, 0.58, 0.66)  # colliders of docs/model.md §3.17


def _mesh_file(traj, collider):
    """A mesh collider's OBJ file beside the colliders file the run named, if it is still there."""
    import os

    cols = str(traj.dynamic_params.get("colliders_file", ""))
    path = os.path.join(os.path.dirname(cols), collider.source) if cols else collider.source
    return path if collider.source and os.path.isfile(path) else None


def _read_obj(path):
    verts, tris = [], []
    with open(path) as f:
        for line in f:
            w = line.split()
            if w and w[0] == "v":
                verts.append([float(x) for x in w[1:4]])
            elif w and w[0] == "f":
                idx = [int(x.split("/")[0]) for x in w[1:]]
                idx = [i - 1 if i > 0 else len(verts) + i for i in idx]
                tris += [(idx[0], idx[k], idx[k + 1]) for k in range(1, len(idx) - 1)]
    return np.array(verts), np.array(tris, dtype=np.int64)


def colliders(traj, frame):
    """The colliders of a state (docs/model.md §3.17) placed at frame `frame`: spheres and
    capsules as drawn bodies, a mesh from its OBJ file where that file is still beside the
    colliders file (the state holds its SDF, not its triangles); planes are not drawn."""
    from harness.check.colliders_dynamic import body_translation

    if not getattr(traj, "colliders", None) or frame < traj.paper_frames:
        return []
    t = frame_end_time(traj, frame)
    q = head_rotation_at(traj, frame)
    b = body_translation(traj.dynamic_params, t)
    out = []
    for c in traj.colliders:
        place = (lambda p: q @ np.asarray(p)) if c.frame == "head" else (lambda p: np.asarray(p) + b)
        g = c.geometry
        if c.kind == "sphere":
            out.append(Sphere(tuple(place(g[:3])), float(g[3]), color=BODY))
        elif c.kind == "capsule":
            out.append(Capsule(tuple(place(g[:3])), tuple(place(g[3:6])), float(g[6]), color=BODY))
        elif c.kind == "mesh" and _mesh_file(traj, c):
            v, tri = _read_obj(_mesh_file(traj, c))
            m = placement(q) if c.frame == "head" else placement(None, b)
            out.append(Mesh(v, tri, m, color=SKIN))
    return out


def of_frame(traj, frame):
    """Every solid body of frame `frame` of a state, placed for that frame: the one place a
    state's bodies are listed (the head and the colliders of §3.17), so every render draws them."""
    return [head(traj, frame), *colliders(traj, frame)]
