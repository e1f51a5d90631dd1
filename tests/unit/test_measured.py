"""tests/support/measured.py: the GPU tests' worst-error file is the maximum over every
xdist worker of one run, and a new run starts it afresh."""

import json

from support.measured import write_worst


def test_workers_of_one_run_merge_and_a_new_run_starts_afresh(tmp_path, monkeypatch):
    path = tmp_path / "errors.json"
    monkeypatch.setenv("PYTEST_XDIST_TESTRUNUID", "run-a")
    write_worst(path, {"positions fp32": 2e-7, "velocities fp32": 5e-7})
    write_worst(path, {"positions fp32": 9e-7, "positions fp64": 1e-15})  # another worker
    assert json.loads(path.read_text()) == {"positions fp32": 9e-7, "velocities fp32": 5e-7, "positions fp64": 1e-15}
    monkeypatch.setenv("PYTEST_XDIST_TESTRUNUID", "run-b")
    write_worst(path, {"positions fp32": 1e-7})
    assert json.loads(path.read_text()) == {"positions fp32": 1e-7}
    monkeypatch.delenv("PYTEST_XDIST_TESTRUNUID")  # one process: its own values only
    write_worst(path, {"positions fp64": 3e-15})
    write_worst(path, {"positions fp64": 2e-15})
    assert json.loads(path.read_text()) == {"positions fp64": 2e-15}
    write_worst(path, {})
    assert json.loads(path.read_text()) == {"positions fp64": 2e-15}
    assert sorted(p.name for p in tmp_path.iterdir()) == ["errors.json", "errors.json.lock"]
