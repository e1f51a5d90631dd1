"""Honest timings (harness/core/timing.py, core/rounds.py): nvbench's stopping rule on known
samples, the statistics and noise of a figure, ties within noise, merging rounds, and the load
probe."""

import math

import pytest

from harness.core import load, rounds, timing, tolerances

RULE = timing.StopRule(min_samples=10, min_seconds=0.5, max_rsd=0.005, timeout_s=3.0, max_samples=2000)


def test_the_rule_asks_for_ten_samples_then_half_a_second_then_a_small_spread():
    assert RULE.need([]) == 10
    assert RULE.need([100.0] * 4) == 6  # 0.4 s but only 4 samples
    assert RULE.need([1.0] * 10) == 490  # 10 ms of 1 ms samples: 490 more make 0.5 s
    assert RULE.need([100.0] * 10) == 0  # 1 s, no spread: met
    noisy = [90.0, 110.0] * 5  # 1 s, spread 10 %: as many again
    assert RULE.need(noisy) == 10
    assert RULE.need([0.001] * 1999) == 1  # at most max_samples
    assert timing.fixed(9).need([1.0, 50.0] * 4 + [3.0]) == 0  # one round of `repeat`, whatever the spread


def test_within_a_budget_the_minimum_time_and_timeout_shrink_to_a_share():
    r = RULE.within(10.0, 100)  # 0.1 s a figure
    assert r.min_seconds == pytest.approx(0.1) and r.timeout_s == pytest.approx(0.1) and r.min_samples == 10
    assert RULE.within(1e6, 1) == RULE


def test_stats_of_known_samples():
    s = timing.stats([1.0, 2.0, 3.0, 4.0])
    assert s["n"] == 4 and s["median_ms"] == 2.5 and s["mean_ms"] == 2.5 and s["total_s"] == pytest.approx(0.01)
    assert s["std_ms"] == pytest.approx(math.sqrt(5 / 3)) and s["rsd"] == pytest.approx(math.sqrt(5 / 3) / 2.5)
    assert timing.stats([])["n"] == 0


def test_a_figure_is_noise_by_its_spread_or_the_load_it_ran_under():
    quiet = timing.Figure([10.0, 10.01, 9.99] * 4, load={"other_cores": 0.05, "gpu_busy_pct": 0.0})
    assert timing.noise(quiet) == ""
    spread = timing.Figure([9.0, 11.0] * 6, load={"other_cores": 0.0})
    assert "spread" in timing.noise(spread)
    loaded = timing.Figure([10.0] * 12, load={"other_cores": tolerances.TIMING_OTHER_CORES + 0.1})
    assert "others used" in timing.noise(loaded)
    gpu = timing.Figure([10.0] * 12, load={"gpu_busy_pct": 50.0}, backend="cuda")
    assert (
        "GPU 50 % busy" in timing.noise(gpu)
        and timing.noise(timing.Figure([10.0] * 12, load={"gpu_busy_pct": 50.0})) == ""
    )
    cols = loaded.columns("time_")
    assert cols["time_n_samples"] == 12 and cols["time_noisy"].startswith("others used")


def test_ties_within_noise():
    assert timing.overlaps((8.0, 0.0), (8.0056, 0.0))  # 0.07 %: inside nvbench's ±0.5 % floor
    assert not timing.overlaps((8.0, 0.001), (8.2, 0.001))  # 2.5 % apart, 0.1 % spreads
    assert timing.overlaps((8.0, 0.01), (8.2, 0.01))  # ±2 % bands meet
    assert timing.tie([(9.0, 0.001), (8.0, 0.001), (8.03, 0.001), (12.0, 0.001)]) == [1, 2]


def test_rounds_merge_the_stage_times_and_recompute_the_statistics():
    rec = {"stages": [{"stage": "simulate", "times_ms": [1.0, 3.0], "median_ms": 2.0, "point_substeps_per_s": 10.0}]}
    more = {"stages": [{"stage": "simulate", "times_ms": [5.0], "median_ms": 5.0, "point_substeps_per_s": 4.0}]}
    st = rounds.merge(rec, more)["stages"][0]
    assert st["times_ms"] == [1.0, 3.0, 5.0] and st["median_ms"] == 3.0 and st["min_ms"] == 1.0
    assert st["point_substeps_per_s"] == pytest.approx(4.0 * 5.0 / 3.0)  # the rate of the merged median


def test_the_next_round_stops_at_the_timeout_or_fits_inside_it():
    rec = {"stages": [{"times_ms": [9.0, 11.0] * 5}]}  # 0.1 s of samples, spread 10 %
    assert rounds._next(rec, RULE, elapsed_s=3.5) == (0, "timeout")
    more, why = rounds._next(rec, RULE, elapsed_s=2.0)
    assert why == "" and more == 40  # 40 × 10 ms make the 0.5 s, inside the 1 s left
    assert rounds._next(rec, RULE, elapsed_s=2.8)[0] == 20  # only 0.2 s left: 20 at the median's pace
    full = {"stages": [{"times_ms": [100.0] * 10}]}
    assert rounds._next(full, RULE, elapsed_s=1.0) == (0, "rule met")


def test_the_load_probe_counts_others_not_ourselves():
    probe = load.LoadProbe()
    x = 0
    for i in range(2_000_000):  # this process busy: not counted as others'
        x += i
    ran_under = probe.stop()
    assert ran_under["wall_s"] > 0 and (ran_under["other_cores"] is None or ran_under["other_cores"] >= 0)
