"""A refused command creates nothing: `sweep --gpu yes` and `judge --gpu yes` on a machine
without a GPU (HAIRBENCH_NO_GPU), and a report of a folder without results, each exit 2 in
one line and leave no folder, not even an empty one or a header-only runs.csv."""

import os
import subprocess
import sys

import pytest

from conftest import ROOT
from harness import HarnessError
from harness.render import report_paper


def harness(*args):
    env = dict(os.environ, HAIRBENCH_NO_GPU="1")
    return subprocess.run(
        [sys.executable, "-m", "harness", *args], cwd=ROOT, capture_output=True, text=True, timeout=300, env=env
    )


@pytest.mark.parametrize(
    "command",
    [["sweep", "quick", "--gpu", "yes"], ["judge", "--quick", "--gpu", "yes"]],
    ids=["sweep", "judge"],
)
def test_gpu_yes_without_a_gpu_leaves_nothing(tmp_path, command):
    out = tmp_path / "new" / "run"
    p = harness(*command, "--out", str(out))
    assert p.returncode == 2 and p.stderr.startswith("harness: error:") and p.stderr.count("\n") == 1, p.stderr
    assert not (tmp_path / "new").exists(), sorted(str(x) for x in tmp_path.rglob("*"))


def test_a_report_without_results_makes_no_folder(tmp_path):
    with pytest.raises(HarnessError, match="runs.csv: no such file"):
        report_paper.build(tmp_path / "nothing", tmp_path / "report")
    assert not (tmp_path / "report").exists()
