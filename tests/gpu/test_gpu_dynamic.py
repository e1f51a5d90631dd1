"""GPU tests of the dynamic model's CUDA port (the simulate stage; cuda/dynamic/kernels.cu,
docs/cuda.md "The dynamic model"). Every test is marked `gpu`; conftest.py skips them, with
the reason, where there is no usable GPU.

One frame on the GPU from the CPU's state: the CPU runs `init,simulate` for K frames with
--velocities all; each GPU build resumes from the CPU's frame k (`--input cpu.h5
--input-frame k --stages simulate --frames 1`) and its frame is compared with the CPU's
frame k+1, positions, velocities and observables. For each variant that runs simulate (from
the binary's --list-variants, within its most-points limit) x solver (xpbd, ftl) x precision
x block size x build, on scenes with the feature set compiled in (cuda/dynamic/kernels.cuh
specialised_mask) and one that runs the generic kernel.

Rules: every frame is judged by harness.check.diff_dynamic.compare, the function behind `harness
stepdiff` and the bench's validation: positions and velocities by the DYN_STEP_K rule of
harness/core/tolerances.py or DYN_SPREAD_K × the scene's spread, whichever is larger;
observables within what the states' difference allows. The strict
build equals the CPU bit for bit without gusts (GPU_DYN_STRICT_EXACT_WITHOUT_GUSTS).
Every build: bit-identical across block sizes and repeats.
Strict build: all simulate variants bit-identical. The measured worst errors go to
build/gpu_dyn_test_errors.json (for recalibrating the tolerances).
"""

import subprocess

import pytest

from conftest import BUILD, CPU_BIN, CUDA_BIN, CUDA_FASTMATH_BIN, CUDA_STRICT_BIN
from harness import HarnessError
from harness.check import diff_dynamic
from harness.core import variants
from harness.core.tolerances import GPU_DYN_STRICT_EXACT_WITHOUT_GUSTS
from harness.io.trajectory import open_trajectory
from support.measured import write_worst
from support.statecheck import run

pytestmark = pytest.mark.gpu


def _simulate_variants():
    """The CUDA variants that run simulate, and what the binary declares (its --list-variants)."""
    try:
        d = variants.declared("cuda")
    except HarnessError:
        return (), None
    return tuple(v for v in d.variants if d.runs(v)), d


VARIANTS, DECLARED = _simulate_variants()
SOLVERS = ("xpbd", "ftl")
PRECISIONS = ("fp32", "fp64")
BLOCKS = (32, 96, 256, 1024)
BUILDS = {"normal": CUDA_BIN, "strict": CUDA_STRICT_BIN, "fastmath": CUDA_FASTMATH_BIN}

# N not a multiple of any block; P = 32 (a lane a point) and P = 45 (lanes take two points)
N, SEED, L = 1500, 20260101, 30.0
SUBSTEPS, ITERATIONS, FRAME_IN = 8, 4, 2  # the CPU writes frames 1..FRAME_IN+1; the GPU resumes at FRAME_IN
SCENES = {
    # the default scene: gravity, stretch, the collider (a specialised kernel)
    "collide": ("--points", 32),
    # every feature (specialised): bend, shape, wind with gusts, a nodding head, drag
    "all": (
        "--points",
        32,
        "--bend-compliance",
        "1e-6",
        "--shape-compliance",
        "1e-5",
        "--shape-range",
        "0.5",
        "--wind-speed",
        "400",
        "--drag",
        "2",
        "--damping",
        "0.5",
        "--gust-amplitude",
        "0.5",
        "--gust-frequency",
        "2",
        "--gust-wavelength",
        "25",
        "--head-motion",
        "nod",
        "--motion-amplitude",
        "0.3",
        "--motion-frequency",
        "1.5",
    ),
    # shape with a shaking head and no collider: the generic kernel (features as run-time flags), P > 32
    "generic": ("--points", 45, "--shape-compliance", "1e-5", "--head-motion", "shake", "--no-collider"),
}
GUSTS = {"collide": False, "all": True, "generic": False}


def scene_points(scene):
    a = SCENES[scene]
    return int(a[a.index("--points") + 1])


def runs(variant, scene):
    return DECLARED is not None and DECLARED.runs(variant, points=scene_points(scene))


# (variant, scene) pairs a variant can run: a variant with a most-points limit skips the
# scene over it (its refusal is tested below)
PAIRS = tuple((v, sc) for v in VARIANTS for sc in SCENES if runs(v, sc))

ERRORS = {}


@pytest.fixture(scope="session", autouse=True)
def _write_measurements():
    yield
    write_worst(BUILD / "gpu_dyn_test_errors.json", ERRORS)


