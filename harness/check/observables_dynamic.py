"""What a hair user sees of a run, as numbers (numpy only): energy, tip motion, rest jitter,
stretch, position error percentiles, long-run distributions and spectra, silhouettes, and
the verdict of a run (docs/harness.md, "The dynamic accuracy study"; docs/model.md §3.8).

Positions are [F][N][P][3] (frames, strands, points, xyz), velocities the same, in cm and
cm/s; L is the hair length. Point 0 of a strand is its root. Nothing here runs a binary.
"""

import numpy as np

from harness.core import tolerances

OK, DIVERGED, ESCAPED = "ok", "diverged", "escaped"


def _f64(a):
    return np.asarray(a, dtype=np.float64)


# ---- verdicts -------------------------------------------------------------------------


def verdict(pos, L, vel=None):
    """'diverged' when any position (or velocity) is NaN or Inf, else 'escaped' when a
    non-root point is farther than 2L from its strand's root, else 'ok' (the split of §3.8's
    blown up by cause)."""
    x = _f64(pos)
    if not np.isfinite(x).all() or (vel is not None and not np.isfinite(_f64(vel)).all()):
        return DIVERGED
    far = np.linalg.norm(x[..., 1:, :] - x[..., :1, :], axis=-1)
    return ESCAPED if (far > 2.0 * L).any() else OK


# ---- energy ---------------------------------------------------------------------------


def energy(pos, vel, gravity):
    """Per frame, per non-root particle (unit masses): kinetic ½|v|², gravitational potential
    g0·y, and their sum, from the stored velocities. Returns three arrays [F]. ftl's stored
    velocities include its correction −s·d/h (docs/model.md §3.7), which no position shows: use
    kinetic_from_positions for the motion."""
    x, v = _f64(pos)[..., 1:, :], _f64(vel)[..., 1:, :]
    kinetic = 0.5 * np.mean(np.sum(v * v, axis=-1), axis=(-2, -1))
    potential = float(gravity) * np.mean(x[..., 1], axis=(-2, -1))
    return kinetic, potential, kinetic + potential


def kinetic_from_positions(pos, dt):
    """Per frame, ½·mean |v|² over the non-root points (unit masses) of the motion the positions
    show: v the central difference (x_{f+1} − x_{f−1})/(2·dt) inside the run, one-sided at its
    two ends ([F], frames dt apart; 0 for a single frame). Zero for positions that do not move,
    whatever velocities a solver stores."""
    x = _f64(pos)[..., 1:, :]
    if len(x) < 2:
        return np.zeros(len(x))
    v = np.gradient(x, dt, axis=0)
    return 0.5 * np.mean(np.sum(v * v, axis=-1), axis=(-2, -1))


def drift(series, times):
    """Least-squares slope of a series against time (units per second): how fast it drifts."""
    t, y = _f64(times), _f64(series)
    if len(t) < 2:
        return 0.0
    return float(np.polyfit(t, y, 1)[0])


# ---- tip motion -----------------------------------------------------------------------


def tip_displacement(pos, axis=1):
    """Per frame, the mean over strands of the tip's coordinate `axis` less its mean over the
    frames: the signal whose oscillation is the strands' swing."""
    tip = _f64(pos)[:, :, -1, axis].mean(axis=1)
    return tip - tip.mean()


def tip_swing(pos):
    """Per strand, the tip's horizontal displacement from its root along the horizontal
    direction it starts in (the plane a released strand swings in): [F][N]. A strand whose
    tip starts straight below its root uses x."""
    x = _f64(pos)
    rel = x[:, :, -1, :] - x[:, :, :1, :].squeeze(2)
    h0 = rel[0].copy()
    h0[:, 1] = 0.0
    norm = np.linalg.norm(h0, axis=-1)
    h0[norm == 0] = (1.0, 0.0, 0.0)
    h0 /= np.linalg.norm(h0, axis=-1, keepdims=True)
    return np.einsum("fnc,nc->fn", rel, h0)


