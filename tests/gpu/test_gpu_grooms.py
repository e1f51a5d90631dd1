"""GPU and grooms (docs/model.md §3.15). Every test is marked `gpu`; conftest.py skips them, with
the reason, where there is no usable GPU.

A CUDA variant that `--list-variants` marks `"per_segment": true` must equal the CPU on a curly
groom under the existing rules (one frame from the CPU's frame, judged by
harness.check.diff_dynamic.compare, as tests/gpu/test_gpu_dynamic.py judges the procedural
scenes); a variant that does not must refuse a groom, and a groom's file given to --input,
with one line and exit 2, writing nothing.
"""

import pytest

from conftest import CPU_BIN, CUDA_BIN
from harness.check import diff_dynamic
from harness.core import variants
from harness.io.trajectory import open_trajectory
from support.statecheck import run

pytestmark = pytest.mark.gpu

CURLY = ["--groom", "curly", "--strands", 200, "--points", 32]
PHYSICS = [
    "--substeps", 4, "--iterations", 2, "--bend-compliance", 1e-6, "--shape-compliance", 1e-4, "--shape-range", 0.5,
    "--wind-speed", 150, "--drag", 0.5, "--gust-amplitude", 0.5, "--head-motion", "nod",
]  # fmt: skip


def _variants():
    d = variants.declared("cuda")
    return [v for v in d.running("simulate", points=32)], d


@pytest.fixture(scope="module")
def cpu_curly(tmp_path_factory):
    """(solver, precision) -> the CPU's curly run: init and 3 simulated frames, velocities all."""
    d = tmp_path_factory.mktemp("gpu_grooms")
    made = {}

    def get(solver, precision):
        if (solver, precision) not in made:
            out = d / f"cpu_{solver}_{precision}.h5"
            run(CPU_BIN, *CURLY, "--stages", "init,simulate", "--frames", 3, "--solver", solver, "--precision",
                precision, *PHYSICS, "--velocities", "all", "--output", out, "--quiet")  # fmt: skip
            made[(solver, precision)] = out
        return made[(solver, precision)]

    return get


@pytest.mark.parametrize("precision", ["fp32", "fp64"])
@pytest.mark.parametrize("solver", ["xpbd", "ftl"])
def test_curly_gpu_equals_cpu_or_is_refused(cpu_curly, tmp_path, solver, precision):
    names, declared = _variants()
    src = cpu_curly(solver, precision)
    with open_trajectory(src) as t:
        k = t.n_frames - 2
        step = int(t.step[k + 1])
    for v in names:
        if solver not in declared.solvers_of(v):
            continue
        out = tmp_path / f"{v}.h5"
        args = ["--input", src, "--input-frame", k, "--stages", "simulate", "--frames", 1, "--variant", v]
        p = run(CUDA_BIN, *args, "--solver", solver, *PHYSICS, "--velocities", "all", "--output", out, "--quiet",
                check=False)  # fmt: skip
        if v in declared.per_segment:
            assert p.returncode == 0, p.stderr
            r = diff_dynamic.compare(src, out, frames=[step], check_paper=False, spread=True)
            assert r.frames[0].velocity_compared and r.equivalent, f"{v}: " + "; ".join(r.failures()[:5])
        else:
            assert p.returncode == 2 and "per-segment" in p.stderr, (v, p.returncode, p.stderr)
            assert "\n" not in p.stderr.strip() and not out.exists()
            g = run(CUDA_BIN, *CURLY, "--stages", "init,simulate", "--variant", v, "--output", out, check=False)
            assert g.returncode == 2 and "per-segment" in g.stderr and not out.exists(), (v, g.stderr)
