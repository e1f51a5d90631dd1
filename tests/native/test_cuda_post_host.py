"""The CUDA port's follower placement (cuda/dyn_post.cuh place_follower, docs/model.md §3.14) run
on the HOST, bit for bit against the C reference (c_ref/dynamic/dyn_followers_impl.h), in the
canonical and the point-major layout: cuda/hostcheck/post_hostcheck.cu. No GPU needed; on the
device the normal build contracts FMAs (tests/gpu/test_gpu_features.py covers that). Built by
the Makefile (`make hostcheck`). Skipped, with the reason, where nvcc is missing."""

import subprocess

import pytest
from test_cuda_port_host import build_hostcheck


@pytest.fixture(scope="module")
def post_hostcheck():
    return build_hostcheck("post_hostcheck")[0]


def test_cuda_follower_placement_matches_c_reference_bit_for_bit(post_hostcheck):
    p = subprocess.run([str(post_hostcheck)], capture_output=True, text=True, timeout=300)
    lines = p.stdout.strip().splitlines()
    summary = lines[-1] if lines else "(no output)"
    assert p.returncode == 0, f"host check failed: {summary}\n" + "\n".join(lines[:20]) + p.stderr
    assert summary == "post host check: 48 cases, 0 mismatches (all identical)", summary
