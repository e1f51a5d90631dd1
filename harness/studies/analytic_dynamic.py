"""Closed forms of docs/model.md §4 and the measurements that compare a run with them.

Pure functions on numpy arrays (no scipy): the pendulum period (small amplitude and any
amplitude, K(m) by the arithmetic–geometric mean), the hanging chain's first mode (continuum
ω1 and shape J0, and the linearised discrete chain of P−1 unit masses), the steady wind
angle; and from a time series: zero crossings with linear interpolation, the period they
give, the steady angle of a segment (a signal's dominant frequency is
harness.check.observables_dynamic.dominant_frequency).

`read_series(path)` gives (time, positions [F][N][P][3]) of a state file (harness.io.trajectory).
"""

import math

import numpy as np

J01 = 2.404825557695773  # first positive zero of J0 (NIST DLMF §10.21)


# ---------------------------------------------------------------- closed forms


def agm(a, b, tol=1e-16):
    """Arithmetic–geometric mean of a, b > 0."""
    a, b = float(a), float(b)
    for _ in range(64):
        if abs(a - b) <= tol * a:
            break
        a, b = 0.5 * (a + b), math.sqrt(a * b)
    return 0.5 * (a + b)


def ellipk(m):
    """Complete elliptic integral of the first kind, parameter convention (DLMF §19.2):
    K(m) = ∫₀^{π/2} dφ/√(1 − m sin²φ) = π / (2·AGM(1, √(1 − m))), 0 ≤ m < 1."""
    if not 0.0 <= m < 1.0:
        raise ValueError(f"ellipk: m = {m} outside [0, 1)")
    return math.pi / (2.0 * agm(1.0, math.sqrt(1.0 - m)))


def pendulum_period_small(length, g):
    """T = 2π√(ℓ/g) (docs/model.md §4.1)."""
    return 2.0 * math.pi * math.sqrt(length / g)


def pendulum_period(length, g, theta0):
    """Any amplitude θ0 < π: T = 4√(ℓ/g)·K(m), m = sin²(θ0/2) (docs/model.md §4.1)."""
    return 4.0 * math.sqrt(length / g) * ellipk(math.sin(0.5 * theta0) ** 2)


def wind_angle(drag, speed, g, psi=0.0):
    """Steady angle from the downward vertical (−y), positive toward +z (docs/model.md §4.2):
    the rod lines up with the net acceleration (0, −g + c_d·U·sin ψ, c_d·U·cos ψ); for a
    horizontal wind (ψ = 0) tan θ = c_d·U/g0. ψ = π gives −atan(c_d·U/g0) up to the 1.2e-16
    of sin π in double."""
    return math.atan2(drag * speed * math.cos(psi), g - drag * speed * math.sin(psi))


def j0(x):
    """Bessel J0 by its power series Σ (−x²/4)^k/(k!)²; 40 terms: exact to rounding for
    |x| ≤ 6, the range of the chain's mode shapes."""
    x = np.asarray(x, dtype=np.float64)
    q = -(x * x) / 4.0
    term = np.ones_like(x)
    total = np.ones_like(x)
    for k in range(1, 40):
        term = term * q / (k * k)
        total = total + term
    return total


def chain_omega1(length, g):
    """Continuum hanging chain: ω1 = (j01/2)·√(g/L) (docs/model.md §4.3)."""
    return 0.5 * J01 * math.sqrt(g / length)


def chain_mode_shape(s, length):
    """Continuum first mode J0(j01·√(s/L)), s measured from the free end."""
    return j0(J01 * np.sqrt(np.asarray(s, dtype=np.float64) / length))


def discrete_chain_matrix(points, length, g):
    """Linearised transverse dynamics ü = −A·u of the model's chain: P−1 unit masses on
    rigid links of length ℓ = L/(P−1), root fixed. Link j (between points j−1 and j)
    carries the weight below it, T_j = g·(P − j), so
    ü_k = (T(k+1)·(u(k+1) − u_k) − T_k·(u_k − u(k−1)))/ℓ, with u_0 = 0 and T_P = 0."""
    n = points - 1
    ell = length / n
    t = g * (points - np.arange(1, points + 1, dtype=np.float64))  # T_1 … T_P (T_P = 0)
    a = np.zeros((n, n))
    for i in range(n):  # row i is point k = i + 1
        a[i, i] = (t[i] + t[i + 1]) / ell
        if i > 0:
            a[i, i - 1] = -t[i] / ell
        if i + 1 < n:
            a[i, i + 1] = -t[i + 1] / ell
    return a


def discrete_chain_modes(points, length, g):
    """(ω ascending, shapes [P][modes] with the root row 0) of the linearised discrete chain."""
    w, v = np.linalg.eig(discrete_chain_matrix(points, length, g))
    order = np.argsort(w.real)
    w, v = w.real[order], v.real[:, order]
    shapes = np.vstack([np.zeros(v.shape[1]), v])
    return np.sqrt(w), shapes


def discrete_chain_omega1(points, length, g):
    """ω1 of the discrete chain (the solver's target; the continuum is its P → ∞ limit)."""
    return float(discrete_chain_modes(points, length, g)[0][0])


# ---------------------------------------------------------------- measurements


def zero_crossings(t, y):
    """Times where y changes sign, by linear interpolation between samples (a sample that
    is exactly 0 counts once)."""
    t = np.asarray(t, dtype=np.float64)
    y = np.asarray(y, dtype=np.float64)
    out = []
    for i in range(len(y) - 1):
        a, b = y[i], y[i + 1]
        if a == 0.0:
            if i == 0 or np.sign(y[i - 1]) != np.sign(b):
                out.append(t[i])
        elif a * b < 0.0:
            out.append(t[i] - a * (t[i + 1] - t[i]) / (b - a))
    return np.asarray(out)


def period_from_crossings(t, y, periods=None):
    """Mean period 2·(t_last − t_first)/(n − 1) over the zero crossings of y; with
    `periods`, only the first 2·periods + 1 crossings (the first `periods` full periods).
    NaN when fewer than 3 crossings."""
    c = zero_crossings(t, y)
    if periods is not None:
        c = c[: 2 * periods + 1]
    if len(c) < 3:
        return float("nan")
    return 2.0 * (c[-1] - c[0]) / (len(c) - 1)


def segment_angle(root, tip):
    """Angle of root→tip from the downward vertical (−y) in the y–z plane, positive toward
    +z: atan2(Δz, −Δy). Arrays [..., 3]."""
    d = np.asarray(tip, dtype=np.float64) - np.asarray(root, dtype=np.float64)
    return np.arctan2(d[..., 2], -d[..., 1])


def relative_error(measured, expected):
    return abs(measured - expected) / abs(expected)


def convergence_order(s_values, errors):
    """Least-squares slope of −log(error) against log(S): 1 for first order."""
    s = np.log(np.asarray(s_values, dtype=np.float64))
    e = np.log(np.asarray(errors, dtype=np.float64))
    return float(-np.polyfit(s, e, 1)[0])


# ---------------------------------------------------------------- reading runs


def read_series(path):
    """(time [F], positions [F][N][P][3] float64) of every written frame of a state file,
    through harness.io.trajectory (time: 0 for paper frames, f·Δt for simulated frame f)."""
    from harness.io.trajectory import open_trajectory

    with open_trajectory(path) as t:
        frames = np.stack([t.frame(f).astype(np.float64) for f in range(t.n_frames)])
        time = np.asarray(t.time, dtype=np.float64)
    return time, frames