def swings(signal, dt, periods=None):
    """Whether a signal swings: its dominant frequency fits at least `periods` (default
    tolerances.OBS_SWING_MIN_PERIODS) whole periods into it and it crosses its mean at least
    2·periods − 1 times. A drift, a settling or a still strand does not: its spectrum's peak is
    its lowest bin, which is no frequency of the hair."""
    periods = tolerances.OBS_SWING_MIN_PERIODS if periods is None else periods
    y = _f64(signal)
    if len(y) < 4 or not np.isfinite(y).all() or not np.ptp(y) > 0:
        return False
    f = dominant_frequency(y, dt)
    c = y - y.mean()
    crossings = int(np.count_nonzero(np.signbit(c[1:]) != np.signbit(c[:-1])))
    return f * len(y) * dt >= periods and crossings >= 2 * periods - 1


def swing(pos, dt):
    """The median over the strands whose tip swings (tip_swing, `swings`) of the dominant
    frequency (Hz) and of the damping ratio, and the median of the damping fits' standard
    errors: the strands' own motion, not their average (strands that swing in opposite phase
    would cancel in a mean). NaN where no strand swings: a frequency is never read off a drift."""
    s = tip_swing(pos)
    moving = [s[:, n] for n in range(s.shape[1]) if swings(s[:, n], dt)]
    f = [dominant_frequency(y, dt) for y in moving]
    fits = [damping_fit(y, dt) for y in moving]
    fits = [v for v in fits if np.isfinite(v[0])]

    def median(v):
        return float(np.median(v)) if len(v) else float("nan")

    return median(f), median([z for z, _ in fits]), median([e for _, e in fits])


def dominant_frequency(signal, dt, pad=16):
    """The frequency (Hz) of the largest peak of the signal's spectrum (mean removed, Hann
    window, zero-padded `pad`× for a finer grid), refined by a parabola through the log
    magnitudes of the peak's three bins; 0 for a flat signal. Needs uniform samples."""
    y = _f64(signal)
    y = y - y.mean()
    n = len(y)
    if n < 4 or not np.any(y):
        return 0.0
    mag = np.abs(np.fft.rfft(y * np.hanning(n), pad * n))
    k = int(np.argmax(mag[1:])) + 1
    shift = 0.0
    if k < len(mag) - 1 and mag[k - 1] > 0 and mag[k + 1] > 0:
        a, b, c = np.log(mag[k - 1 : k + 2])
        den = a - 2 * b + c
        shift = 0.5 * (a - c) / den if den != 0 else 0.0
    return float((k + shift) / (pad * n * dt))


def damping_fit(signal, dt):
    """(ζ, its standard error) of a decaying swing from its envelope: the signal from its first
    extremum is cut into windows one period of its dominant frequency f long, half a period
    apart; each window's height (max − min, so an offset does not matter, and an extremum of
    a faster, smaller mode only adds its own amplitude) falls as e^(−σt); σ is the
    least-squares slope of their logarithms against time and ζ = σ/√(ω_d² + σ²), ω_d = 2π·f.
    The standard error is the slope's, from the fit's residuals (0 for an exact exponential).
    (NaN, NaN) for a signal that is flat, not finite, or shorter than 4 windows; a swing
    damped so fast (ζ ≳ 0.15 over many periods) that its spectrum has no peak at its
    frequency has no fit either."""
    y = _f64(signal)
    nan = (float("nan"), float("nan"))
    if not np.isfinite(y).all():
        return nan
    f = dominant_frequency(y, dt)
    if not f > 0:
        return nan
    period = 1.0 / (f * dt)  # samples
    first = int(np.argmax(np.abs(y - y.mean())[: int(period) + 1]))  # the first swing's extremum
    starts = np.arange(float(first), len(y) - period + 1e-9, period / 2)
    if len(starts) < 4:
        return nan
    heights = np.array([np.ptp(y[int(round(a)) : int(round(a + period)) + 1]) for a in starts])
    if not (heights > 0).all():
        return nan
    t = (starts + period / 2) * dt
    (slope, _), res, *_ = np.polyfit(t, np.log(heights), 1, full=True)
    dof = len(t) - 2
    var = float(res[0]) / dof if len(res) and dof > 0 else 0.0
    se_slope = np.sqrt(var / np.sum((t - t.mean()) ** 2))
    wd, sigma = 2 * np.pi * f, -float(slope)
    norm = np.hypot(wd, sigma)
    # dζ/dσ = ω_d²/(ω_d² + σ²)^(3/2)
    return float(sigma / norm), float(se_slope * wd * wd / norm**3)


