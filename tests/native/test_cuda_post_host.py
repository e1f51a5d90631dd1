"""The CUDA port's follower placement (cuda/dyn_post.cuh place_follower, docs/model.md §3.13) run
on the HOST, bit for bit against the C reference (c_ref/dyn_followers_impl.h), in the
canonical and the point-major layout: cuda/hostcheck/post_hostcheck.cu. No GPU needed; on the
device the normal build contracts FMAs (tests/gpu/test_gpu_features.py covers that). Skipped,
with the reason, where nvcc or gcc is missing."""

import subprocess

import pytest
from test_cuda_port_host import C_FLAGS, _run, _tool

NVCC_FLAGS = ["-std=c++17", "-O1", "-Xcompiler", "-ffp-contract=off,-fno-fast-math"]


@pytest.fixture(scope="module")
def post_hostcheck(tmp_path_factory):
    nvcc = _tool("NVCC", "nvcc", "/usr/local/cuda/bin/nvcc")
    if nvcc is None:
        pytest.skip("nvcc not found (set NVCC or put it on PATH): the placement's host check cannot be built")
    cc = _tool("CC", "gcc", "cc")
    if cc is None:
        pytest.skip("no C compiler (gcc/cc) found: the C reference cannot be built for the host check")
    d = tmp_path_factory.mktemp("post_hostcheck")
    objs = []
    for src in ("dyn_followers.c", "dynamics_host.c", "params.c"):
        obj = d / src.replace(".c", ".o")
        _run([cc, *C_FLAGS, "-Ic_ref", "-c", f"c_ref/{src}", "-o", obj])
        objs.append(obj)
    exe = d / "post_hostcheck"
    _run([nvcc, *NVCC_FLAGS, "-Ic_ref", "-Icuda", "cuda/hostcheck/post_hostcheck.cu", *objs, "-o", exe, "-lm"])
    return exe


def test_cuda_follower_placement_matches_c_reference_bit_for_bit(post_hostcheck):
    p = subprocess.run([str(post_hostcheck)], capture_output=True, text=True, timeout=300)
    lines = p.stdout.strip().splitlines()
    summary = lines[-1] if lines else "(no output)"
    assert p.returncode == 0, f"host check failed: {summary}\n" + "\n".join(lines[:20]) + p.stderr
    assert summary == "post host check: 48 cases, 0 mismatches (all identical)", summary
