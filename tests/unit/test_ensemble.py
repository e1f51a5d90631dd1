"""The metrics that survive chaos (harness/check/ensemble_dynamic.py) on cases with known answers: the
curvature of points on a circle is 1/r, a tip distribution shifted by δ is δ away, identical
runs are 0 apart, a mode equal to a member passes every use and one far outside the spread
fails."""

import math

import numpy as np
import pytest

from harness.check import ensemble_dynamic as en
from harness.core import tolerances

DT = 1 / 60
L = 30.0
BOX = en.envelope_box(10.0, L)


def circle(r, points, frames=3):
    a = np.linspace(0.0, math.pi, points)
    x = np.stack([np.zeros(points), r * np.sin(a), r * np.cos(a)], axis=-1)
    return np.broadcast_to(x, (frames, 4, points, 3)).copy()


def test_curvature_of_points_on_a_circle_is_one_over_r():
    assert en.curvatures(circle(2.5, 17)[0]) == pytest.approx(np.full((4, 15), 1 / 2.5), rel=1e-12)


def test_a_shifted_tip_distribution_is_its_shift_away():
    a = circle(5.0, 9, frames=30)
    b = a.copy()
    b[:, :, 1:, 1] -= 0.3  # every tip (not the roots) 0.3 cm lower
    sa = en.signature(a, DT, L, None, BOX)
    sb = en.signature(b, DT, L, None, BOX)
    assert en.distances(sa, sa) == {"tip_L": 0.0, "curvature_rel": 0.0, "envelope_rel": 0.0}
    assert en.distances(sb, sa)["tip_L"] == pytest.approx(0.3 / L, rel=1e-9)


def test_windows_cover_every_frame_once():
    ws = en.windows(70, DT)
    assert ws[0].start == 0 and ws[-1].stop == 70
    assert all(a.stop == b.start for a, b in zip(ws, ws[1:]))
    assert all(w.stop - w.start >= round(tolerances.DYN_ENSEMBLE_WINDOW_S / DT) for w in ws)


def test_a_mode_equal_to_a_member_passes_and_one_far_off_fails():
    rng = np.random.default_rng(1)
    base = circle(5.0, 9, frames=30)
    members = []
    for k in range(3):
        m = base.copy()
        m[:, :, 1:, :] += 0.01 * rng.standard_normal(m[:, :, 1:, :].shape)
        members.append(en.signature(m, DT, L, None, BOX))
    ens = en.spread(members)
    assert 0 < ens["tip_L"] < 1e-3
    same = en.compare(members[0], members, ens)
    for use in tolerances.DYN_ACC_USES:
        ok = en.passes(same, use)
        assert all(ok[m] for m in en.DISTANCES), (use, ok)
    far = base.copy()
    far[:, :, 1:, 1] -= 3.0  # tips 0.1·L lower
    got = en.passes(en.compare(en.signature(far, DT, L, None, BOX), members, ens), "previews")
    assert not got["tip_L"]


def test_within_range_widens_by_the_factor_and_the_share():
    assert en.within_range(2.0, 1.0, 1.5, factor=1.5) and not en.within_range(2.3, 1.0, 1.5, factor=1.5)
    assert en.within_range(0.9, 1.0, 1.0, rel=0.1) and not en.within_range(float("nan"), 0, 1)


def test_a_diverged_run_has_no_signature_and_fails():
    x = circle(5.0, 9)
    x[1, 0, 3, 0] = np.nan
    assert en.signature(x, DT, L, None, BOX) is None
    members = [en.signature(circle(5.0, 9), DT, L, None, BOX)]
    assert not any(en.passes(en.compare(None, members), "previews").values())
