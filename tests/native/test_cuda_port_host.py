"""The CUDA port's model math (cuda/paper/model.cuh) run on the HOST against the C reference
(c_ref/paper/model.c). No GPU needed: cuda/paper/model.cuh is `__host__ __device__`, so a host-only program
(cuda/hostcheck/paper_hostcheck.cu, no kernel launches) runs the very templates the kernels
run, on the CPU, with glibc's libm like model.c. Both layouts, fp32 and fp64, P = 2, 3, 16,
64, four scenes, every stage, the fused wind+collide with and without the kept
intermediate, prefetch depths 0-4. Built twice:

- the reference arithmetic (-DHB_REFERENCE_ARITHMETIC=1, the strict build's): bit for bit;
  any difference is a porting, layout or indexing bug;
- the free arithmetic (the normal build's): every frame within the paper model's
  tolerances of harness/core/tolerances.py (the fp32 and fp64 same-precision pairs, and
  MOVED_COUNT_FRACTION for collide's counts), and the port's layouts and depths
  bit-identical to each other.

Built by the Makefile (`make hostcheck`: the reference's objects, and nvcc with the host
compiler told the reference's rules, no FMA contraction, no fast math); the fixture runs make,
which does nothing when they are current. Skipped, with the reason, where nvcc is missing.
"""

import os
import shutil
import subprocess
from pathlib import Path

import pytest

from harness.core import tolerances

ROOT = Path(__file__).resolve().parents[2]


def _tool(env, default, *fallbacks):
    for name in (os.environ.get(env), default, *fallbacks):
        if name and shutil.which(name):
            return shutil.which(name)
    return None


def build_hostcheck(*names):
    """`make` the host checks named (build/hostcheck/<name>) and return their paths; skips
    where nvcc is missing."""
    nvcc = _tool("NVCC", "nvcc", "/usr/local/cuda/bin/nvcc")
    if nvcc is None:
        pytest.skip("nvcc not found (set NVCC or put it on PATH): the CUDA port's host checks cannot be built")
    targets = [f"build/hostcheck/{n}" for n in names]
    p = subprocess.run(
        ["make", "--no-print-directory", f"NVCC={nvcc}", *targets],
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=1800,
    )
    if p.returncode != 0:
        raise AssertionError(f"make {' '.join(targets)} exited {p.returncode}:\n{p.stdout[-4000:]}\n{p.stderr[-4000:]}")
    return [ROOT / t for t in targets]


@pytest.fixture(scope="module")
def hostcheck():
    ref, free = build_hostcheck("paper_hostcheck_reference", "paper_hostcheck_free")
    return {"reference": ref, "free": free}


def check_hostcheck(exe, *args):
    p = subprocess.run([str(exe), *map(str, args)], capture_output=True, text=True, timeout=600)
    summary = p.stdout.strip().splitlines()[-1] if p.stdout.strip() else "(no output)"
    assert p.returncode == 0, (
        f"host check failed: {summary}\n"
        + "\n".join(line for line in p.stdout.splitlines() if line.startswith("MISMATCH"))[:20000]
        + p.stderr
    )
    assert " 0 mismatches" in summary, summary
    assert "MISMATCH" not in p.stdout
    return p.stdout


def assert_hostcheck_all_identical(name, summary):
    """Build and run build/hostcheck/NAME; its last line must be `summary` (every case identical)."""
    last = check_hostcheck(build_hostcheck(name)[0]).strip().splitlines()[-1]
    assert last == summary, last


def test_cuda_model_matches_c_reference_bit_for_bit(hostcheck):
    """The reference arithmetic (the strict build's): every case bit-identical."""
    out = check_hostcheck(hostcheck["reference"])
    assert "host check (reference arithmetic)" in out and out.count(" identical ") == 32, out


def test_cuda_free_arithmetic_within_paper_tolerance(hostcheck):
    """The free arithmetic (the normal build's) against the reference, under the paper
    model's tolerances; its worst error is printed (docs/cuda.md quotes it)."""
    f32 = tolerances.pair_tolerance("fp32", "fp32")
    f64 = tolerances.pair_tolerance("fp64", "fp64")
    args = (f32.point_k, f32.max_over_fraction, f64.point_k, f64.max_over_fraction, tolerances.MOVED_COUNT_FRACTION)
    out = check_hostcheck(hostcheck["free"], 2000, *args)
    assert "host check (free arithmetic)" in out and out.count(" within tolerance ") == 32, out


def test_free_arithmetic_check_fails_outside_its_tolerance(hostcheck):
    """The tolerance check can fail: with point_k = 0.01 u, below the errors it measures, it does."""
    p = subprocess.run(
        [str(hostcheck["free"]), "200", "0.01", "0", "0.01", "0", "0"], capture_output=True, text=True, timeout=600
    )
    assert p.returncode == 1 and "MISMATCH" in p.stdout, p.stdout[-2000:]
