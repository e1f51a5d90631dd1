"""`--batch FILE` (docs/interfaces.md, "Batches"): several runs in one process, each line a
run's flags separated by tabs, in order until one fails. Checked on the C reference (the
driver is the one both backends share) through the harness's runner.run_batch, which a sweep
uses for its GPU cases."""

import subprocess

import pytest

from harness.core import runner
from harness.core.runner import BackendError, DoesNotFit, TimedOut

SMALL = ["--strands", "120", "--points", "8", "--repeat", "3"]


# what differs between two runs of the same flags: the times and when
def timing(key):
    return key.endswith(("_ms", "_at", "_per_s")) or key == "times_ms"


def settled(record):
    """A record without its times (the rest is the same for the same flags)."""
    out = {k: v for k, v in record.items() if not timing(k)}
    out["stages"] = [{k: v for k, v in s.items() if not timing(k)} for s in record["stages"]]
    return out


RUNS = [
    SMALL,
    [*SMALL, "--threads", "1", "--precision", "fp64"],
    [*SMALL, "--variant", "simd", "--seed", "7"],
    [*SMALL, "--stages", "init,simulate", "--frames", "2", "--solver", "ftl"],
    SMALL,  # no --threads after a run with one: all cores again
]


def test_a_batch_gives_the_records_of_separate_runs(cpu_bin):
    ended = list(runner.run_batch(cpu_bin, RUNS, timeout=120))
    assert [i for i, _, _ in ended] == list(range(len(RUNS)))
    assert all(e is None for _, _, e in ended)
    for (_, rec, _), args in zip(ended, RUNS):
        assert settled(rec) == settled(runner.run_binary(cpu_bin, args, timeout=120))
    threads = [rec["threads"] for _, rec, _ in ended]
    assert threads[1] == 1 and threads[4] == threads[0]


def test_a_failing_run_is_reported_and_the_runs_after_it_go_on(cpu_bin, tmp_path):
    runs = [SMALL, ["--strands", "-5"], [*SMALL, "--points", "1000000000000"], [*SMALL, "--seed", "3"]]
    ended = list(runner.run_batch(cpu_bin, runs, timeout=120))
    assert [i for i, _, _ in ended] == [0, 1, 2, 3]
    assert ended[0][2] is None and ended[3][2] is None and ended[3][1]["seed"] == 3
    bad = ended[1][2]
    assert isinstance(bad, BackendError) and bad.code == 2 and "--strands must be at least 1" in str(bad)
    assert isinstance(ended[2][2], DoesNotFit | BackendError) and ended[2][2].code in (2, 3)


def test_a_run_past_its_timeout_is_killed_and_the_rest_run(cpu_bin, tmp_path):
    out = tmp_path / "slow.h5"
    # The slow run takes minutes on any machine; the timeout leaves a small run (0.1 s alone) room on a
    # loaded node (1 s was not enough beside 32 test workers on a GPU node's 32 cores).
    slow = ["--strands", "400000", "--points", "64", "--repeat", "100000", "--output", str(out)]
    ended = list(runner.run_batch(cpu_bin, [SMALL, slow, SMALL], timeout=10.0))
    assert ended[0][2] is None and ended[2][2] is None
    assert isinstance(ended[1][2], TimedOut) and ended[1][2].code == 124
    assert list(tmp_path.iterdir()) == []  # the killed run's temporary output is gone


@pytest.mark.parametrize(
    "lines, message",
    [
        (None, "--batch FILE takes no other flag"),
        ("--strands\t10\t--batch\tx\n", "batches do not nest"),
        ("\t".join(["--seed", "1"] * 200) + "\n", "has more than 255 flags and values"),
    ],
)
def test_a_bad_batch_is_one_line_and_exit_2(cpu_bin, tmp_path, lines, message):
    batch = tmp_path / "runs.txt"
    if lines is None:
        cmd = [str(cpu_bin), "--strands", "10", "--batch", str(batch)]
    else:
        batch.write_text(lines)
        cmd = [str(cpu_bin), "--batch", str(batch)]
    p = subprocess.run(cmd, capture_output=True, text=True, timeout=60)
    assert p.returncode == 2 and p.stdout == ""
    assert p.stderr.count("\n") == 1 and message in p.stderr


def test_an_unreadable_batch_file_is_refused(cpu_bin, tmp_path):
    p = subprocess.run([str(cpu_bin), "--batch", str(tmp_path / "none")], capture_output=True, text=True, timeout=60)
    assert p.returncode == 2 and p.stderr.strip().endswith("none: no such file")


def test_flags_holding_a_tab_are_refused_before_any_run(cpu_bin, tmp_path):
    with pytest.raises(runner.HarnessError, match="tab or a line break"):
        list(runner.run_batch(cpu_bin, [SMALL, ["--output", str(tmp_path / "a\tb.h5")]]))
