"""GPU tests of docs/model.md §3.14 (guides and followers, long-range attachments) in the CUDA
port: guides through a strand map in the strand, warp and warpreg kernels, the followers'
placement kernel (cuda/dynamic/post.cu), LRA in the generic kernels and warpreg, the sag-free
targets (made on the host, c_ref/dynamic/dyn_sagfree.c, read by every variant). Marked `gpu`;
conftest.py skips them where there is no usable GPU.

As tests/gpu/test_gpu_dynamic.py: the CPU runs K frames with --velocities all, each GPU
build resumes from the CPU's frame K−1 for one frame, and harness.check.diff_dynamic.compare
judges it (the strict build bit for bit: no gusts here). The strict build's followers are
also recomputed from its own guides by harness/check/followers_dynamic.py, bit for bit. Each variant
runs the scenes whose features it declares; `lanes` refuses guides and LRA (docs/cuda.md).
"""

import numpy as np
import pytest

from conftest import CPU_BIN, CUDA_BIN, CUDA_STRICT_BIN
from harness import HarnessError
from harness.check import diff_dynamic
from harness.check import followers_dynamic as followers
from harness.core import variants
from harness.io.trajectory import open_trajectory
from support.statecheck import run

pytestmark = pytest.mark.gpu

try:
    _DECLARED = variants.declared("cuda")
    VARIANTS = tuple(v for v in _DECLARED.variants if _DECLARED.runs(v, points=24))
except HarnessError:
    _DECLARED, VARIANTS = None, ()
BUILDS = {"normal": CUDA_BIN, "strict": CUDA_STRICT_BIN}
BASE = ["--strands", "300", "--points", "24", "--substeps", "4", "--iterations", "2"]
SCENES = {
    "blend3": ["--bend-compliance", "1e-6", "--head-motion", "nod", "--guides", "0.1"],
    "one": ["--shape-compliance", "1e-5", "--head-motion", "shake", "--guides", "0.25", "--follow", "one"],
    "lra": ["--stretch-compliance", "1e-4", "--head-motion", "nod", "--motion-frequency", "8", "--lra", "1.02"],
    "sagfree": ["--shape-compliance", "1e-4", "--shape-range", "1", "--sag-free", "--head-motion", "tilt"],
}
FRAMES = 3
# (variant, scene) where the variant declares the scene's features (--list-variants); `lanes`
# declares neither guides nor LRA, and its refusal is tested below
RUNS = [(v, s) for v in VARIANTS for s in SCENES if _DECLARED.runs_features(v, variants.features_of(SCENES[s]))]


@pytest.fixture(scope="module")
def cpu_files(tmp_path_factory):
    work = tmp_path_factory.mktemp("gpu_features")
    cache = {}

    def get(scene, solver, precision):
        key = (scene, solver, precision)
        if key not in cache:
            out = work / f"cpu_{scene}_{solver}_{precision}.h5"
            args = [*BASE, *SCENES[scene], "--solver", solver, "--precision", precision, "--frames", FRAMES]
            run(CPU_BIN, "--stages", "init,collide,simulate", *args, "--velocities", "all", "--output", out, "--quiet")
            cache[key] = (work, out)
        return cache[key]

    return get


@pytest.mark.parametrize("precision", ["fp32", "fp64"])
@pytest.mark.parametrize("solver", ["xpbd", "ftl"])
@pytest.mark.parametrize("variant,scene", RUNS)
@pytest.mark.parametrize("build", tuple(BUILDS))
def test_gpu_frame_matches_cpu(cpu_files, build, variant, scene, solver, precision):
    work, cpu = cpu_files(scene, solver, precision)
    with open_trajectory(cpu) as t:
        k = t.n_frames - 2
        step = int(t.step[-1])
    out = work / f"gpu_{build}_{variant}_{scene}_{solver}_{precision}.h5"
    run(BUILDS[build], "--input", cpu, "--input-frame", k, "--stages", "simulate", "--frames", 1,
        "--variant", variant, "--output", out, "--force", "--quiet")  # fmt: skip
    exact = build == "strict"
    r = diff_dynamic.compare(cpu, out, frames=[step], exact=exact, check_paper=False)
    assert r.equivalent, f"{build} {variant} {scene}: " + "; ".join(r.failures()[:5])
    if exact and "--guides" in SCENES[scene]:
        with open_trajectory(out) as g:
            f = g.n_frames - 1
            v = g.velocity_at_step(int(g.step[f]))
            x_want, v_want = followers.place_followers(g, f, v)
            x = g.frame(f).reshape(x_want.shape)
            assert np.array_equal(x.view(np.uint8), x_want.view(np.uint8))
            assert np.array_equal(v.reshape(x.shape).view(np.uint8), v_want.view(np.uint8))


@pytest.mark.parametrize("flag", [["--guides", "0.5"], ["--lra"]])
def test_lanes_refuses_the_features(tmp_path, flag):
    out = tmp_path / "o.h5"
    p = run(CUDA_BIN, "--stages", "init,simulate", *BASE, *flag, "--variant", "lanes", "--output", out,
            "--quiet", check=False)  # fmt: skip
    assert p.returncode == 2 and "--variant lanes does not run" in p.stderr
    assert not out.exists()
