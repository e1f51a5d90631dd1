"""The CUDA port's rendering of simulated-point LOD (cuda/dynamic/lod.cuh lod_render_point, docs/model.md
§3.14) run on the HOST, bit for bit against the C reference (c_ref/dynamic/dyn_lod_impl.h), positions
and velocities, in the canonical and the point-major layout: cuda/hostcheck/lod_hostcheck.cu. No
GPU needed; on the device the normal build contracts FMAs (tests/gpu/test_gpu_lod.py covers that).
Built by the Makefile (`make hostcheck`). Skipped, with the reason, where nvcc is missing."""

from test_cuda_port_host import assert_hostcheck_all_identical


def test_cuda_lod_rendering_matches_c_reference_bit_for_bit():
    assert_hostcheck_all_identical("lod_hostcheck", "lod host check: 48 cases, 0 mismatches (all identical)")
