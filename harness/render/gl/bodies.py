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
    )
    return np.asarray(q).reshape(3, 3)


def head(traj, frame):
    """The head sphere of frame `frame`: radius head_radius about the origin, turned by Q(t)."""
    return Sphere((0.0, 0.0, 0.0), float(traj.params["head_radius"]), head_rotation_at(traj, frame), face_marks=True)


def of_frame(traj, frame):
    """Every solid body of frame `frame` of a state, placed for that frame: the one place a
    state's bodies are listed (today the head; colliders the model gains go here, as Capsule
    or Mesh with their transforms of the frame), so every render draws them."""
    return [head(traj, frame)]