def record(key, value):
    ERRORS[key] = max(float(value), ERRORS.get(key, 0.0))


def dyn_args(scene, solver):
    return ["--substeps", SUBSTEPS, "--iterations", ITERATIONS, "--solver", solver, *SCENES[scene]]


def simulate(binary, out, scene, solver, *flags):
    """`binary FLAGS` with the scene's and solver's dynamic flags, quiet, into out (replaced)."""
    return run(binary, *flags, "--quiet", *dyn_args(scene, solver), "--output", out, "--force")


def last_step(path):
    with open_trajectory(path) as t:
        return int(t.step[-1])


_CACHE = {}


@pytest.fixture(scope="session")
def work(tmp_path_factory):
    return tmp_path_factory.mktemp("gpu_dyn")


@pytest.fixture(scope="session")
def cpu_run(work):
    """(scene, solver, precision) -> the CPU's file (frames 0..FRAME_IN+1, velocities all)."""

    def get(scene, solver, precision):
        key = ("cpu", scene, solver, precision)
        if key not in _CACHE:
            out = work / f"cpu_{scene}_{solver}_{precision}.h5"
            scene_flags = ("--strands", N, "--seed", SEED, "--hair-length", L, "--precision", precision)
            flags = ("--stages", "init,simulate", "--frames", FRAME_IN + 1, "--velocities", "all")
            simulate(CPU_BIN, out, scene, solver, *scene_flags, *flags)
            _CACHE[key] = out
        return _CACHE[key]

    return get


@pytest.fixture(scope="session")
def gpu_frame(work, cpu_run):
    """(build, variant, scene, solver, precision, block, tag) -> the GPU's frame from the CPU's frame FRAME_IN."""

    def get(build, variant, scene, solver, precision, block, tag="", extra=()):
        key = ("gpu", build, variant, scene, solver, precision, block, tag)
        if key not in _CACHE:
            src = cpu_run(scene, solver, precision)
            out = work / f"gpu_{build}_{variant}_{scene}_{solver}_{precision}_{block}{tag}.h5"
            flags = ("--input", src, "--input-frame", FRAME_IN, "--stages", "simulate", "--frames", 1)
            simulate(BUILDS[build], out, scene, solver, *flags, "--variant", variant, "--block-size", block, *extra)
            _CACHE[key] = out
        return _CACHE[key]

    return get


def judge(a, b, what, exact=False):
    """harness.check.diff_dynamic.compare of the last frame of GPU file b against the same step of a:
    the rule of `harness stepdiff` and of the bench (positions, velocities, observables)."""
    step = last_step(b)
    r = diff_dynamic.compare(a, b, frames=[step], exact=exact, check_paper=False, spread=not exact)
    f = r.frames[0]
    if not exact:
        record(f"positions {what}", f.max_rel_L)
        if getattr(f, "velocity_compared", False):
            record(f"velocities {what}", f.velocity_max_abs / r.hair_length)
    assert getattr(f, "velocity_compared", False), f"{what}: velocities of step {step} not stored in both files"
    spread = f"spread {getattr(f, 'spread', float('nan')):.3g}, limit {getattr(f, 'limit', float('nan')):.3g}: "
    assert r.equivalent, f"{what}: {spread}" + "; ".join(r.failures()[:5])


def same_bits(a, b):
    """Two GPU files of the same frame: bit-identical positions, velocities and observables."""
    return diff_dynamic.compare(a, b, frames=[last_step(a)], exact=True, check_paper=False).equivalent


# ---- against the CPU ------------------------------------------------------------------------
@pytest.mark.parametrize("precision", PRECISIONS)
@pytest.mark.parametrize("solver", SOLVERS)
@pytest.mark.parametrize(("variant", "scene"), PAIRS)
@pytest.mark.parametrize("build", tuple(BUILDS))
def test_frame_matches_cpu(cpu_run, gpu_frame, build, variant, scene, solver, precision):
    cpu = cpu_run(scene, solver, precision)
    gpu = gpu_frame(build, variant, scene, solver, precision, 256)
    exact = build == "strict" and GPU_DYN_STRICT_EXACT_WITHOUT_GUSTS and not GUSTS[scene]
    judge(cpu, gpu, f"{build} {precision}" if not exact else f"{build} {variant} {scene} {solver} {precision}", exact)


