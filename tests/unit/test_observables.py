"""harness/check/observables.py on inputs with known answers (numpy only, no binary):
verdicts split by cause, silhouettes, jitter, stretch, error percentiles, spectra, and the
tip-motion fits on synthetic oscillations."""

import math

import numpy as np
import pytest

from harness.check import observables as ob

L = 30.0


def hanging(n=3, p=5):
    """n straight strands hanging from roots along x, points [1][n][p][3]."""
    x = np.zeros((1, n, p, 3))
    x[0, :, :, 0] = np.arange(n)[:, None]
    x[0, :, :, 1] = -np.linspace(0, L, p)[None, :]
    return x


def test_verdict_nan_is_diverged_and_a_far_point_escaped():
    x = hanging()
    assert ob.verdict(x, L) == ob.OK
    far = x.copy()
    far[0, 1, -1, 1] = -2.5 * L  # farther than 2L from its root
    assert ob.verdict(far, L) == ob.ESCAPED
    bad = far.copy()
    bad[0, 0, 2, 0] = np.nan  # a NaN wins over a far point
    assert ob.verdict(bad, L) == ob.DIVERGED
    inf_vel = np.zeros_like(x)
    inf_vel[0, 2, 3, 2] = np.inf
    assert ob.verdict(x, L, vel=inf_vel) == ob.DIVERGED


def test_iou_identical_one_disjoint_zero():
    x = hanging()[0]
    assert ob.silhouette_iou(x, x) == {"front": 1.0, "side": 1.0}
    a = np.zeros((16, 16), bool)
    b = np.zeros((16, 16), bool)
    a[:4, :4] = True
    b[8:, 8:] = True
    assert ob.iou(a, b) == 0.0
    assert ob.iou(a, a) == 1.0
    moved = x.copy()
    moved[..., 0] += 10 * L  # far to the side: no pixel shared in either view's box
    moved[..., 2] += 10 * L
    got = ob.silhouette_iou(x, moved)
    assert got["front"] == 0.0 and got["side"] == 0.0


def test_iou_of_half_overlap():
    a = np.zeros((10, 10), bool)
    b = np.zeros((10, 10), bool)
    a[:, :6] = True
    b[:, 3:9] = True  # overlap 3 of 9 columns
    assert ob.iou(a, b) == pytest.approx(3 / 9)


def test_jitter_zero_for_a_still_strand_and_measured_for_a_shaking_one():
    still = np.repeat(hanging(), 10, axis=0)
    assert ob.jitter(still, 1 / 60) == (0.0, 0.0)
    shake = still.copy()
    shake[1::2, :, 1:, 0] += 0.01  # every other frame, every non-root point 0.01 cm aside
    rms_v, most = ob.jitter(shake, 1 / 60)
    assert most == pytest.approx(0.01)
    assert rms_v == pytest.approx(0.01 * 60)


def test_stretch_stats_of_one_stretched_segment():
    x = hanging(n=1, p=101)  # 100 segments
    assert ob.stretch_stats(x, L) == (pytest.approx(0.0, abs=1e-14), pytest.approx(0.0, abs=1e-14))
    y = x.copy()
    y[0, 0, -1, 1] -= 0.5 * L / 100  # the last segment 50 % long
    mx, p99 = ob.stretch_stats(y, L)
    assert mx == pytest.approx(0.5)
    assert p99 == pytest.approx(0.01 * 0.5, rel=1e-9)  # numpy's linear percentile: 0.01 of the way to the top


def test_error_percentiles_of_known_offsets():
    ref = np.zeros((1, 1, 100, 3))
    x = ref.copy()
    x[0, 0, :, 2] = np.arange(100) * L / 100  # offsets 0 … 0.99 L
    e = ob.error_percentiles(x, ref, L)
    assert e["max"] == pytest.approx(0.99)
    assert e["p50"] == pytest.approx(0.495)
    assert e["rms"] == pytest.approx(math.sqrt(np.mean((np.arange(100) / 100) ** 2)))
    x[0, 0, 3, 0] = np.nan
    assert math.isnan(ob.error_percentiles(x, ref, L)["rms"])


