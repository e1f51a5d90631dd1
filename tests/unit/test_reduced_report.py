"""The reduced-models page words the sag-free swing as measured (harness/render/reduced_dynamic_report.py):
a solver whose strands do not swing is said so, and a changed frequency is given with its change."""

from harness.render import reduced_dynamic_report as reduced_report


def _rows(xpbd_hz, ftl_hz):
    rows = []
    for solver, (off, on) in (("xpbd", xpbd_hz), ("ftl", ftl_hz)):
        for sag, rest in (("0", 0.01), ("1", 0.0001)):
            rows.append(dict(study="sagfree", solver=solver, shape_range="1.0", sag_free=sag, rest_rms_L=rest))
        rows.append(dict(study="sagfreq", solver=solver, sag_free="0", tip_hz=off))
        rows.append(dict(study="sagfreq", solver=solver, sag_free="1", tip_hz=on))
    return rows


def test_no_swing_is_said_and_a_changed_frequency_given_with_its_change():
    (line,) = reduced_report._sag_recommendation(_rows(("", ""), ("16.88", "18.9")))
    assert "xpbd: no strand swings" in line
    assert "ftl: the tip swings at 16.88 Hz without it and 18.9 Hz with it (+12.0%)" in line
    assert "— Hz" not in line


def test_equal_frequencies_are_given_as_measured():
    (line,) = reduced_report._sag_recommendation(_rows(("15.7", "15.7"), ("15.67", "15.69")))
    assert "xpbd: the tip swings at 15.7 Hz without it and 15.7 Hz with it (+0.0%)" in line
    assert "ftl: the tip swings at 15.67 Hz without it and 15.69 Hz with it (+0.1%)" in line


def test_one_run_without_swing_is_not_called_a_frequency():
    (line,) = reduced_report._sag_recommendation(_rows(("15.7", ""), ("15.67", "15.69")))
    assert "xpbd: no strand swings in one of the two runs" in line
