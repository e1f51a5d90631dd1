"""The dynamic bench's order of steps (harness/bench/dynamic.py `studies`): the pictures — the
animation and the renders — come before the open-ended studies, so a budget that those studies
spend still leaves the report its pictures, and the accuracy study's modes are drawn right after
the study that picks them (the studies stubbed: no real run)."""

from harness.bench import dynamic as bench_dynamic
from harness.core.budget import Budget
from harness.studies import featurecost_dynamic as featurecost
from support.bench_stubs import Clock  # the fixture `stubbed` comes from there too (tests/conftest.py)


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
