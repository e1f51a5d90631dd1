"""The depth of points inside the colliders of a dynamic file (docs/model.md §3.17, §3.8's
penetration_max), in double from the stored values, independently of the binaries: each
collider placed at time t (a head collider turned by Q(t), a body collider moved by the body's
motion), a mesh through the trilinear value of its stored SDF."""

import math

import numpy as np

from harness.check.head_motion_dynamic import head_rotation


def body_translation(params, t):
    """b(t) of the body frame (docs/model.md §3.17), in double."""
    motion = params.get("body_motion", "still")
    motion = motion.decode() if isinstance(motion, bytes) else str(motion)
    a, f = float(params.get("body_amplitude", 0.0)), float(params.get("body_frequency", 0.0))
    if motion == "sway":
        return np.array([a * math.sin(2.0 * math.pi * f * t), 0.0, 0.0])
    if motion == "rise":
        rest = 1.0 - f * t
        return np.array([0.0, -a * rest if rest > 0.0 else 0.0, 0.0])
    return np.zeros(3)


def _rot(q, a):
    """Q·a with each row summed left to right (c_ref/dynamic/colliders.c rot)."""
    return np.array([(q[3 * i] * a[0] + q[3 * i + 1] * a[1]) + q[3 * i + 2] * a[2] for i in range(3)])


def _sdf_value(sdf, lo, scale, u):
    """Trilinear value of a mesh's SDF at mesh-frame points u [M][3] (corners in the binaries'
    order, contact_impl.h); NaN outside its cube."""
    n = sdf.shape[0]
    g = (u - lo) * scale
    inside = np.all((g >= 0) & (g < n - 1), axis=1)
    i = np.clip(np.floor(g).astype(np.int64), 0, n - 2)
    f = g - i
    val = np.zeros(len(u))
    for k in range(8):
        a, b, cc = k & 1, (k >> 1) & 1, (k >> 2) & 1
        w = ((f[:, 0] if a else 1 - f[:, 0]) * (f[:, 1] if b else 1 - f[:, 1])) * (f[:, 2] if cc else 1 - f[:, 2])
        val = val + w * sdf[i[:, 2] + cc, i[:, 1] + b, i[:, 0] + a]
    return np.where(inside, val, np.nan)


def depths(traj, points, t):
    """The depth of each point [M][3] in each collider at time t: [ncol][M] (≤ 0 outside; NaN
    where a mesh's cube does not reach). The poses, the mesh's field and its cube are rounded to
    the file's working precision first, as the binaries hold them; the rest is double."""
    params = traj.dynamic_params
    rnd = (lambda a: np.asarray(a, np.float32).astype(np.float64)) if traj.dtype == np.float32 else np.asarray
    q = [1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0]
    turns = traj.head_motion != "still"
    if turns:
        q = head_rotation(
            traj.head_motion, float(params["motion_amplitude"]), float(params["motion_frequency"]), t, traj.motion_track
        )
    b = body_translation(params, t)
    cm = float(params.get("collision_margin", 0.0))
    x = np.asarray(points, float).reshape(-1, 3)
    out = []
    for c in traj.colliders:
        g = c.geometry

        def place(a, c=c):
            return _rot(q, a) if c.frame == "head" else np.asarray(a) + b

        if c.kind in ("sphere", "capsule"):
            if c.kind == "sphere":
                centre, r = rnd(place(g[:3]))[None, :], float(rnd(g[3] + cm))
            else:
                a, bb, r = rnd(place(g[:3])), rnd(place(g[3:6])), float(rnd(g[6] + cm))
                e = g[3:6] - g[:3]
                l2 = float(rnd((e[0] * e[0] + e[1] * e[1]) + e[2] * e[2]))
                ab = bb - a
                s = np.clip(
                    (((x[:, 0] - a[0]) * ab[0] + (x[:, 1] - a[1]) * ab[1]) + (x[:, 2] - a[2]) * ab[2]) / l2, 0, 1
                )
                centre = a + s[:, None] * ab
            e = x - centre
            out.append(r - np.sqrt((e[:, 0] * e[:, 0] + e[:, 1] * e[:, 1]) + e[:, 2] * e[:, 2]))
        elif c.kind == "plane":
            o = rnd(place(g[:3]))
            n = rnd(_rot(q, g[3:6]) if c.frame == "head" else g[3:6])
            rho = ((x[:, 0] - o[0]) * n[0] + (x[:, 1] - o[1]) * n[1]) + (x[:, 2] - o[2]) * n[2]
            out.append(float(rnd(cm)) - rho)
        else:
            if c.frame == "head" and turns:  # u = Qᵀ·x, column c summed top to bottom
                qr = rnd(q)
                u = np.stack([(qr[c_] * x[:, 0] + qr[3 + c_] * x[:, 1]) + qr[6 + c_] * x[:, 2] for c_ in range(3)], 1)
            elif c.frame == "body" and params.get("body_motion", "still") not in ("still", b"still"):
                u = x - rnd(b)
            else:
                u = x
            lo, scale = rnd(c.sdf_lo), float(rnd(1.0 / c.sdf_spacing))
            out.append(float(rnd(cm)) - _sdf_value(rnd(c.sdf), lo, scale, u))
    return np.array(out) if out else np.zeros((0, len(x)))
