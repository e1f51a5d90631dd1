"""GPU and grooms (docs/model.md §3.15). Every test is marked `gpu`; conftest.py skips them, with
the reason, where there is no usable GPU.

A CUDA variant that `--list-variants` marks `"per_segment": true` must equal the CPU on a curly
groom under the existing rules (one frame from the CPU's frame, judged by
harness.check.diff_dynamic.compare, as tests/gpu/test_gpu_dynamic.py judges the procedural
scenes); a variant that does not must refuse a groom, and a groom's file given to --input,
with one line and exit 2, writing nothing.
"""

import json

import numpy as np
import pytest

from conftest import CPU_BIN, CUDA_BIN
from harness.check import diff_dynamic
from harness.core import variants
from harness.io import grooms
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


def test_given_head_on_the_gpu_is_the_cpu_s(tmp_path):
    """--head-center through the CUDA binary (the runtime both share): on a groom whose roots are not
    near one sphere, the same init bits, head radius and record's head as the CPU's."""
    axes = np.vstack([np.eye(3), -np.eye(3)])
    strands = [np.outer(10.0 + np.arange(5.0), n) for n in axes]
    strands[0] = 2.0 * strands[0]  # a lock off the scalp: refused by the fit
    hair = grooms.write_hair(tmp_path / "lock.hair", strands)
    head = ["--head-center", "0.5,-1.0,0.25", "--head-radius", "9.5"]
    recs = {}
    for name, binary in (("cpu", CPU_BIN), ("cuda", CUDA_BIN)):
        out = tmp_path / f"{name}.h5"
        p = run(binary, "--groom", hair, *head, "--points", 5, "--stages", "init", "--precision", "fp64", "--json",
                "--quiet", "--output", out)  # fmt: skip
        recs[name] = json.loads(p.stdout)
    assert recs["cuda"]["groom"] == recs["cpu"]["groom"] and recs["cuda"]["groom"]["head"] == "given"
    assert recs["cuda"]["head_radius"] == recs["cpu"]["head_radius"] == 9.5
    with open_trajectory(tmp_path / "cpu.h5") as a, open_trajectory(tmp_path / "cuda.h5") as b:
        assert np.array_equal(a.frame(0), b.frame(0))
        assert list(b.params["groom_head_center"]) == [0.5, -1.0, 0.25]
