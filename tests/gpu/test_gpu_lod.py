"""GPU tests of simulated-point LOD (docs/model.md §3.14, --render-points): the rendering kernel
(cuda/dynamic/lod.cu) of every simulating variant against the C reference. Marked `gpu`;
conftest.py skips them where there is no usable GPU.

Both backends simulate from the same CPU paper state (init, collide) with --render-points. The
strict build (no FMA contraction; no gusts here) writes the CPU's file bit for bit: positions,
velocities and rest shape, rendered rows and simulated rows alike. The default build's rendered
rows are recomputed by harness/check/lod_dynamic.py from its own simulated rows and must lie within
DYN_LOD_KERNEL_K·ε·E of it (E = R + c_m + 2L), the kernel's contraction of the same operations.
"""

import json

import numpy as np
import pytest

from conftest import CPU_BIN, CUDA_BIN, CUDA_STRICT_BIN
from harness import HarnessError
from harness.check import lod_dynamic as lod
from harness.core import tolerances, variants
from harness.io.trajectory import open_trajectory
from support.statecheck import run

pytestmark = pytest.mark.gpu

P, PR = 16, 46
try:
    _DECLARED = variants.declared("cuda")
    VARIANTS = tuple(v for v in _DECLARED.variants if _DECLARED.runs(v, points=P))
except HarnessError:
    VARIANTS = ()
SCENE = ["--strands", "200", "--points", str(P), "--hair-length", "30"]
PHYSICS = ["--substeps", "4", "--iterations", "2", "--bend-compliance", "1e-6", "--head-motion", "nod",
           "--motion-frequency", "4", "--frames", "3", "--velocities", "all", "--render-points", str(PR)]  # fmt: skip


@pytest.fixture(scope="module")
def cpu_files(tmp_path_factory):
    work = tmp_path_factory.mktemp("gpu_lod")
    cache = {}

    def get(precision):
        if precision not in cache:
            paper, out = work / f"paper_{precision}.h5", work / f"cpu_{precision}.h5"
            run(CPU_BIN, "--stages", "init,collide", *SCENE, "--precision", precision, "--output", paper, "--quiet")
            run(CPU_BIN, "--input", paper, "--stages", "simulate", *PHYSICS, "--output", out, "--quiet")
            cache[precision] = (work, paper, out)
        return cache[precision]

    return get


def bits(a):
    return np.ascontiguousarray(a).view(np.uint8)


@pytest.mark.parametrize("precision", ["fp32", "fp64"])
@pytest.mark.parametrize("variant", VARIANTS)
@pytest.mark.parametrize("build", ["strict", "normal"])
def test_gpu_rendering_matches_the_reference(cpu_files, build, variant, precision):
    work, paper, cpu = cpu_files(precision)
    out = work / f"gpu_{build}_{variant}_{precision}.h5"
    binary = CUDA_STRICT_BIN if build == "strict" else CUDA_BIN
    rec = json.loads(
        run(
            binary,
            "--input",
            paper,
            "--stages",
            "simulate",
            *PHYSICS,
            "--variant",
            variant,
            "--output",
            out,
            "--force",
            "--json",
            "--quiet",
        ).stdout  # fmt: skip
    )
    sim = rec["stages"][-1]
    assert sim["render_points"] == PR and np.isfinite(sim["render_ms"]) and sim["render_ms"] >= 0
    with open_trajectory(cpu) as c, open_trajectory(out) as g:
        assert (g.points, g.simulated_points) == (PR, P) and np.array_equal(g.simulated_rows, c.simulated_rows)
        assert np.array_equal(bits(g.rest), bits(c.rest)), "the rest shape is rendered on the host by both"
        for f in g.simulated:
            v = g.velocity_at_step(int(g.step[f]))
            x = g.frame(f).reshape(g.n_strands, PR, 3)
            if build == "strict":
                assert np.array_equal(bits(x), bits(c.frame(f).reshape(x.shape))), f"frame {f}: positions"
                assert np.array_equal(bits(v), bits(c.velocity_at_step(int(c.step[f])))), f"frame {f}: velocities"
                continue
            want_x, want_v = lod.recompute(g, f, v)
            extent = g.collide_radius + 2.0 * float(g.params["hair_length"])
            bound = tolerances.DYN_LOD_KERNEL_K * float(np.finfo(x.dtype).eps) * extent
            assert float(np.abs(x.astype(np.float64) - want_x).max()) <= bound, f"frame {f}: rendered rows"
            # velocities: the same weights on values of their own scale
            vscale = float(np.abs(v).max()) or 1.0
            vbound = tolerances.DYN_LOD_KERNEL_K * float(np.finfo(x.dtype).eps) * vscale
            assert float(np.abs(v.astype(np.float64) - want_v).max()) <= vbound, f"frame {f}: rendered velocities"
