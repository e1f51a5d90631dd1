"""`harness sweep`: tidy rows, IQR from times_ms, roofline bytes, skipped cases said aloud,
and resume after a kill with no lost or duplicated rows.

The backend is support.fakebackend (installed as build/hairsim-* in a temporary build dir
through HAIRBENCH_BUILD_DIR), so these tests need no build and take seconds."""

import csv
import os
import signal
import subprocess
import sys
import time

import pytest

from conftest import ROOT
from harness.io import runlog
from harness.io.sweepfile import load_sweep
from harness.studies import roofline
from harness.studies.sweep import quartiles, run_sweep
from support.fakebackend import install
from support.sweeps import sweep_toml

SWEEP = sweep_toml(
    "t",
    strands=[10, 20, 30],
    points=[4],
    precision=["fp32", "fp64"],
    warmup=1,
    threads=[1, "all"],
    cuda={"variant": ["paper"], "block_size": [32, 64]},
)
N_CPU_CASES = 3 * 2 * 2
STAGES = 4


@pytest.fixture
def fake(tmp_path, monkeypatch):
    build = install(tmp_path / "build", ["hairsim-cpu", "hairsim-cuda"])
    monkeypatch.setenv("HAIRBENCH_BUILD_DIR", str(build))
    monkeypatch.setenv("HAIRBENCH_NO_GPU", "1")
    sweep = tmp_path / "t.toml"
    sweep.write_text(SWEEP)
    return sweep


def read_csv(path):
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def assert_complete_once(rows, n_cases):
    keys = [(r["case_id"], r["stage_index"]) for r in rows]
    assert len(keys) == len(set(keys)), "duplicated rows"
    cases = {r["case_id"] for r in rows}
    assert len(cases) == n_cases, "lost cases"
    for c in cases:
        assert sorted(int(r["stage_index"]) for r in rows if r["case_id"] == c) == list(range(STAGES))


def test_rows_are_tidy_with_iqr_and_roofline(fake, tmp_path, capsys):
    out = tmp_path / "res"
    run_sweep(fake, out=out)
    err = capsys.readouterr().out
    assert "skipping 12 cuda" in err and "HAIRBENCH_NO_GPU is set" in err  # said, not silent
    rows = read_csv(out / "runs.csv")
    assert_complete_once(rows, N_CPU_CASES)
    assert list(rows[0]) == runlog.COLUMNS
    r = next(r for r in rows if r["stage"] == "wind" and r["precision"] == "fp64" and r["strands"] == "20")
    # the fake's wind (stage 2) takes 3·(1…9) ms: quartiles of 3, 6, …, 27
    assert float(r["median_ms"]) == 15.0 and int(r["n_times"]) == 9
    assert float(r["q1_ms"]) == 9.0 and float(r["q3_ms"]) == 21.0 and float(r["iqr_ms"]) == 12.0
    assert int(r["bytes_moved"]) == 20 * 4 * 2 * 8 * 2
    assert float(r["achieved_gbps"]) == pytest.approx(20 * 4 * 2 * 8 * 2 / 15e-3 / 1e9)
    assert float(r["copy_gbps"]) == 10.0
    assert float(r["bandwidth_fraction"]) == pytest.approx(float(r["achieved_gbps"]) / 10.0)
    env = (out / "env.json").read_text()
    assert '"cpu_cores"' in env and '"git_revision"' in env and '"flags": "fake"' in env


def test_roofline_bytes():
    assert roofline.stage_bytes("init", 10, 4, "fp32") == 10 * 4 * 3 * 4
    assert roofline.stage_bytes("wind", 10, 4, "fp64") == 10 * 4 * 2 * 8 * 2
    assert roofline.stage_bytes("collide", 10, 4, "fp32") == 10 * 4 * 2 * 4 * 2
    # a collide pass writes only the points it moves
    assert roofline.stage_bytes("collide", 10, 4, "fp32", moved=3) == 10 * 4 * 2 * 4 + 3 * 2 * 4
    assert roofline.stage_bytes("collide", 10, 4, "fp32", moved=0) == 10 * 4 * 2 * 4
    assert roofline.stage_bytes("wind", 10, 4, "fp32", fused="wind+collide") == 10 * 4 * 2 * 4 * 2
    assert roofline.stage_bytes("collide", 10, 4, "fp32", fused="into-previous") == 0
    assert roofline.stage_bytes("wind", 10, 4, "fp32", skipped=True) == 0
    assert quartiles([1, 2, 3, 4, 5]) == (2.0, 4.0)
    assert quartiles([]) == (None, None)


def test_resume_after_sigkill(fake, tmp_path):
    """Kill a running sweep with SIGKILL mid-way, tear its last line, resume: every case
    once, complete."""
    out = tmp_path / "res"
    env = dict(os.environ, FAKE_SLEEP="0.25", PYTHONPATH=str(ROOT))
    cmd = [sys.executable, "-m", "harness", "sweep", str(fake), "--out", str(out), "--gpu", "no"]
    p = subprocess.Popen(
        cmd, cwd=ROOT, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, start_new_session=True
    )
    csv_path = out / "runs.csv"
    deadline = time.time() + 60
    while time.time() < deadline:
        if csv_path.exists() and len(read_csv(csv_path)) >= 3 * STAGES:
            break
        time.sleep(0.05)
    os.killpg(p.pid, signal.SIGKILL)
    p.wait()
    rows = read_csv(csv_path)
    assert STAGES * 3 <= len(rows) < STAGES * N_CPU_CASES, "the kill came too late to test anything"
    with open(csv_path, "a") as f:  # what a kill inside a write leaves: a torn line
        f.write("paper:cpu:ref:t1:fp32:N30:P4:r9w1,0,4,in")
    done_before = {r["case_id"] for r in rows}

    p = subprocess.run(cmd, cwd=ROOT, env=dict(env, FAKE_SLEEP="0"), capture_output=True, text=True)
    assert p.returncode == 0, p.stderr
    assert f"{len(done_before)} case(s) already complete" in p.stdout
    assert "dropped" in p.stdout
    assert_complete_once(read_csv(csv_path), N_CPU_CASES)


