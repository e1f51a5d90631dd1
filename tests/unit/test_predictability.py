"""The Lyapunov rate and predictability time (harness/check/predictability_dynamic.py) on systems whose
rate is known: the tent map doubles a separation exactly (λ = ln 2 per step), an unstable
linear oscillator x'' = k²x separates as cosh(k·t) (λ = k), a stable one not at all (no
growth: predictable beyond the run)."""

import math

import numpy as np
import pytest

from harness.check import predictability_dynamic as pr
from harness.core import tolerances


def tent_twins(x0, d0, steps):
    """Separations of the tent map x ← 2·min(x, 1 − x) from x0 and x0 + d0: exact doublings in
    binary floating point while both lie on one branch."""
    a, b, out = x0, x0 + d0, []
    for _ in range(steps):
        a, b = 2 * min(a, 1 - a), 2 * min(b, 1 - b)
        out.append(abs(a - b))
    return np.array(out)


def test_tent_map_rate_is_ln2_per_step():
    d0 = 1e-12
    sep = [tent_twins(x0, d0, 40) for x0 in (0.1234567, 0.3141592, 0.2718281)]
    r = pr.rate(np.arange(1, 41), sep, d0)
    assert r.grew
    assert r.lam == pytest.approx(math.log(2), rel=1e-9)
    assert r.samples >= 20  # from 10·d0 to the ceiling: log2(1e-4 / 1e-11) ≈ 23 doublings


def oscillator(k2, x0, steps, dt):
    """x'' = k2·x from (x0, 0), integrated exactly: [steps] positions at t = dt, 2dt, …"""
    t = dt * np.arange(1, steps + 1)
    if k2 > 0:
        return t, x0 * np.cosh(math.sqrt(k2) * t)
    return t, x0 * np.cos(math.sqrt(-k2) * t)


def test_unstable_oscillator_rate_is_k():
    k, d0 = 20.0, 1e-12
    t, sep = oscillator(k * k, d0, 200, 1 / 60)
    r = pr.rate(t, sep, d0)
    assert r.grew and r.lam == pytest.approx(k, rel=5e-3)
    assert r.predictability == pytest.approx(
        math.log(tolerances.DYN_PREDICT_TOLERANCE_L / tolerances.DYN_PREDICT_SEED_L) / r.lam
    )


def test_a_stable_oscillator_does_not_grow_and_stays_predictable():
    t, x = oscillator(-(30.0**2), 1e-12, 300, 1 / 60)
    r = pr.rate(t, np.abs(x) + 1e-13, 1e-12)
    assert not r.grew
    assert abs(r.lam) < 1.0 and math.isinf(r.predictability)


def test_the_fit_stops_at_saturation():
    """A separation that grows at rate 3 and then saturates at 1e-2: the rate is the growth's."""
    t = np.arange(200) * 0.05
    sep = np.minimum(1e-12 * np.exp(3 * t), 1e-2)
    r = pr.rate(t, sep, 1e-12)
    assert r.lam == pytest.approx(3.0, rel=1e-9) and r.t_hi <= math.log(1e-4 / 1e-12) / 3 + 0.05


def test_perturbation_has_the_asked_rms_and_leaves_roots():
    p = pr.perturbation((16, 8, 3), 1e-12, 30.0, seed=3)
    assert np.all(p[:, 0] == 0)
    assert math.sqrt(np.mean(np.sum(p * p, axis=-1))) == pytest.approx(3e-11, rel=1e-12)
    assert not np.array_equal(p, pr.perturbation((16, 8, 3), 1e-12, 30.0, seed=4))


def test_predictability_time_is_infinite_without_growth():
    assert math.isinf(pr.predictability_time(0.0)) and math.isinf(pr.predictability_time(float("nan")))
    assert pr.predictability_time(120.0) == pytest.approx(math.log(1e-2 * 2**24) / 120.0)


def test_a_growth_faster_than_the_frames_gives_a_lower_bound():
    """At 400 /s sampled every 0.05 s the separation passes 1e-4·L by the second frame: the rate is
    the secant's lower bound, and the predictability time an upper bound, not 'predictable'."""
    t = 0.05 * np.arange(1, 21)
    sep = np.minimum(1e-12 * np.exp(400 * (t - 0.0)), 1e-2)
    r = pr.rate(t, sep, 1e-12)
    assert r.grew and r.bound and r.samples == 0
    assert 0 < r.lam <= 400 and r.predictability < 0.2
