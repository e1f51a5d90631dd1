"""The head's rotation Q(t) of docs/model.md §3.2 in double, as the binaries compute it."""

import math


def head_rotation(motion, amplitude, frequency, t):
    """Q(t) of §3.2 in double, row-major, as c_ref/dynamic/dynamics_host.c hb_head_rotation."""
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