def damping_ratio(signal, dt):
    """ζ of a decaying swing (damping_fit)."""
    return damping_fit(signal, dt)[0]


# ---- jitter, stretch, errors ------------------------------------------------------------


def jitter(pos, dt):
    """Rest jitter of a still scene: RMS over points and frames of the frame-to-frame
    velocity |x_{f+1} − x_f|/dt (cm/s), and the largest frame-to-frame move (cm)."""
    x = _f64(pos)[..., 1:, :]
    if len(x) < 2:
        return 0.0, 0.0
    step = np.linalg.norm(np.diff(x, axis=0), axis=-1)
    return float(np.sqrt(np.mean(step * step)) / dt), float(step.max())


def stretch_stats(pos, L, ell=None):
    """Max and 99th percentile of |len/ℓ_k − 1| over every segment of every frame: ℓ_k each
    segment's own rest length where given ([P−1] or [N][P−1], e.g. Trajectory.segment_rest()
    or rest_lengths(rest), docs/model.md §3.15), else ℓ = L/(P−1)."""
    x = _f64(pos)
    ell = L / (x.shape[-2] - 1) if ell is None else _f64(ell)
    s = np.abs(np.linalg.norm(np.diff(x, axis=-2), axis=-1) / ell - 1.0).ravel()
    s = s[np.isfinite(s)]
    if s.size == 0:
        return float("nan"), float("nan")
    return float(s.max()), float(np.percentile(s, 99))


def rest_lengths(rest):
    """ℓ_k = |X̄_k − X̄_{k−1}| in double from a rest shape [..., P, 3]: [..., P − 1]."""
    return np.linalg.norm(np.diff(_f64(rest), axis=-2), axis=-1)


def error_percentiles(pos, ref, L):
    """|x − x_ref|/L over every point and frame given: RMS, p50, p95, p99 and max (NaN where
    either is not finite)."""
    d = np.linalg.norm(_f64(pos) - _f64(ref), axis=-1).ravel() / L
    if d.size == 0 or not np.isfinite(d).all():
        return dict(rms=np.nan, p50=np.nan, p95=np.nan, p99=np.nan, max=np.nan)
    p50, p95, p99 = np.percentile(d, (50, 95, 99))
    return dict(rms=float(np.sqrt(np.mean(d * d))), p50=float(p50), p95=float(p95), p99=float(p99), max=float(d.max()))


# ---- long runs: distributions and spectra ------------------------------------------------


def wasserstein_1d(a, b):
    """The 1-D Wasserstein (earth mover's) distance between two samples: the mean absolute
    difference of their quantiles on a common grid."""
    a, b = np.sort(_f64(a).ravel()), np.sort(_f64(b).ravel())
    q = (np.arange(512) + 0.5) / 512
    return float(np.mean(np.abs(np.quantile(a, q) - np.quantile(b, q))))


def tip_distribution_distance(pos, ref, L):
    """Over a long run: the Wasserstein distance, over L, between the distributions (over
    frames and strands) of the tip's position relative to its root, summed over x, y, z.
    Zero for the same statistics whatever the phase of the motion."""
    x, r = _f64(pos), _f64(ref)
    a = x[:, :, -1, :] - x[:, :, 0, :]
    b = r[:, :, -1, :] - r[:, :, 0, :]
    return float(sum(wasserstein_1d(a[..., c], b[..., c]) for c in range(3)) / L)


