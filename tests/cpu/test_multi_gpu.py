"""The sweep on a node with several GPUs, with stand-ins: the fake backend (support.fakebackend)
and an nvidia-smi that lists two GPUs. The CPU cases run before any GPU case, the GPU cases
run on one worker per GPU, each child seeing only its GPU (CUDA_VISIBLE_DEVICES), and each
row names the GPU that measured it; HB_GPUS keeps one GPU."""

import csv
import json
import os
import subprocess
import sys

import pytest

from conftest import ROOT
from support.fakebackend import install
from support.sweeps import sweep_toml

SWEEP = sweep_toml(
    "two-gpus",
    strands=[100, 200, 300],
    points=[8],
    precision=["fp32"],
    cuda={"build": ["default"], "variant": ["paper", "fused"], "block_size": [32, 64]},
)
SMI = """#!/bin/sh
case "$1" in
  -L) printf 'GPU 0: Fake GPU (UUID: GPU-fake-0)\\nGPU 1: Fake GPU (UUID: GPU-fake-1)\\n' ;;
  *) printf 'Fake GPU, 0.0, 80 GiB\\nFake GPU, 0.0, 80 GiB\\n' ;;
esac
"""


@pytest.fixture
def node(tmp_path):
    build = install(tmp_path / "build", ["hairsim-cpu", "hairsim-cuda"])
    bin_dir = tmp_path / "bin"
    bin_dir.mkdir()
    (bin_dir / "nvidia-smi").write_text(SMI)
    (bin_dir / "nvidia-smi").chmod(0o755)
    sweep = tmp_path / "two-gpus.toml"
    sweep.write_text(SWEEP)
    env = {k: v for k, v in os.environ.items() if k not in ("HAIRBENCH_NO_GPU", "CUDA_VISIBLE_DEVICES", "HB_GPUS")}
    env.update(
        HAIRBENCH_BUILD_DIR=str(build),
        PATH=f"{bin_dir}{os.pathsep}{env.get('PATH', '')}",
        FAKE_LOG=str(tmp_path / "runs.log"),
        FAKE_SLEEP="0.2",
    )
    return tmp_path, sweep, env


