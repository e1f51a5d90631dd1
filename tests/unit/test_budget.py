"""harness.core.budget: the size ladder's selection on fake timings (no real run is timed)."""

import pytest

from harness import HarnessError
from harness.core import budget
from harness.core.budget import Budget, TierGate


class Clock:
    def __init__(self):
        self.t = 0.0

    def __call__(self):
        return self.t


@pytest.mark.parametrize(("text", "seconds"), [("600", 600), ("90s", 90), ("10m", 600), ("1h30m", 5400)])
def test_durations(text, seconds):
    assert budget.parse_duration(text) == seconds


@pytest.mark.parametrize("text", ["", "0", "10 m", "m10", "10x", "-5m", "1.5h", "10m10"])
def test_bad_durations_are_refused_in_one_line(text):
    with pytest.raises(HarnessError, match="--budget") as e:
        budget.parse_duration(text)
    assert e.value.code == 2 and "\n" not in str(e.value)


def test_tiers_group_by_size_smallest_first_in_declared_order():
    cases = [("a", 300), ("b", 100), ("c", 300), ("d", 200)]
    got = budget.tiers(cases, size=lambda c: c[1])
    assert [(s, [c[0] for c in t]) for s, t in got] == [(100, ["b"]), (200, ["d"]), (300, ["a", "c"])]


def test_estimate_scales_the_last_tier_by_size_and_count():
    # 4 cases of size 1000 took 8 s: 2 s a case; size 3000 is 3× → 6 s a case, 5 cases → 30 s
    assert budget.estimate((1000, 4, 8.0), (3000, 5)) == pytest.approx(30.0)


def test_only_the_timed_samples_scale_with_the_size():
    """Half of the last tier's 2 s a case was samples (the rest process starts and the stopping
    rule's rounds): at 3× the size a case takes 1 + 3 = 4 s, 5 cases 20 s."""
    assert budget.estimate((1000, 4, 8.0), (3000, 5), work=0.5) == pytest.approx(20.0)
    gate = budget.TierGate(100.0, clock=Clock())
    gate.measured(1000, 4, 8.0, sampled=4.0)
    assert gate.work == 0.5 and gate.admit(3000, 5) == (True, None)


def run_ladder(gate, clock, ladder, seconds_per_unit):
    """Drive the gate over (size, cases) like the sweep, a case costing size × seconds_per_unit."""
    ran = []
    for size, n in ladder:
        ok, _ = gate.admit(size, n)
        if ok:
            took = n * size * seconds_per_unit
            clock.t += took
            gate.measured(size, n, took)
            ran.append(size)
    return ran


def test_the_gate_runs_what_fits_and_leaves_out_the_rest():
    clock = Clock()
    gate = TierGate(100.0, clock=clock)
    ladder = [(1000, 2), (10_000, 2), (100_000, 2), (1_000_000, 2)]
    # a case costs size / 10 000 s: 0.2 s, 2 s, 20 s, 200 s per tier
    ran = run_ladder(gate, clock, ladder, 1e-4)
    assert ran == [1000, 10_000, 100_000]
    assert gate.refused == [(1_000_000, 2)]
    assert gate.summary() == "2 case(s) at sizes 1000000 (strands × points)"
    assert "estimated at 200 s" in gate.closed and "78 s" in gate.closed  # 100 - 22.2 s used


def test_once_a_tier_is_left_out_every_larger_one_is_too():
    clock = Clock()
    gate = TierGate(10.0, clock=clock)
    ran = run_ladder(gate, clock, [(1, 1), (100, 1), (2, 1)], 1.0)  # tiers come sorted; the gate stays shut
    assert ran == [1] and [s for s, _ in gate.refused] == [100, 2]


def test_the_first_tier_always_runs_and_nothing_is_left_out_with_room():
    clock = Clock()
    gate = TierGate(0.0, clock=clock)
    assert gate.admit(10, 3) == (True, None)
    big = TierGate(1e9, clock=clock)
    assert run_ladder(big, clock, [(1, 1), (10, 1), (100, 1)], 1.0) == [1, 10, 100]
    assert big.summary() is None


def test_the_budget_shares_what_is_left_and_records_what_it_left_out():
    clock = Clock()
    b = Budget(600.0, clock=clock)
    clock.t = 100.0  # validation took 100 s
    assert b.allowance("paper sweep") == pytest.approx(500.0 * budget.SHARES["paper sweep"])
    clock.t = 700.0
    assert b.left() == pytest.approx(-100.0) and b.allowance("dynamic sweep") == 0.0
    b.leave_out("peer", "the whole study", "no time left")
    assert b.record() == {
        "budget_s": 600.0,
        "used_s": 700.0,
        "left_out": [{"step": "peer", "what": "the whole study", "reason": "no time left"}],
    }


def test_the_reports_reserve_is_never_handed_to_a_step():
    clock = Clock()
    b = Budget(600.0, clock=clock, reserve=20.0)
    assert b.left() == pytest.approx(580.0)
    assert b.allowance("paper sweep") == pytest.approx(580.0 * budget.SHARES["paper sweep"])
    clock.t = 590.0  # the studies stop at 580 s; the reports have the last 20
    assert b.left() == pytest.approx(-10.0) and b.allowance("curly sweep") == 0.0
    assert b.record()["budget_s"] == 600.0 and b.record()["used_s"] == 590.0


def test_a_study_takes_the_largest_size_that_fits():
    ladder = (100_000, 30_000, 10_000, 1_000)
    per_strand = 0.002  # s: 100 000 strands take 200 s
    assert budget.largest_that_fits(ladder, lambda n: n * per_strand, 500.0) == 100_000
    assert budget.largest_that_fits(ladder, lambda n: n * per_strand, 100.0) == 30_000
    assert budget.largest_that_fits(ladder, lambda n: n * per_strand, 1.0) == 1_000  # none fits: the smallest


def test_the_validations_fixed_cost_is_said_and_an_overrun_says_what_still_runs():
    clock, lines = Clock(), []
    b = Budget(300.0, clock=clock)
    clock.t = 120.0
    budget.say_fixed_cost(b, lines.append)
    assert lines == ["harness: budget: the validations took 120 s; 180 s left for the sweeps and studies"]
    clock.t = 330.0
    budget.say_fixed_cost(b, lines.append)
    assert "the validations alone took 330 s of the 300 s budget" in lines[1]
    assert "smallest size only and no study runs (give at least 390 s for more)" in lines[1]
