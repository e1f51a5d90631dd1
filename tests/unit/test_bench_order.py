"""`harness bench`: both models are validated before either is timed (the order of the
steps, with the steps themselves stood in for; nothing is run)."""

import argparse

import pytest

from harness.bench import dynamic as bench_dynamic
from harness.bench import paper as bench_paper
from harness.cli import main


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
    args = argparse.Namespace(
        model=model,
        sweep="quick",
        out=str(tmp_path / "run"),
        report_dir=None,
        shard=None,
        budget=None,
        gpu="no",
        full_studies=False,
    )
    assert main.cmd_bench(args) == 0
    assert steps == expected
