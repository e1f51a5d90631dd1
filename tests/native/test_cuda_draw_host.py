"""--draw's two paths run on the HOST with known answers (cuda/hostcheck/draw_hostcheck.cu): the
compute rasteriser's functions (cuda/draw/view.cuh) with a host atomicMin, and the OpenGL path
(cuda/draw/egl_gl.cuh) through EGL on whatever driver is here (Mesa's llvmpipe in CI): a strand at
known coordinates covers its row and columns, a strand behind the head is hidden and one in
front is not. Skipped, with the reason, where nvcc is missing; the GL half where EGL gives no
context."""

import pytest
from test_cuda_port_host import build_hostcheck, check_hostcheck


def test_draw_paths_cover_the_known_pixels():
    out = check_hostcheck(build_hostcheck("draw_hostcheck")[0]).strip().splitlines()[-1]
    assert out.startswith("draw host check: compute 5 checks, 0 failed; "), out
    if "gl skipped" in out:
        pytest.skip(f"the OpenGL half: {out.split('gl skipped: ', 1)[1].rsplit(';', 1)[0]}")
    assert out.endswith("gl 5 checks, 0 failed; 0 mismatches"), out