# ---- determinism ------------------------------------------------------------------------------
@pytest.mark.parametrize("precision", PRECISIONS)
@pytest.mark.parametrize("solver", SOLVERS)
@pytest.mark.parametrize("variant", VARIANTS)
@pytest.mark.parametrize("build", tuple(BUILDS))
def test_bits_do_not_depend_on_block_size_or_repeats(gpu_frame, build, variant, solver, precision):
    ref = gpu_frame(build, variant, "all", solver, precision, BLOCKS[0])
    # the warp variant at 1024, P = 32, fp64: 32 strands x 3.75 KB = 120 KB of shared memory
    for b in (b for b in BLOCKS[1:] if DECLARED.runs(variant, block=b)):
        other = gpu_frame(build, variant, "all", solver, precision, b)
        assert same_bits(ref, other), (
            f"{build} {variant} {solver} {precision}: block {b} differs from block {BLOCKS[0]}"
        )
    again = gpu_frame(build, variant, "all", solver, precision, BLOCKS[0], tag="-again")
    assert same_bits(ref, again), f"{build} {variant} {solver} {precision}: a second run differs"
    # --repeat 3: the frame is run three times from the saved state (positions and velocities)
    rep = gpu_frame(build, variant, "all", solver, precision, BLOCKS[0], tag="-repeat", extra=("--repeat", 3))
    assert same_bits(ref, rep), f"{build} {variant} {solver} {precision}: --repeat 3 differs (save/restore)"


@pytest.mark.parametrize("precision", PRECISIONS)
@pytest.mark.parametrize("solver", SOLVERS)
@pytest.mark.parametrize("scene", tuple(SCENES))
def test_strict_variants_identical(gpu_frame, scene, solver, precision):
    """The strict build: every simulate variant gives the same bits (one order of the math)."""
    names = [v for v in VARIANTS if runs(v, scene)]
    assert len(names) >= 2, f"{scene}: fewer than two variants run it: {names}"
    a = gpu_frame("strict", names[0], scene, solver, precision, 256)
    for other in names[1:]:
        b = gpu_frame("strict", other, scene, solver, precision, 256)
        assert same_bits(a, b), f"strict {scene} {solver} {precision}: {names[0]} and {other} differ"


def one_frame_on_cuda(out, *flags):
    """build/hairsim-cuda FLAGS through init and one simulated frame into out; the
    CompletedProcess, whatever its exit status (the refusal tests)."""
    return run(CUDA_BIN, *flags, "--stages", "init,simulate", "--frames", 1, "--quiet", "--output", out, check=False)


def test_variant_over_its_point_limit_is_refused(tmp_path):
    limited = [(v, DECLARED.max_points[v]) for v in VARIANTS if DECLARED.max_points.get(v)]
    assert limited, "no simulate variant declares a most-points limit"
    for v, most in limited:
        out = tmp_path / f"{v}.h5"
        p = one_frame_on_cuda(out, "--strands", 10, "--points", most + 1, "--variant", v)
        assert p.returncode == 2, (v, p.returncode, p.stderr)
        assert "--points" in p.stderr and v in p.stderr and "\n" not in p.stderr.strip(), p.stderr
        assert not out.exists()


# ---- refusals ---------------------------------------------------------------------------------
def test_warp_block_too_large_for_shared_memory_is_refused(tmp_path):
    # 512 points x 32 strands a block x 15 reals x 8 bytes = 1.9 MB: more than any GPU gives a block
    flags = ("--strands", 100, "--points", 512, "--hair-length", 60, "--precision", "fp64")
    p = one_frame_on_cuda(tmp_path / "o.h5", *flags, "--variant", "warp", "--block-size", 1024)
    assert p.returncode == 2, p.stderr
    assert "shared memory" in p.stderr and "--block-size" in p.stderr, p.stderr
    assert not (tmp_path / "o.h5").exists()


def test_state_too_large_for_simulate_is_refused(tmp_path):
    # a state of a third of the free GPU memory: the state and its staging copy fit, but not
    # with the velocities, the rest shape and the strand variant's scratch on top
    smi = subprocess.run(
        ["nvidia-smi", "--query-gpu=memory.free", "--format=csv,noheader,nounits", "-i", "0"],
        capture_output=True,
        text=True,
        timeout=60,
    )
    free = int(smi.stdout.split()[0]) * 2**20
    strands = free // 3 // (32 * 3 * 8)
    out = tmp_path / "big.h5"
    p = one_frame_on_cuda(out, "--strands", strands, "--points", 32, "--precision", "fp64", "--variant", "strand")
    assert p.returncode == 3, (p.returncode, p.stderr)
    assert "GPU memory" in p.stderr and "simulate" in p.stderr, p.stderr
    assert list(tmp_path.iterdir()) == [], "a refused run must leave no file"
