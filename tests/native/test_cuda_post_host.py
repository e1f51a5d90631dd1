"""The CUDA port's follower placement (cuda/dyn_post.cuh place_follower, docs/model.md §3.14) run
on the HOST, bit for bit against the C reference (c_ref/dynamic/dyn_followers_impl.h), in the
canonical and the point-major layout: cuda/hostcheck/post_hostcheck.cu. No GPU needed; on the
device the normal build contracts FMAs (tests/gpu/test_gpu_features.py covers that). Built by
the Makefile (`make hostcheck`). Skipped, with the reason, where nvcc is missing."""

import pytest
from test_cuda_port_host import build_hostcheck, check_hostcheck


@pytest.fixture(scope="module")
def post_hostcheck():
    return build_hostcheck("post_hostcheck")[0]


def test_cuda_follower_placement_matches_c_reference_bit_for_bit(post_hostcheck):
    summary = check_hostcheck(post_hostcheck).strip().splitlines()[-1]
    assert summary == "post host check: 48 cases, 0 mismatches (all identical)", summary
