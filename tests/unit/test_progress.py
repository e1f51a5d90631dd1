"""harness.core.progress off a terminal: a line at the start, then at least every 30 s and at
the end, with the count, the time elapsed and an estimate of what is left (a CI log shows the
step is alive)."""

import io
import time

import pytest

from harness.core.progress import LINE_AFTER_S, LOG_EVERY_S, Progress, StepTimes


class Clock:
    def __init__(self):
        self.t = 1000.0

    def __call__(self):
        return self.t


def test_a_start_line_then_lines_every_30_s_and_at_the_end():
    out, clock = io.StringIO(), Clock()
    p = Progress(10, "sweep", stream=out, clock=clock)
    for _ in range(10):
        clock.t += 10.0  # a case takes 10 s
        p.update()
    p.close()
    lines = out.getvalue().splitlines()
    assert lines[0] == "sweep: 10 to do"
    # 30 s, 60 s and 90 s pass after cases 3, 6, 9; case 10 ends the step
    assert [ln.split(":")[1].split()[0] for ln in lines[1:]] == ["3/10", "6/10", "9/10", "10/10"]
    assert lines[1] == "sweep: 3/10 done, 30 s elapsed, about 70 s left"
    assert lines[-1] == "sweep: 10/10 done, 100 s elapsed, about 0 s left"
    assert LOG_EVERY_S == 30.0 and LINE_AFTER_S < LOG_EVERY_S


def test_quick_steps_print_only_the_start_and_end_lines():
    out, clock = io.StringIO(), Clock()
    p = Progress(4, "validation", stream=out, clock=clock)
    for _ in range(4):
        clock.t += 1.0
        p.update()
    assert out.getvalue().splitlines() == ["validation: 4 to do", "validation: 4/4 done, 4 s elapsed, about 0 s left"]


def test_messages_pass_through_and_an_empty_step_prints_nothing():
    out = io.StringIO()
    p = Progress(0, "nothing", stream=out, clock=Clock())
    p.write("harness: skipping a case")
    p.close()
    assert out.getvalue() == "harness: skipping a case\n"


def test_a_long_case_still_prints_a_line_every_30_s():
    """One case can take minutes: the timer's tick prints the line while nothing ends, a
    second before the 30 s are up."""
    out, clock = io.StringIO(), Clock()
    p = Progress(3, "featurecost", stream=out, clock=clock)
    clock.t += 28.5
    p.tick()
    assert out.getvalue().splitlines() == ["featurecost: 3 to do"]
    clock.t += 0.5
    p.tick()
    clock.t += 10.0
    p.tick()  # 10 s after the last line: nothing
    clock.t += 19.0
    p.tick()
    p.close()
    assert out.getvalue().splitlines()[1:] == [
        "featurecost: 0/3 done, 29 s elapsed, no estimate before the first is done",
        "featurecost: 0/3 done, 58 s elapsed, no estimate before the first is done",
    ]


def test_the_timer_thread_prints_without_an_update():
    out = io.StringIO()
    with Progress(2, "peer", stream=out, every=0.05, timer=True) as p:
        deadline = time.monotonic() + 5.0
        while "done" not in out.getvalue() and time.monotonic() < deadline:
            time.sleep(0.01)
        assert p.done == 0
    first, line = out.getvalue().splitlines()[:2]
    assert first == "peer: 2 to do"
    assert line == "peer: 0/2 done, 0 s elapsed, no estimate before the first is done"


def test_step_times_say_each_step_in_order_and_the_total():
    clock = Clock()
    times = StepTimes(clock=clock)

    def work(seconds, result):
        clock.t += seconds
        return result

    assert times.step("validation", work, 72.4, "ok") == "ok"

    def fails():
        work(337.0, None)
        raise RuntimeError("stop")

    with pytest.raises(RuntimeError):  # a step that fails is timed too
        times.step("sweep default", fails)
    clock.t += 5.0  # time between the steps counts in the total only
    assert [name for name, _ in times.steps] == ["validation", "sweep default"]
    assert [s for _, s in times.steps] == pytest.approx([72.4, 337.0])
    assert times.summary("bench") == "harness: bench took 414 s (validation 72 s, sweep default 337 s)"
    assert StepTimes(clock=clock).summary("bench") == "harness: bench took 0 s"


def test_the_estimate_is_by_the_cases_sizes_where_given():
    """Nine small cases (1 unit, 1 s each) then one of 90 units (90 s): by count the line after
    the ninth promises 11 s more; by size it promises the 90 s it takes. A case left out of the
    run leaves the total."""
    out, clock = io.StringIO(), Clock()
    p = Progress(11, "sweep", stream=out, clock=clock, every=1.0, timer=False, work=9 + 90 + 50)
    p.update(1, work=50, skip=True)  # left out by a budget: never run
    for _ in range(9):
        clock.t += 1.0
        p.update(work=1)
    assert out.getvalue().splitlines()[-1] == "sweep: 10/11 done, 9 s elapsed, about 90 s left"
    clock.t += 90.0
    p.update(work=90)
    assert out.getvalue().splitlines()[-1] == "sweep: 11/11 done, 99 s elapsed, about 0 s left"
    by_count = Progress(10, "sweep", stream=io.StringIO(), clock=Clock(), every=1.0, timer=False)
    by_count.clock.t += 9.0
    by_count.update(9)
    assert by_count.stream.getvalue().splitlines()[-1].endswith("about 1 s left")
