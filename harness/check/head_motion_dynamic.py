"""The head's rotation Q(t) of docs/model.md §3.2 in double, as the binaries compute it: the
sinusoids, or a recorded track (c_ref/dynamic/head_track.h)."""

import math


def track_rotation(track, t):
    """Q(t) of a recorded track (rows time, qw, qx, qy, qz, tx, ty, tz) in double, row-major, with
    the operations of c_ref/dynamic/head_track.h in its order (Python's floats and math are the
    same IEEE doubles and libm, so the result is the binary's to the bit)."""
    n = len(track)
    if n == 1 or not t > track[0][0]:
        return _quat_matrix(track[0][1:5])
    if t >= track[n - 1][0]:
        return _quat_matrix(track[n - 1][1:5])
    lo, hi = 0, n - 1
    while hi - lo > 1:
        mid = lo + (hi - lo) // 2
        lo, hi = (mid, hi) if track[mid][0] <= t else (lo, mid)
    a, b0 = [float(v) for v in track[lo][1:5]], [float(v) for v in track[lo + 1][1:5]]
    u = (t - float(track[lo][0])) / (float(track[lo + 1][0]) - float(track[lo][0]))
    dot = 0.0
    for c in range(4):
        dot += a[c] * b0[c]
    sign = -1.0 if dot < 0.0 else 1.0
    b, dm, dp = [sign * v for v in b0], 0.0, 0.0
    for c in range(4):
        dm += (a[c] - b[c]) * (a[c] - b[c])
        dp += (a[c] + b[c]) * (a[c] + b[c])
    theta = 2.0 * math.atan2(math.sqrt(dm), math.sqrt(dp))
    wa, wb = 1.0 - u, u
    if theta > 1e-12:
        s = math.sin(theta)
        wa, wb = math.sin((1.0 - u) * theta) / s, math.sin(u * theta) / s
    q = [wa * a[c] + wb * b[c] for c in range(4)]
    n2 = 0.0
    for c in range(4):
        n2 += q[c] * q[c]
    inv = 1.0 / math.sqrt(n2)
    return _quat_matrix([v * inv for v in q])


def _quat_matrix(q):
    w, x, y, z = (float(v) for v in q)
    return [
        1.0 - 2.0 * (y * y + z * z),
        2.0 * (x * y - z * w),
        2.0 * (x * z + y * w),
        2.0 * (x * y + z * w),
        1.0 - 2.0 * (x * x + z * z),
        2.0 * (y * z - x * w),
        2.0 * (x * z - y * w),
        2.0 * (y * z + x * w),
        1.0 - 2.0 * (x * x + y * y),
    ]


def head_rotation(motion, amplitude, frequency, t, track=None):
    """Q(t) of §3.2 in double, row-major, as c_ref/dynamic/dynamics_host.c hb_head_rotation
    (`track`: a recorded track's rows, for motion "track")."""
    if motion == "track":
        return track_rotation(track, t)
    th = amplitude * math.sin(2.0 * math.pi * frequency * t)
    c, s = math.cos(th), math.sin(th)
    q = [1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0]
    if motion == "nod":
        q[4], q[5], q[7], q[8] = c, -s, s, c
    elif motion == "shake":
        q[0], q[2], q[6], q[8] = c, s, -s, c
    elif motion == "tilt":
        q[0], q[1], q[3], q[4] = c, -s, s, c
    return q