def test_resume_drops_a_partial_case_and_keeps_the_rest(fake, tmp_path):
    out = tmp_path / "res"
    run_sweep(fake, out=out, gpu="no")
    path = out / "runs.csv"
    lines = path.read_text().splitlines(keepends=True)
    complete = lines[: 1 + 5 * STAGES]
    partial = lines[1 + 5 * STAGES : 1 + 5 * STAGES + 2]  # 2 of a case's 4 rows
    path.write_text("".join(complete + partial))
    size_before = len("".join(complete))
    done, dropped = runlog.resume(path)
    assert len(done) == 5 and dropped == len("".join(partial))
    assert path.stat().st_size == size_before
    run_sweep(fake, out=out, gpu="no")
    assert_complete_once(read_csv(path), N_CPU_CASES)
    # a finished sweep run again adds nothing
    before = path.read_text()
    run_sweep(fake, out=out, gpu="no")
    assert path.read_text() == before


def test_a_foreign_csv_is_never_truncated(fake, tmp_path):
    out = tmp_path / "res"
    out.mkdir()
    (out / "runs.csv").write_text("a,b,c\n1,2,3\n")
    with pytest.raises(Exception) as e:  # a folder that is not a run's: refused before anything
        run_sweep(fake, out=out, gpu="no")
    assert "not a hairbench run folder" in str(e.value)
    with pytest.raises(Exception) as e:  # and with --force, its foreign runs.csv is still not touched
        run_sweep(fake, out=out, gpu="no", force=True)
    assert "other columns" in str(e.value)
    assert (out / "runs.csv").read_text() == "a,b,c\n1,2,3\n"


def test_missing_bandwidth_and_too_big_cases(fake, tmp_path, monkeypatch, capsys):
    monkeypatch.setenv("FAKE_NO_BANDWIDTH", "1")
    monkeypatch.setenv("FAKE_TOO_BIG", "25")
    out = tmp_path / "res"
    _, failed = run_sweep(fake, out=out, gpu="no")
    said = capsys.readouterr().out
    assert failed == 0
    assert "--measure-bandwidth failed" in said and "fractions are left empty" in said
    rows = read_csv(out / "runs.csv")
    assert {r["strands"] for r in rows} == {"10", "20"}
    assert all(r["bandwidth_fraction"] == "" and r["copy_gbps"] == "" for r in rows)
    assert "N30" in (out / "env.json").read_text()  # the skipped cases are recorded


def test_gpu_yes_without_gpu_is_an_error(fake, tmp_path):
    with pytest.raises(Exception) as e:
        run_sweep(fake, out=tmp_path / "res", gpu="yes")
    assert "no GPU is usable" in str(e.value)


def test_groups_and_overrides(tmp_path):
    p = tmp_path / "g.toml"
    p.write_text(
        'scene = "paper"\n[axes]\nstrands = [1, 2]\n[[cpu]]\nthreads = [1]\n'
        '[[cpu]]\nthreads = [1, "all"]\nstrands = [2, 3]\n'
    )
    cases = load_sweep(p).cases()
    assert sorted((c.strands, c.threads) for c in cases) == [(1, "1"), (2, "1"), (2, "all"), (3, "1"), (3, "all")]


def test_a_sweep_does_not_resume_rows_of_another_machine(tmp_path):
    """Rows measured on two machines must never mix in one runs.csv."""
    from harness import HarnessError
    from harness.studies.sweep import check_same_machine

    h200 = {"cpu_model": "Intel(R) Xeon(R) Processor", "cpu_cores": 16, "gpus": [{"name": "NVIDIA H200"}]}
    laptop = {"cpu_model": "AMD EPYC", "cpu_cores": 2, "gpus": []}
    check_same_machine(h200, dict(h200), tmp_path)  # same machine: fine
    with pytest.raises(HarnessError, match="another machine .*NVIDIA H200.*this one is AMD EPYC, 2 cores, no GPU"):
        check_same_machine(h200, laptop, tmp_path)


def test_a_killed_session_is_not_marked_finished(fake, tmp_path):
    """#46 M9: env.json's session of a sweep killed mid-way has no finished_at; the one that
    resumes it to the end has."""
    import json

    out = tmp_path / "res"
    env = dict(os.environ, FAKE_SLEEP="0.25", PYTHONPATH=str(ROOT))
    cmd = [sys.executable, "-m", "harness", "sweep", str(fake), "--out", str(out), "--gpu", "no"]
    p = subprocess.Popen(
        cmd, cwd=ROOT, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, start_new_session=True
    )

    def cases_run():
        try:
            return json.loads((out / "env.json").read_text())["sessions"][-1]["cases_run"]
        except (OSError, ValueError, KeyError, IndexError):
            return 0

    deadline = time.time() + 60
    while time.time() < deadline and cases_run() < 1:
        time.sleep(0.05)
    os.killpg(p.pid, signal.SIGKILL)
    p.wait()
    killed = json.loads((out / "env.json").read_text())["sessions"][-1]
    assert killed["cases_run"] >= 1 and "finished_at" not in killed, killed
    assert subprocess.run(cmd, cwd=ROOT, env=dict(env, FAKE_SLEEP="0"), capture_output=True).returncode == 0
    assert "finished_at" in json.loads((out / "env.json").read_text())["sessions"][-1]
