"""harness.core.progress off a terminal: a line at most every 30 s and at the end, with the
count, the time elapsed and an estimate of what is left (a CI log shows the step is alive)."""

import io

from harness.core.progress import LOG_EVERY_S, Progress


class Clock:
    def __init__(self):
        self.t = 1000.0

    def __call__(self):
        return self.t


def test_lines_at_most_every_30_s_and_at_the_end():
    out, clock = io.StringIO(), Clock()
    p = Progress(10, "sweep", stream=out, clock=clock)
    for _ in range(10):
        clock.t += 10.0  # a case takes 10 s
        p.update()
    p.close()
    lines = out.getvalue().splitlines()
    # 30 s, 60 s and 90 s pass after cases 3, 6, 9; case 10 ends the step
    assert [ln.split(":")[1].split()[0] for ln in lines] == ["3/10", "6/10", "9/10", "10/10"]
    assert lines[0] == "sweep: 3/10 done, 30 s elapsed, about 70 s left"
    assert lines[-1] == "sweep: 10/10 done, 100 s elapsed, about 0 s left"
    assert LOG_EVERY_S == 30.0


def test_quick_steps_print_only_the_end_line():
    out, clock = io.StringIO(), Clock()
    p = Progress(4, "validation", stream=out, clock=clock)
    for _ in range(4):
        clock.t += 1.0
        p.update()
    assert out.getvalue().splitlines() == ["validation: 4/4 done, 4 s elapsed, about 0 s left"]


def test_messages_pass_through_and_an_empty_step_prints_nothing():
    out = io.StringIO()
    p = Progress(0, "nothing", stream=out, clock=Clock())
    p.write("harness: skipping a case")
    p.close()
    assert out.getvalue() == "harness: skipping a case\n"
