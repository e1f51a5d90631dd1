"""`harness bench`: the order of its steps, with the steps themselves stood in for (nothing is
run): both models are validated before either is timed; the dynamic bench's pictures (the
animation and the renders) come before the open-ended studies, so a budget that those studies
spend still leaves the report its pictures, and the accuracy study's modes are drawn right after
the study that picks them."""

import argparse

import pytest

from harness.bench import dynamic as bench_dynamic
from harness.bench import paper as bench_paper
from harness.cli.commands import bench as bench_command
from harness.core.budget import Budget
from harness.studies import featurecost_dynamic as featurecost
from support.bench_stubs import Clock  # the fixture `stubbed` comes from there too (tests/conftest.py)


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


def test_the_pictures_are_made_before_the_studies_that_spend_the_budget(stubbed, tmp_path, monkeypatch):
    calls, _ = stubbed
    clock = Clock()
    budget = Budget(100.0, clock=clock, stop_studies=False)  # the fake clock times no child: studies in-process

    def spend_it_all(**k):  # the first open-ended study uses the whole budget
        calls.append(("featurecost", k.get("backend")))
        clock.t = 200.0

    monkeypatch.setattr(featurecost, "measure", spend_it_all)
    report = tmp_path / "report"
    report.mkdir()
    log = []
    bench_dynamic.studies(tmp_path, [], log.append, report_dir=report, quick=True, budget=budget)
    assert [c[0] for c in calls] == ["animate", "renders", "featurecost"]
    assert calls[0][1] == report / "dynamic.gif" and calls[1][1] == tmp_path
    left_out = {e["step"] for e in budget.record()["left_out"]}
    assert {"animate", "renders"}.isdisjoint(left_out)
    assert {"reduced", "accuracy", "stability"} <= left_out


def test_without_a_report_the_bench_makes_no_pictures(stubbed, tmp_path):
    calls, _ = stubbed
    bench_dynamic.studies(tmp_path, [], lambda line: None, quick=True)
    assert not [c for c in calls if c[0] in ("animate", "renders")]


def test_the_accuracy_modes_are_drawn_right_after_the_study_that_picks_them(stubbed, tmp_path):
    calls, _ = stubbed
    report = tmp_path / "report"
    report.mkdir()
    bench_dynamic.studies(tmp_path, [], lambda line: None, report_dir=report, quick=True)
    steps = [c[0] if isinstance(c[0], str) else f"accuracy {c[0].scene}" for c in calls]
    assert steps[:2] == ["animate", "renders"]
    assert steps[steps.index("accuracy dynamic") + 1] == "mode renders" and steps.count("mode renders") == 1
