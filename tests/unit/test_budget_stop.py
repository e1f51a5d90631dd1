"""core.budget.run_study: a study under a budget is stopped, with the binaries it started,
when the budget runs out, and what it had written by then is removed (nothing it found)."""

import os
import subprocess
import time

import pytest

from harness import HarnessError
from harness.core.budget import Budget, run_study


def test_a_study_that_ends_in_time_keeps_its_files(tmp_path):
    plan, lines = Budget(60.0), []
    out = tmp_path / "study"

    def study():
        out.mkdir()
        (out / "rows.csv").write_text("a\n1\n")

    assert run_study(plan, "study", study, [out], lines.append) is True
    assert (out / "rows.csv").read_text() == "a\n1\n" and plan.left_out == [] and lines == []


def test_a_study_past_the_budget_is_stopped_with_its_binaries_and_its_new_files_removed(tmp_path):
    out = tmp_path / "study"
    out.mkdir()
    (out / "earlier.csv").write_text("kept\n")  # what the folder held before: never removed
    pid_file = tmp_path / "pid"
    plan, lines = Budget(1.0), []

    def study():
        (out / "partial.csv").write_text("half\n")
        (tmp_path / "report").mkdir()  # a folder it made: removed too
        (tmp_path / "report" / "plot.png").write_bytes(b"png")
        child = subprocess.Popen(["sleep", "120"])
        pid_file.write_text(str(child.pid))
        child.wait()

    t0 = time.monotonic()
    assert run_study(plan, "stability", study, [out, tmp_path / "report"], lines.append) is False
    assert time.monotonic() - t0 < 30  # stopped, not waited for
    assert sorted(p.name for p in out.iterdir()) == ["earlier.csv"] and not (tmp_path / "report").exists()
    assert plan.left_out == [
        {
            "step": "stability",
            "what": "the whole study",
            "reason": "stopped when the budget ran out; what it had written was removed",
        }
    ]
    assert lines == ["harness: stability: stopped when the budget ran out (what it had written is removed)"]
    pid = int(pid_file.read_text())
    for _ in range(50):  # the binary it started is gone too (reaped by init once killed)
        try:
            os.kill(pid, 0)
        except ProcessLookupError:
            break
        with open(f"/proc/{pid}/stat") as f:
            if f.read().split()[2] == "Z":
                break
        time.sleep(0.1)
    else:
        pytest.fail(f"the study's binary {pid} still runs")


def test_a_failing_study_fails_the_bench_in_one_line(tmp_path, capfd):
    def study():
        raise HarnessError("the reference ladder did not converge")

    with pytest.raises(HarnessError, match=r"accuracy failed \(exit 2; its error is above\)") as e:
        run_study(Budget(60.0), "accuracy", study, [tmp_path], lambda m: None)
    assert e.value.code == 2  # the study's own exit status
    err = capfd.readouterr().err
    assert "harness: error: the reference ladder did not converge" in err and "Traceback" not in err


def test_a_budget_on_a_fake_clock_runs_the_study_in_process(tmp_path):
    seen = []
    plan = Budget(10.0, clock=lambda: 0.0, stop_studies=False)
    assert run_study(plan, "study", lambda: seen.append(os.getpid()), [tmp_path], lambda m: None) is True
    assert seen == [os.getpid()]
