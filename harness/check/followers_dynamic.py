"""Followers of a guided dynamic file recomputed from its guides (docs/model.md §3.14).

`follower_plan(rest_roots, g, follow)` each follower's guides and weights (in double);
`place_followers(traj, f)` the positions and velocities [N][P][3] that frame f's followers
have when placed from that frame's guides, in the file's precision and in §3.14's order of
operations, so that a file from the same build matches bit for bit. Guides are returned as
stored.
"""

import numpy as np

from harness.check.invariants_dynamic import frame_end_time, head_rotation
from harness.core.guides import guide_count, guide_strands


def follower_plan(rest_roots, g, follow):
    """(guides [G], followers [F], src [F][W] strand indices, weights [F][W] in double)."""
    n = rest_roots.shape[0]
    guides = guide_strands(n, g)
    followers = np.setdiff1d(np.arange(n, dtype=np.int64), guides)
    width = 1 if follow == "one" else min(3, g)
    roots = rest_roots.astype(np.float64)
    gr = roots[guides]
    src = np.empty((followers.size, width), dtype=np.int64)
    w = np.zeros((followers.size, width))
    for lo in range(0, followers.size, 4096):
        fr = roots[followers[lo : lo + 4096]]
        d = gr[None, :, :] - fr[:, None, :]
        d2 = (d[..., 0] * d[..., 0] + d[..., 1] * d[..., 1]) + d[..., 2] * d[..., 2]
        order = np.argsort(d2, axis=1, kind="stable")[:, :width]  # ties: the lower guide number
        near = np.take_along_axis(d2, order, axis=1)
        src[lo : lo + 4096] = guides[order]
        inv = 1.0 / np.sqrt(np.where(near[:, :1] > 0.0, near, 1.0))
        total = inv[:, 0].copy()
        for i in range(1, width):
            total = total + inv[:, i]
        blend = inv / total[:, None]
        one = np.zeros_like(blend)
        one[:, 0] = 1.0
        w[lo : lo + 4096] = np.where(near[:, :1] > 0.0, blend, one) if width > 1 else one
    return guides, followers, src, w


def _rotate(q, a):
    return np.stack([q[3 * r] * a[..., 0] + q[3 * r + 1] * a[..., 1] + q[3 * r + 2] * a[..., 2] for r in range(3)], -1)


def _dot(a, b):
    return (a[..., 0] * b[..., 0] + a[..., 1] * b[..., 1]) + a[..., 2] * b[..., 2]


def _cross(a, b):
    return np.stack(
        [
            a[..., 1] * b[..., 2] - a[..., 2] * b[..., 1],
            a[..., 2] * b[..., 0] - a[..., 0] * b[..., 2],
            a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0],
        ],
        -1,
    )


def _carry(xg, rg, rf, q, one):
    """y = x_g,k + M(a → b)·o for every follower and point k ≥ 1 (arrays [F][P−1][3])."""
    e = rg[:, 1:] - rg[:, :-1]
    length = np.sqrt(_dot(e, e))[..., None]
    d = rf[:, 1:] - rg[:, 1:]
    t = np.where(length > 0, e / np.where(length > 0, length, one), 0 * one)
    a, o = (_rotate(q, t), _rotate(q, d)) if q is not None else (t, d)
    e = xg[:, 1:] - xg[:, :-1]
    rho = np.sqrt(_dot(e, e))[..., None]
    b = e / np.where(rho > 0, rho, one)
    cs = _dot(a, b)[..., None]
    den = one + cs
    u = _cross(a, b)
    sc = _dot(u, o)[..., None] / np.where(den > 0, den, one)
    rotated = (cs * o + _cross(u, o)) + sc * u
    r = np.where((length > 0) & (rho > 0) & (den > 0), rotated, o)
    return xg[:, 1:] + r


def _follower_rest(traj, followers, dtype):
    """ℓ_k of each follower in the working precision: [F][P−1] from a groom's rest shape, else ℓ
    (as the backends round them: once, from double)."""
    ell = traj.segment_rest()
    if np.ndim(ell) == 0:
        return np.full((followers.size, traj.points - 1), dtype.type(ell), dtype=dtype)
    return ell[followers].astype(dtype)


