"""`harness bench` (what `make bench` runs), end to end on the tiny configs/sweeps/quick.toml.

The CPU test needs build/hairsim-cpu (skipped with the reason without it; `make test`
builds it first); the GPU test is marked `gpu`. The failure paths use the stand-in
backend support.fakebackend."""

import csv
import json
import os
import subprocess
import sys

import pytest

from conftest import CPU_BIN, ROOT
from harness.render.gl import context
from support.fakebackend import install

needs_cpu = pytest.mark.skipif(not CPU_BIN.exists(), reason=f"{CPU_BIN} is not built (run make)")


def bench(tmp_path, *extra, env=None, timeout=600):
    cmd = [
        sys.executable,
        "-m",
        "harness",
        "bench",
        "--model",
        "paper",
        "--sweep",
        "configs/sweeps/quick.toml",
        "--out",
        str(tmp_path / "run"),
        *extra,
    ]
    return subprocess.run(
        cmd, cwd=ROOT, capture_output=True, text=True, timeout=timeout, env=dict(os.environ, **(env or {}))
    )


def git_status():
    """The repository's `git status --porcelain` of tracked files (other tests may add files)."""
    p = subprocess.run(
        ["git", "status", "--porcelain", "--untracked-files=no"], cwd=ROOT, capture_output=True, text=True, timeout=60
    )
    assert p.returncode == 0, p.stderr
    return p.stdout


