"""The CUDA port's dynamic model (cuda/dyn_model.cuh) run on the HOST, bit for bit against the
C reference (c_ref/dynamics_impl.h). No GPU needed: dyn_model.cuh is `__host__ __device__`,
so a host-only program (cuda/hostcheck/dyn_hostcheck.cu, no kernel launches) runs the very
templates the kernels run, with glibc's libm like the C reference. It covers every valid
feature set (96) x xpbd and ftl x fp32 and fp64 x P = 2, 3, 5, 8, 33, 70, two frames each,
in the three ways the kernels run the math (sequential on the canonical layout, the strand
kernel's point-major layout and interleaved scratch, and an emulation of the warp kernel's
lanes that runs every parallel group in reverse lane order), with the feature set compiled
in and as a run-time mask, long-range attachments (docs/model.md §3.13) on in a third of the
cases; plus the bend rest lengths and the per-strand observables.

What it cannot show: on the device, CUDA's sinf/sin (gust frames only) may differ from
glibc's, and the normal build contracts a*b + c into FMAs; tests/gpu/test_gpu_dynamic.py
compares the GPU's frames with the CPU's there.

Built here, independently of the Makefile, into a temporary folder: gcc compiles the C
reference's dynamics with its flags (no FMA contraction, no fast math), nvcc compiles the
host check with the host compiler told the same (-O1: the many instantiations compile in
about a minute; optimisation level does not change IEEE results without contraction).
Skipped, with the reason, where nvcc or gcc is missing.
"""

import subprocess

import pytest
from test_cuda_port_host import C_FLAGS, _run, _tool

from conftest import CUDA_BIN

NVCC_FLAGS = ["-std=c++17", "-O1", "-Xcompiler", "-ffp-contract=off,-fno-fast-math"]


@pytest.fixture(scope="module")
def dyn_hostcheck(tmp_path_factory):
    nvcc = _tool("NVCC", "nvcc", "/usr/local/cuda/bin/nvcc")
    if nvcc is None:
        pytest.skip("nvcc not found (set NVCC or put it on PATH): the dynamic model's host check cannot be built")
    cc = _tool("CC", "gcc", "cc")
    if cc is None:
        pytest.skip("no C compiler (gcc/cc) found: the C reference cannot be built for the host check")
    d = tmp_path_factory.mktemp("dyn_hostcheck")
    objs = []
    for src in ("dynamics_f32.c", "dynamics_f64.c", "dynamics_host.c", "params.c"):
        obj = d / src.replace(".c", ".o")
        _run([cc, *C_FLAGS, "-Ic_ref", "-c", f"c_ref/{src}", "-o", obj])
        objs.append(obj)
    exe = d / "dyn_hostcheck"
    _run(
        [nvcc, *NVCC_FLAGS, "-Ic_ref", "-Icuda", "cuda/hostcheck/dyn_hostcheck.cu", *objs, "-o", exe, "-lm"],
        timeout=1200,
    )
    return exe


def test_cuda_dynamic_model_matches_c_reference_bit_for_bit(dyn_hostcheck):
    p = subprocess.run([str(dyn_hostcheck)], capture_output=True, text=True, timeout=600)
    lines = p.stdout.strip().splitlines()
    summary = lines[-1] if lines else "(no output)"
    mismatches = "\n".join(line for line in lines if line.startswith("MISMATCH"))[:20000]
    assert p.returncode == 0, f"host check failed: {summary}\n{mismatches}{p.stderr}"
    assert summary.startswith("dyn host check: ") and " 0 mismatches" in summary, summary
    # every case ran: 96 feature sets x 2 solvers x 2 precisions x 6 sizes, each with the bend
    # rest lengths, the observables and 3 modes x (run-time mask, + compiled where specialised)
    cases = int(summary.split()[3])
    assert cases >= 96 * 2 * 2 * 6 * (2 + 3), summary


@pytest.mark.parametrize("variant", ("paper", "soa", "fused"))
def test_paper_variants_refuse_simulate(variant):
    """The driver refuses before any device is touched, so this runs without a GPU."""
    if not CUDA_BIN.exists():
        pytest.skip(f"{CUDA_BIN} is not built (nvcc missing or `make` not run)")
    p = subprocess.run(
        [str(CUDA_BIN), "--strands", "10", "--stages", "init,simulate", "--variant", variant, "--quiet"],
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert p.returncode == 2, (p.returncode, p.stderr)
    assert f"variant {variant} does not run 'simulate'" in p.stderr, p.stderr
