"""The dynamic bench's studies replaced by recorders (harness/bench/dynamic.py `studies`), for
tests of what the bench runs, in which order and under which budget, without a real run."""

import pytest

from harness.bench import animate_dynamic as animate
from harness.bench import dynamic as bench_dynamic
from harness.render import accuracy_dynamic_report
from harness.studies import accuracy_dynamic
from harness.studies import budget_curves_dynamic as budget_curves
from harness.studies import featurecost_dynamic as featurecost
from harness.studies import peer_dynamic as peer
from harness.studies import reduced_dynamic as reduced
from harness.studies import stability_dynamic as stability


class Clock:
    def __init__(self):
        self.t = 0.0

    def __call__(self):
        return self.t


@pytest.fixture
def stubbed(monkeypatch):
    """Every dynamic study replaced by a recorder; the accuracy study's calls in `calls` as
    (plan, folder), the animation's and the renders' as ("animate", file), ("renders", root) and
    ("mode renders", root)."""
    calls = []
    hooks = []  # run after each accuracy call (to spend the budget)

    def run_study(plan, out_dir=None, force=False, command=None, log=print):
        calls.append((plan, out_dir))
        for h in hooks:
            h(plan)
        return 0

    monkeypatch.setattr(accuracy_dynamic, "run_study", run_study)
    monkeypatch.setattr(accuracy_dynamic_report, "write", lambda *a, **k: [])
    monkeypatch.setattr(featurecost, "measure", lambda **k: None)
    monkeypatch.setattr(reduced, "measure", lambda *a, **k: None)
    monkeypatch.setattr(stability, "run_study", lambda **k: None)
    monkeypatch.setattr(bench_dynamic, "budget_modes", lambda acc_dir: [])  # the frame budget's curves
    monkeypatch.setattr(budget_curves, "measure", lambda *a, **k: None)
    monkeypatch.setattr(peer, "run_study", lambda *a, **k: None)
    monkeypatch.setattr(bench_dynamic.accuracy_world, "run_study", lambda *a, **k: None)
    monkeypatch.setattr(bench_dynamic.peer_report, "write", lambda *a, **k: None)
    monkeypatch.setattr(animate, "run", lambda **k: calls.append(("animate", k.get("out"))))
    monkeypatch.setattr(bench_dynamic.renders, "simulate", lambda *a, **k: calls.append(("renders", a[0])))
    monkeypatch.setattr(bench_dynamic.renders, "simulate_modes", lambda *a, **k: calls.append(("mode renders", a[0])))
    monkeypatch.setattr(bench_dynamic.stability_report, "report_from_csv", lambda *a, **k: None)
    return calls, hooks