def _radial(p, rc, one):
    """§3.5's head collision of points p [F][3]: radially onto the sphere rc where inside."""
    n = np.sqrt(_dot(p, p))[..., None]
    scaled = p * (rc / np.where(n == 0, one, n))
    centre = np.broadcast_to(np.array([0, rc, 0], dtype=p.dtype), p.shape)
    return np.where(n < rc, np.where(n == 0, centre, scaled), p)


def _collide(a, q, ell, rc, one):
    """§3.14's head collision of follower points q [F][3] placed ell [F][1] from their predecessors
    a: inside the sphere rc, the nearest point of the circle where the sphere of radius ell about a
    meets it; where there is none, radially (_radial); rc falsy: the collider is off."""
    if not rc:
        return q
    zero = one - one
    d = np.sqrt(_dot(a, a))[..., None]
    dd = np.where(d > zero, d, one)
    tau = ((d - rc) * (d + rc) + ell * ell) / (dd + dd)
    cp = d - tau
    h2 = ((rc - d) + tau) * (rc + cp)
    n = a / dd
    m = cp * n
    v = q - m
    s = _dot(v, n)[..., None]
    u = v - s * n
    lam = np.sqrt(_dot(u, u))[..., None]
    on_circle = m + np.sqrt(np.where(h2 > zero, h2, zero)) * (u / np.where(lam > zero, lam, one))
    inside = np.sqrt(_dot(q, q))[..., None] < rc
    use = inside & (d > zero) & (h2 > zero) & (lam > zero)
    return np.where(use, on_circle, _radial(q, rc, one))


def _follow_blend(root, acc, ell, rc, one):
    """Points 1 … P−1 of every follower (§3.14 step 2): each the blended point acc[:, k−1] pulled
    onto the segment of length ℓ_k from the placed predecessor, then the follower's head collision."""
    out = np.empty_like(acc)
    prev = root
    for k in range(acc.shape[1]):
        e = acc[:, k] - prev
        rho = np.sqrt((e[:, 0] * e[:, 0] + e[:, 1] * e[:, 1]) + e[:, 2] * e[:, 2])[:, None]
        lk = ell[:, k][:, None]
        down = prev - lk * np.array([0, 1, 0], dtype=acc.dtype)
        p = np.where(rho > 0, prev + lk * (e / np.where(rho > 0, rho, one)), down)
        prev = out[:, k] = _collide(prev, p, lk, rc, one)
    return out


def place_followers(traj, f, velocity=None):
    """(x, v) of written frame f with every follower placed from the frame's guides (§3.14).
    `velocity` is the frame's stored velocities (None: v is None)."""
    x = traj.frame(f).reshape(traj.n_strands, traj.points, 3).copy()
    rest = traj.rest
    dt = x.dtype.type
    one = dt(1)
    g = guide_count(traj.n_strands, float(traj.dynamic_params["guides"]))
    _, followers, src, w64 = follower_plan(rest[:, 0, :], g, traj.follow)
    w = w64.astype(x.dtype)
    q = None
    if traj.head_motion != "still":
        p = traj.dynamic_params
        q = [
            dt(v)
            for v in head_rotation(
                traj.head_motion,
                float(p["motion_amplitude"]),
                float(p["motion_frequency"]),
                frame_end_time(traj, f),
                traj.motion_track,
            )
        ]
    with np.errstate(all="ignore"):
        rf = rest[followers]
        root = _rotate(q, rf[:, 0]) if q is not None else rf[:, 0]
        acc = None
        for i in range(src.shape[1]):
            y = _carry(x[src[:, i]], rest[src[:, i]], rf, q, one)
            wi = w[:, i][:, None, None]
            acc = wi * y if acc is None else acc + wi * y
        ell = _follower_rest(traj, followers, x.dtype)
        placed = _follow_blend(root, acc, ell, traj.collider and dt(traj.collide_radius), one)
        x[followers, 0] = root
        x[followers, 1:] = placed
        v = None
        if velocity is not None:
            v = velocity.reshape(traj.n_strands, traj.points, 3).copy()
            vacc = w[:, 0][:, None, None] * velocity[src[:, 0]]
            for i in range(1, src.shape[1]):
                vacc = vacc + w[:, i][:, None, None] * velocity[src[:, i]]
            v[followers] = vacc
    return x, v