@needs_cpu
def test_bench_end_to_end_on_cpu(tmp_path):
    before, status = scratch_listing(), git_status()
    p = bench(tmp_path, env={"HAIRBENCH_NO_GPU": "1"})
    assert p.returncode == 0, p.stdout + p.stderr
    assert "Traceback" not in p.stderr
    # the tree is left as found: no tracked file changed
    assert git_status() == status
    # the validator's states went to a scratch under --out and are gone
    assert scratch_listing() == before and not (tmp_path / "run" / "sweep" / "_scratch").exists()
    gpu_lines = [ln for ln in p.stdout.splitlines() if "GPU" in ln]
    assert gpu_lines == ["harness: GPU rows skipped: HAIRBENCH_NO_GPU is set"]
    results = tmp_path / "run" / "sweep"
    validation = json.loads((results / "validation.json").read_text())
    assert validation["checks"] and all(c["equivalent"] for c in validation["checks"])
    n = len(validation["checks"])  # the progress line counted every comparison it planned
    assert f"validation: {n}/{n} done" in p.stderr
    whats = " ".join(c["what"] for c in validation["checks"])
    assert "1 thread vs all cores" in whats and "fp32 vs cpu fp64" in whats and "resumed" in whats
    with open(results / "runs.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    cases = {r["case_id"] for r in rows}
    assert len(cases) == 2 * 2 * 2 and len(rows) == 4 * len(cases)  # strands × precision × threads
    assert all(r["backend"] == "cpu" and float(r["median_ms"]) > 0 for r in rows)
    assert all(int(r["n_times"]) >= 9 and r["copy_gbps"] for r in rows)
    env = json.loads((results / "env.json").read_text())
    assert env["sessions"][0]["skipped"][0]["reason"] == "HAIRBENCH_NO_GPU is set"
    # where the time went: steps.json holds the steps the log's last line names, no GPU work
    steps = json.loads((tmp_path / "run" / "steps.json").read_text())
    last = p.stdout.strip().splitlines()[-1]
    assert [s["name"] for s in steps["steps"]] == ["validation", "sweep quick and its report"]
    assert all(f"{s['name']} {s['seconds']:.0f} s" in last for s in steps["steps"]) and steps["gpus"] == []
    assert not any("gpu_work_s" in s for s in steps["steps"])
    md = (tmp_path / "run" / "report" / "report.md").read_text()  # the report inside the run's folder
    assert "GPU rows are absent**: HAIRBENCH_NO_GPU is set" in md
    n = len(validation["checks"])
    assert f"{n} of {n} comparisons equivalent" in md
    for png in ("speedup_fp32.png", "fig1_initialized.png", "fig2_after_wind.png"):
        assert (tmp_path / "run" / "report" / png).stat().st_size > 5000
    if context.unavailable() is None:  # the paper's figures rendered too (harness/render/hair_report.py)
        for png in ("fig1_rendered.png", "fig2_rendered.png"):
            assert (tmp_path / "run" / "report" / png).stat().st_size > 5000
        assert "![Fig. 2, hair after wind](fig2_rendered.png)" in md
    else:
        assert f"Not rendered: {context.unavailable()}" in md
    # the report is what its results render to: rendered again from the run's files, the
    # same page but for the line that says when and from where
    again = subprocess.run(
        [sys.executable, "-m", "harness", "report", str(results), "--report-dir", str(tmp_path / "again")],
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert again.returncode == 0, again.stdout + again.stderr
    page = [ln for ln in md.splitlines() if not ln.startswith("Generated ")]
    assert page == [
        ln for ln in (tmp_path / "again" / "report.md").read_text().splitlines() if not ln.startswith("Generated ")
    ]
    # run again: the sweep resumes (nothing to do), the report is rebuilt
    p = bench(tmp_path, env={"HAIRBENCH_NO_GPU": "1"})
    assert p.returncode == 0 and "8 case(s) already complete" in p.stdout
    with open(results / "runs.csv", newline="") as f:
        assert len(list(csv.DictReader(f))) == len(rows)


def test_bench_without_binaries_says_run_make(tmp_path):
    p = bench(tmp_path, env={"HAIRBENCH_BUILD_DIR": str(tmp_path / "empty")})
    assert p.returncode == 2
    assert p.stderr.strip().endswith("hairsim-cpu not found: run make")
    assert p.stderr.count("\n") == 1 and not (tmp_path / "run").exists()


def scratch_listing():
    """What the repository's results/_scratch holds (a bench with --out must add nothing)."""
    d = ROOT / "results" / "_scratch"
    return sorted(str(q) for q in d.rglob("*")) if d.exists() else []


def test_bench_fails_before_timing_when_not_equivalent(tmp_path):
    build = install(tmp_path / "build", ["hairsim-cpu"])
    before = scratch_listing()
    p = bench(tmp_path, env={"HAIRBENCH_BUILD_DIR": str(build), "HAIRBENCH_NO_GPU": "1", "FAKE_SHIFT_FP32": "0.01"})
    assert p.returncode == 1, p.stdout + p.stderr
    assert "harness: error: validation failed" in p.stderr and "nothing was timed" in p.stderr
    assert "NOT EQUIVALENT: cpu fp32 vs cpu fp64" in p.stdout
    results = tmp_path / "run" / "sweep"
    assert not (results / "runs.csv").exists()
    checks = json.loads((results / "validation.json").read_text())["checks"]
    assert not next(c for c in checks if c["what"] == "cpu fp32 vs cpu fp64")["equivalent"]
    # the states are kept for a look under --out, nothing under the repository's results/
    assert scratch_listing() == before
    kept = list((results / "_scratch").glob("bench-validation-*/*.h5"))
    assert kept and str(kept[0].parent.relative_to(results)) in p.stderr.replace("\\", "/")


@pytest.mark.gpu
def test_bench_validates_every_gpu_variant(tmp_path):
    # 383 validations, each a GPU process: on a GPU node shared with three other jobs (16 cores,
    # 2026-11-27) they took about 530 s of the 600 this test once allowed
    p = bench(tmp_path, "--gpu", "yes", timeout=1800)
    assert p.returncode == 0, p.stdout[-3000:] + p.stderr[-3000:]
    checks = json.loads((tmp_path / "run" / "sweep" / "validation.json").read_text())["checks"]
    gpu = [c for c in checks if c["what"].startswith("cuda")]
    assert len(gpu) >= 3 * 6 * 2 and all(c["equivalent"] for c in gpu)
    with open(tmp_path / "run" / "sweep" / "runs.csv", newline="") as f:
        assert any(r["backend"] == "cuda" for r in csv.DictReader(f))


def test_the_default_run_folder_and_report_are_untracked_and_ignored():
    """make bench's defaults write only where git ignores: results/local/ and its report/,
    never the committed report/ (so the run's recorded revision stays clean)."""
    from harness.core.paths import LOCAL_RUN, REFERENCE_REPORT, REPORT

    assert REPORT.is_relative_to(LOCAL_RUN) and REFERENCE_REPORT == ROOT / "report"
    for path in (LOCAL_RUN / "sweep" / "runs.csv", REPORT / "report.md", REPORT / "dynamic.gif"):
        rel = str(path.relative_to(ROOT))
        ignored = subprocess.run(["git", "check-ignore", "-q", rel], cwd=ROOT, timeout=60)
        assert ignored.returncode == 0, f"{rel} is not ignored by git"
        tracked = subprocess.run(["git", "ls-files", "--error-unmatch", rel], cwd=ROOT, capture_output=True, timeout=60)
        assert tracked.returncode != 0, f"{rel} is tracked"
