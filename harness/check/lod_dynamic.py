"""Simulated-point LOD (docs/model.md §3.14): a file's rendered points recomputed from its
simulated ones.

`render(x, pr, y=None)` the P_r points a strand of every strand in x [N][P_s][3] (the values
y, e.g. velocities, interpolated with x's knots and weights), in x's precision and in
§3.14's order of operations (c_ref/dynamic/dyn_lod_impl.h), so that a file from the same build
matches bit for bit; `recompute(traj, f)` frame f of a --render-points file recomputed from
the simulated rows it holds; `check_rendered(traj)` every written frame's rendered rows (and
stored velocities) against their recomputation, as invariant violations; `straightness(x)` how
far each point of a strand lies from the line through its ends, relative to the strand's length.
"""

import numpy as np

from harness.check.invariants import Violation
from harness.core import tolerances


def _knot(a, b):
    e = b - a
    return np.sqrt(np.sqrt((e[..., 0] * e[..., 0] + e[..., 1] * e[..., 1]) + e[..., 2] * e[..., 2]))


def _padded(v):
    """[N][P_s + 2][3]: the reflected phantom ends x_{−1} = x_0 + (x_0 − x_1), x_{P_s} likewise."""
    head = v[:, :1] + (v[:, :1] - v[:, 1:2])
    tail = v[:, -1:] + (v[:, -1:] - v[:, -2:-1])
    return np.concatenate([head, v, tail], axis=1)


def render(x, pr, y=None):
    """Rendered points [N][pr][3] of strands x [N][P_s][3] (of y with x's knots when given)."""
    n, ps, _ = x.shape
    if pr <= ps or (pr - 1) % (ps - 1):
        raise ValueError(f"render: P_r = {pr} must exceed P_s = {ps} with P_r − 1 a multiple of P_s − 1")
    dt = x.dtype.type
    m = (pr - 1) // (ps - 1)
    y = x if y is None else y
    xp, yp = _padded(x), _padded(y)
    # segment k's control points are padded rows k … k+3
    da = _knot(xp[:, :-3], xp[:, 1:-2])[..., None]
    db = _knot(xp[:, 1:-2], xp[:, 2:-1])[..., None]
    dc = _knot(xp[:, 2:-1], xp[:, 3:])[..., None]
    p0, p1, p2, p3 = yp[:, :-3], yp[:, 1:-2], yp[:, 2:-1], yp[:, 3:]
    out = np.empty((n, pr, 3), dtype=x.dtype)
    out[:, ::m] = y
    zero = dt(0)
    spline = (da > zero) & (db > zero) & (dc > zero)
    with np.errstate(all="ignore"):
        for i in range(1, m):
            s = dt(i) / dt(m)
            t = s * db
            ua, ub, uc = (t + da) / da, t / db, (t - db) / dc
            ud, ue = (t + da) / (da + db), t / (db + dc)
            a1, a2, a3 = p0 + ua * (p1 - p0), p1 + ub * (p2 - p1), p2 + uc * (p3 - p2)
            b1, b2 = a1 + ud * (a2 - a1), a2 + ue * (a3 - a2)
            out[:, i::m][:, : ps - 1] = np.where(spline, b1 + ub * (b2 - b1), p1 + s * (p2 - p1))
    return out


def recompute(traj, f, velocity=None):
    """(x, v): frame f of a --render-points file recomputed from its simulated rows (v from
    `velocity`, that frame's stored velocities [N][P_r][3], or None)."""
    rows = traj.simulated_rows
    x = traj.frame(f).reshape(traj.n_strands, traj.points, 3)[:, rows]
    v = None if velocity is None else render(x, traj.points, velocity[:, rows])
    return render(x, traj.points), v


def straightness(x):
    """Per strand, the largest distance of a point from the line through its ends over the
    strand's end-to-end length (in double)."""
    x = x.astype(np.float64)
    a, b = x[:, :1], x[:, -1:]
    d = b - a
    length = np.sqrt((d * d).sum(-1, keepdims=True))
    u = d / length
    r = x - a
    off = r - (r * u).sum(-1, keepdims=True) * u
    return np.sqrt((off * off).sum(-1)).max(axis=1) / length[:, 0, 0]


def check_rendered(traj, exact, frames=None):
    """Violations of a --render-points file's rendered rows: each written frame's positions (and
    its stored velocities) recomputed from its simulated rows; bit for bit with `exact` (the
    reference build), else within DYN_LOD_KERNEL_K·ε·E (E = R + c_m + 2L, the kernel's
    contraction). Returns (violations, the worst difference over ε·E)."""
    kind = tolerances.kind_of(traj.precision, traj.fast_math)
    unit = tolerances.EPS[kind] * (traj.collide_radius + 2.0 * traj.hair_length)
    out, worst = [], 0.0
    for f in range(traj.n_frames) if frames is None else frames:
        step = int(traj.step[f])
        v = traj.velocity_at_step(step)
        x_want, v_want = recompute(traj, f, v)
        pairs = [("positions", traj.frame(f), x_want)] + ([("velocities", v, v_want)] if v is not None else [])
        for what, got, want in pairs:
            with np.errstate(invalid="ignore"):
                d = np.abs(got.astype(np.float64) - want.astype(np.float64)) / unit
            bad = ~(d == 0) if exact else ~(d <= tolerances.DYN_LOD_KERNEL_K)
            worst = max(worst, float(np.nanmax(d)) if d.size else 0.0)
            n = int(np.count_nonzero(bad))
            if n:
                rule = "bit for bit" if exact else f"within {tolerances.DYN_LOD_KERNEL_K:g}·ε·E"
                out.append(Violation(f, traj.stages[f], "rendered", n, float(np.nanmax(d)),
                                     f"frame {f}: {n} rendered {what} coordinate(s) differ from their recomputation "
                                     f"from the simulated rows ({rule}; worst {np.nanmax(d):.3g}·ε·E)"))  # fmt: skip
    return out, worst
