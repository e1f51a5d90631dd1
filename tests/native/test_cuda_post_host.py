"""The CUDA port's follower placement (cuda/dynamic/post.cuh place_follower, docs/model.md §3.14) run
on the HOST, bit for bit against the C reference (c_ref/dynamic/dyn_followers_impl.h), in the
canonical and the point-major layout, with ℓ or a groom's ℓ_k: cuda/hostcheck/post_hostcheck.cu. No GPU needed; on the
device the normal build contracts FMAs (tests/gpu/test_gpu_features.py covers that). Built by
the Makefile (`make hostcheck`). Skipped, with the reason, where nvcc is missing."""

from test_cuda_port_host import assert_hostcheck_all_identical


def test_cuda_follower_placement_matches_c_reference_bit_for_bit():
    assert_hostcheck_all_identical("post_hostcheck", "post host check: 96 cases, 0 mismatches (all identical)")
