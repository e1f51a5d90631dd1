"""The CUDA port's dynamic model (cuda/dynamic/model.cuh) run on the HOST, bit for bit against the
C reference (c_ref/dynamic/dynamics_impl.h). No GPU needed: cuda/dynamic/model.cuh is `__host__ __device__`,
so a host-only program (cuda/hostcheck/dyn_hostcheck.cu, no kernel launches) runs the very
templates the kernels run, with glibc's libm like the C reference. It covers every valid
feature set (96) x xpbd and ftl x fp32 and fp64 x P = 2, 3, 5, 8, 33, 70, two frames each,
in the three ways the kernels run the math (sequential on the canonical layout, the strand
kernel's point-major layout and interleaved scratch, and an emulation of the warp kernel's
lanes that runs every parallel group in reverse lane order), with the feature set compiled
in and as a run-time mask, long-range attachments (docs/model.md §3.14) on in a third of the
cases; plus the bend rest lengths and the per-strand observables.

What it cannot show: on the device, CUDA's sinf/sin (gust frames only) may differ from
glibc's, and the normal build contracts a*b + c into FMAs; tests/gpu/test_gpu_dynamic.py
compares the GPU's frames with the CPU's there.

Built by the Makefile (`make hostcheck`; the Makefile says its flags). Skipped, with the
reason, where nvcc is missing.
"""

import subprocess

import pytest
from test_cuda_port_host import build_hostcheck

from conftest import CUDA_BIN


@pytest.fixture(scope="module")
def dyn_hostcheck():
    return build_hostcheck("dyn_hostcheck")[0]


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