def spectrum(signal, dt, bands=16, fmax=None):
    """Power of the signal (mean removed) in `bands` equal frequency bands up to fmax (default
    Nyquist): a coarse spectrum two runs can be compared on. Returns (band edges, power)."""
    y = _f64(signal)
    y = y - y.mean()
    p = np.abs(np.fft.rfft(y * np.hanning(len(y)))) ** 2
    f = np.fft.rfftfreq(len(y), dt)
    edges = np.linspace(0.0, fmax or f[-1], bands + 1)
    power = np.array([p[(f >= lo) & (f < hi)].sum() for lo, hi in zip(edges[:-1], edges[1:])])
    return edges, power


def spectrum_distance(signal, ref_signal, dt, bands=16):
    """Total variation between the two normalised band spectra (0: the same shape, 1:
    disjoint), of signals of equal length."""
    _, a = spectrum(signal, dt, bands)
    _, b = spectrum(ref_signal, dt, bands)
    if a.sum() == 0 or b.sum() == 0:
        return float(a.sum() != b.sum())
    return float(0.5 * np.abs(a / a.sum() - b / b.sum()).sum())


# ---- silhouettes ------------------------------------------------------------------------

VIEWS = {"front": (0, 1), "side": (2, 1)}  # image axes: front looks along z (x, y), side along x (z, y)


def rasterise(pos, axes, lo, hi, pixels=64):
    """Occupancy image [pixels][pixels] of the strands [N][P][3] projected on `axes` within the
    box lo … hi: every segment sampled finer than a pixel."""
    x = _f64(pos)[..., axes]
    img = np.zeros((pixels, pixels), dtype=bool)
    seg = np.diff(x, axis=-2)
    span = np.maximum(np.asarray(hi, float) - np.asarray(lo, float), 1e-300)
    n = int(np.ceil(np.nanmax(np.abs(seg) / span * pixels, initial=0.0) * 2)) + 1
    t = np.linspace(0.0, 1.0, n + 1)
    pts = x[..., :-1, None, :] + seg[..., None, :] * t[:, None]
    pts = pts.reshape(-1, 2)
    pts = pts[np.isfinite(pts).all(axis=1)]
    ij = np.floor((pts - lo) / span * pixels).astype(np.int64)
    keep = ((ij >= 0) & (ij < pixels)).all(axis=1)
    img[ij[keep, 1], ij[keep, 0]] = True
    return img


def iou(a, b):
    """Intersection over union of two occupancy images (1 when both are empty)."""
    a, b = np.asarray(a, bool), np.asarray(b, bool)
    union = np.count_nonzero(a | b)
    return 1.0 if union == 0 else float(np.count_nonzero(a & b) / union)


def silhouette_iou(pos, ref, pixels=64):
    """Per view (front, side): IoU of the strands' silhouettes [N][P][3] of a frame against the
    reference's, rasterised in one box around both."""
    x, r = _f64(pos), _f64(ref)
    both = np.concatenate([x.reshape(-1, 3), r.reshape(-1, 3)])
    both = both[np.isfinite(both).all(axis=1)]
    out = {}
    for view, axes in VIEWS.items():
        if both.size == 0:
            out[view] = float("nan")
            continue
        lo, hi = both[:, axes].min(axis=0), both[:, axes].max(axis=0)
        pad = 0.02 * max(float((hi - lo).max()), 1e-12)
        lo, hi = lo - pad, hi + pad
        out[view] = iou(rasterise(x, axes, lo, hi, pixels), rasterise(r, axes, lo, hi, pixels))
    return out


# ---- noise ---------------------------------------------------------------------------------


def split_half(metric, *arrays):
    """A metric's sampling noise: half the difference between its value on the even strands and
    on the odd ones (arrays [F][N]…, the strand axis second). NaN with fewer than 2 strands."""
    if _f64(arrays[0]).shape[1] < 2:
        return float("nan")
    a = metric(*[_f64(x)[:, 0::2] for x in arrays])
    b = metric(*[_f64(x)[:, 1::2] for x in arrays])
    return float(abs(a - b) / 2)