def sweep(node, **extra):
    tmp_path, path, env = node
    out = tmp_path / "out"
    p = subprocess.run(
        [sys.executable, "-m", "harness", "sweep", str(path), "--out", str(out), "--gpu", "yes"],
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=300,
        env=dict(env, **extra),
    )
    assert p.returncode == 0, p.stdout + p.stderr
    with open(out / "runs.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    log = [line.split() for line in (tmp_path / "runs.log").read_text().splitlines()]
    return p, rows, log


def test_gpu_cases_spread_over_both_gpus_after_the_cpu_cases(node):
    p, rows, log = sweep(node)
    assert "spread over 2 GPUs" in p.stdout
    cuda = [e for e in log if e[1] == "cuda"]
    cpu = [e for e in log if e[1] == "cpu"]
    assert len(cpu) == 2 * 3 and len(cuda) == 2 * 3 * 4  # start and end of each case
    first_gpu = next(i for i, e in enumerate(log) if e[1] == "cuda")
    assert all(i < first_gpu for i, e in enumerate(log) if e[1] == "cpu"), "a CPU case ran beside GPU workers"
    assert {e[3] for e in cuda} == {"GPU-fake-0", "GPU-fake-1"}  # each child saw one GPU
    assert {e[3] for e in cpu} == {"-"}
    in_flight, most = 0, 0
    for e in log[first_gpu:]:
        in_flight += 1 if e[0] == "start" else -1
        most = max(most, in_flight)
    assert most == 2  # the two workers overlapped, never more than one case a GPU
    gpu_of = {r["gpu"] for r in rows if r["backend"] == "cuda"}
    assert gpu_of == {"0", "1"} and {r["gpu"] for r in rows if r["backend"] == "cpu"} == {""}
    assert len({r["case_id"] for r in rows}) == 3 + 12
    # the 12 GPU cases in batches of 2 (a quarter of a worker's share), one process each
    pids = [e[4] for e in cuda if e[0] == "start"]
    assert len(set(pids)) == 6 and all(pids.count(p) == 2 for p in pids)


def test_one_gpu_runs_its_cases_in_one_batch_and_each_cpu_case_alone(node):
    p, rows, log = sweep(node, HB_GPUS="0")
    starts = [e for e in log if e[0] == "start"]
    assert len({e[4] for e in starts if e[1] == "cuda"}) == 1  # 12 cases, one process and context
    assert len({e[4] for e in starts if e[1] == "cpu"}) == 3
    assert len({r["case_id"] for r in rows if r["backend"] == "cuda"}) == 12


def test_hb_gpus_keeps_one_gpu_and_the_sweep_order(node):
    p, rows, log = sweep(node, HB_GPUS="1")
    assert "spread over" not in p.stdout
    assert {e[3] for e in log if e[1] == "cuda"} == {"GPU-fake-1"}
    assert {r["gpu"] for r in rows if r["backend"] == "cuda"} == {"1"}
    in_flight = 0
    for e in log:
        in_flight += 1 if e[0] == "start" else -1
        assert in_flight <= 1  # one case at a time, as on any one-GPU machine


STEPS = """
import sys
from harness.bench import steps
from harness.core import gpus
from harness.core.progress import StepTimes
from harness.studies import sweep

out, path = sys.argv[1], sys.argv[2]
node = gpus.visible()
times = StepTimes(on_step=lambda t: steps.write(out, t, node))
times.step("sweep", sweep.run_sweep, path, out=out + "/sweep", gpu="yes", log=lambda m: None)
times.step("no GPU", lambda: None)
print("\\n".join(steps.gpu_lines(times, node)))
"""


def bench_steps(node, name, **extra):
    """The bench's step record (bench/steps.py) around the two-GPU sweep: steps.json and the log's lines."""
    tmp_path, path, env = node
    out = tmp_path / name
    p = subprocess.run(
        [sys.executable, "-c", STEPS, str(out), str(path)],
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=300,
        env=dict(env, PYTHONPATH=str(ROOT), **extra),
    )
    assert p.returncode == 0, p.stdout + p.stderr
    return json.loads((out / "steps.json").read_text()), p.stdout


def test_each_step_records_the_work_each_gpu_got(node):
    """Twelve GPU cases of FAKE_SLEEP = 0.2 s each: both GPUs get work, at least the sleeps' 2.4 s
    between them; a step that sent nothing to a GPU records none; the log says it per GPU."""
    record, log = bench_steps(node, "two")
    assert [g["index"] for g in record["gpus"]] == [0, 1]
    sweep_step, idle = record["steps"]
    assert sweep_step["name"] == "sweep" and set(sweep_step["gpu_work_s"]) == {"0", "1"}
    work = list(sweep_step["gpu_work_s"].values())
    assert min(work) > 0 and sum(work) >= 12 * 0.2
    assert sweep_step["balance"] == pytest.approx(min(work) / max(work))
    assert sweep_step["gpu_work_per_s"] == pytest.approx(sum(work) / sweep_step["seconds"])
    assert "gpu_work_s" not in idle and record["total_s"] >= sweep_step["seconds"]
    assert log.startswith("harness: GPU work of sweep (") and "GPU 0 " in log and "GPU 1 " in log


def test_one_gpu_records_all_the_work_on_it_and_compare_sets_two_runs_side_by_side(node, capsys):
    one, log = bench_steps(node, "one", HB_GPUS="0")
    two, _ = bench_steps(node, "two")
    assert [g["index"] for g in one["gpus"]] == [0] and log == "\n"  # no per-GPU lines with one GPU
    assert set(one["steps"][0]["gpu_work_s"]) == {"0"} and one["steps"][0]["balance"] == 1.0
    from harness.check import compare_runs

    tmp_path = node[0]
    comp = compare_runs.compare(tmp_path / "one" / "steps.json", tmp_path / "two" / "steps.json")
    assert set(comp.table.key) == {"step sweep", "step no GPU"}  # each step's B/A: the scaling, step by step
    assert set(comp.table.noise_from_a) == {""}  # a step is timed once: no spread of its own
