"""roofline.in_rounds: each round's row is judged against the copy measured just before it,
and the median round is the one reported, with every round kept."""

import itertools

import pytest

from harness.studies import roofline


def _fake_copies(monkeypatch, copies):
    it = iter(copies)
    monkeypatch.setattr(roofline, "measure_bandwidth", lambda binary, timeout=None: {"copy_gbps": next(it)})


def test_each_round_uses_its_own_copy_and_the_median_round_is_reported(monkeypatch):
    _fake_copies(monkeypatch, [100.0, 50.0, 80.0, 40.0, 90.0])
    times = iter([10.0, 11.0, 12.0, 13.0, 14.0])

    def measure(copy):
        ms = next(times)
        gbps = 400.0 / ms  # a row that moves 400 GB·ms
        return {"median_ms": ms, "gbps": gbps, "fraction": gbps / copy}

    row = roofline.in_rounds("cpu", 5, measure)
    fractions = sorted(r["fraction"] for r in row["rounds"])
    assert [r["copy_gbps"] for r in row["rounds"]] == [100.0, 50.0, 80.0, 40.0, 90.0]
    assert [r["median_ms"] for r in row["rounds"]] == [10.0, 11.0, 12.0, 13.0, 14.0]
    assert row["fraction"] == pytest.approx(fractions[2])
    assert row["fraction"] == pytest.approx(row["gbps"] / row["copy_gbps"])
    assert (row["median_ms"], row["copy_gbps"]) == (12.0, 80.0)  # 400/12/80 is the middle fraction


def test_an_even_count_reports_the_lower_middle_round(monkeypatch):
    _fake_copies(monkeypatch, itertools.repeat(100.0))
    fr = iter([0.9, 0.5, 0.7, 0.6])
    row = roofline.in_rounds("cpu", 4, lambda copy: {"wind_collide_fraction": next(fr)}, key="wind_collide_fraction")
    assert row["wind_collide_fraction"] == 0.6
    assert len(row["rounds"]) == 4 and row["rounds"][0]["fraction"] == 0.9


def test_the_median_round_against_the_first_copy(monkeypatch):
    _fake_copies(monkeypatch, [50.0, 80.0, 40.0])
    fr = iter([0.6, 0.5, 0.9])
    row = roofline.in_rounds("cpu", 3, lambda copy: {"fraction": next(fr)}, first_copy=100.0)
    assert (row["fraction"], row["copy_gbps"]) == (0.6, 50.0)
    assert row["fraction_of_first_copy"] == pytest.approx(0.3)  # 0.6 of 50 GB/s is 0.3 of 100
    _fake_copies(monkeypatch, [50.0])
    assert "fraction_of_first_copy" not in roofline.in_rounds("cpu", 1, lambda copy: {"fraction": 0.5})