def test_dominant_frequency_and_damping_ratio_of_a_damped_sine():
    dt, f0, zeta = 1 / 60, 1.3, 0.05
    t = np.arange(600) * dt
    w0 = 2 * math.pi * f0
    wd = w0 * math.sqrt(1 - zeta**2)
    y = 3.0 + np.exp(-zeta * w0 * t) * np.cos(wd * t)  # an offset must not matter
    assert ob.damping_ratio(y, dt) == pytest.approx(zeta, rel=0.02)
    steady = np.cos(w0 * t)
    assert ob.dominant_frequency(steady, dt) == pytest.approx(f0, rel=1e-3)
    assert ob.dominant_frequency(np.zeros(50), dt) == 0.0
    assert math.isnan(ob.damping_ratio(np.linspace(0, 1, 50), dt))


def test_energy_of_a_falling_point():
    """Two frames of one root and one point: kinetic ½v², potential g·y, per non-root particle."""
    x = np.zeros((2, 1, 2, 3))
    v = np.zeros_like(x)
    x[1, 0, 1, 1] = -2.0
    v[1, 0, 1, 1] = -4.0
    v[:, 0, 0, :] = 99.0  # the root does not count
    k, p, e = ob.energy(x, v, 10.0)
    assert list(k) == [0.0, 8.0]
    assert list(p) == [0.0, -20.0]
    assert list(e) == [0.0, -12.0]
    assert ob.drift([1.0, 2.0, 3.0], [0.0, 0.5, 1.0]) == pytest.approx(2.0)


def test_distribution_and_spectrum_distances():
    rng = np.random.default_rng(1)
    a = rng.normal(size=4000)
    assert ob.wasserstein_1d(a, a) == 0.0
    assert ob.wasserstein_1d(a, a + 0.5) == pytest.approx(0.5, rel=1e-9)
    dt = 1 / 60
    t = np.arange(600) * dt
    s1, s2 = np.sin(2 * math.pi * 1 * t), np.sin(2 * math.pi * 20 * t)
    assert ob.spectrum_distance(s1, 2 * s1, dt) == pytest.approx(0.0, abs=1e-12)  # shape, not scale
    assert ob.spectrum_distance(s1, s2, dt) > 0.95


def test_split_half_noise():
    x = np.zeros((4, 6))
    x[:, 0::2] = 1.0  # even strands 1, odd 0

    def mean(a):
        return float(a.mean())

    assert ob.split_half(mean, x) == 0.5
    assert math.isnan(ob.split_half(mean, x[:, :1]))


def test_swing_of_strands_in_opposite_phase_and_other_planes():
    """Two strands swing in the x and the z plane, in opposite phase: their mean would cancel,
    each strand's own swing does not."""
    dt, f0, zeta = 1 / 60, 0.9, 0.04
    t = np.arange(600) * dt
    w0 = 2 * math.pi * f0
    a = 2.0 * np.exp(-zeta * w0 * t) * np.cos(w0 * math.sqrt(1 - zeta**2) * t)
    pos = np.zeros((len(t), 2, 3, 3))
    pos[:, :, :, 1] = -np.array([0.0, 15.0, 30.0])  # hanging; roots at the origin
    pos[:, 0, -1, 0] = a + 0.5  # starts displaced: the swing's plane is its start's
    pos[:, 1, -1, 2] = -a - 0.5
    assert np.allclose(ob.tip_displacement(pos, axis=0) + ob.tip_displacement(pos, axis=2), 0)
    f, z = ob.swing(pos, dt)
    assert f == pytest.approx(f0, rel=2e-3)
    assert z == pytest.approx(zeta, rel=0.02)
