"""`harness bench`: both models are validated before either is timed (the order of the
steps, with the steps themselves stood in for; nothing is run)."""

import argparse

import pytest

from harness.bench import dynamic as bench_dynamic
from harness.bench import paper as bench_paper
from harness.cli.commands import bench as bench_command


def bench_args(model, tmp_path):
    """`harness bench --model MODEL --sweep quick --gpu no --out TMP/run`'s arguments."""
    return argparse.Namespace(
        model=model,
        sweep="quick",
        out=str(tmp_path / "run"),
        report_dir=None,
        shard=None,
        budget=None,
        gpu="no",
        full_studies=False,
        scene=None,
    )


@pytest.mark.parametrize(
    ("model", "expected"),
    [
        ("all", ["validate paper", "validate dynamic", "time paper", "time dynamic"]),
        ("paper", ["validate paper", "time paper"]),
        ("dynamic", ["validate dynamic", "time dynamic"]),
    ],
)
def test_every_validation_runs_before_any_timing(monkeypatch, tmp_path, model, expected):
    steps = []
    monkeypatch.setattr(bench_paper, "validate_first", lambda *a, **k: steps.append("validate paper"))
    monkeypatch.setattr(bench_dynamic, "validate_first", lambda *a, **k: steps.append("validate dynamic"))

    def timed(name):
        def run(*a, validated=False, **k):
            assert validated, f"{name} would validate again"
            steps.append(f"time {name}")
            return 0

        return run

    monkeypatch.setattr(bench_paper, "run", timed("paper"))
    monkeypatch.setattr(bench_dynamic, "run", timed("dynamic"))
    assert bench_command.cmd_bench(bench_args(model, tmp_path)) == 0
    assert steps == expected


def test_the_bench_log_ends_with_the_time_of_each_step(monkeypatch, tmp_path, capsys):
    monkeypatch.setattr(bench_paper, "validate_first", lambda *a, **k: None)
    monkeypatch.setattr(bench_dynamic, "validate_first", lambda *a, **k: None)
    monkeypatch.setattr(bench_paper, "run", lambda *a, **k: 0)

    def dynamic(*a, times=None, **k):  # the dynamic bench times its own steps into the same record
        times.step("sweep dynamic", lambda: None)
        return 0

    monkeypatch.setattr(bench_dynamic, "run", dynamic)
    assert bench_command.cmd_bench(bench_args("all", tmp_path)) == 0
    last = capsys.readouterr().out.strip().splitlines()[-1]
    assert last.startswith("harness: bench took ")
    assert last.endswith("(validation 0 s, dynamic validation 0 s, sweep quick and its report 0 s, sweep dynamic 0 s)")
