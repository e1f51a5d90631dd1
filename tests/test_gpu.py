"""GPU tests of the CUDA backend (cuda/, docs/cuda.md). Every test is marked `gpu`;
conftest.py skips them, with the reason, where there is no usable GPU.

Binaries: build/hairsim-cuda (normal build: FMA contraction), build/hairsim-cuda-strict (no
contraction, IEEE division and square root: differs from the C reference only where CUDA's
sinf/cosf/asinf/atan2f differ from glibc's, so the tight comparisons use it),
build/hairsim-cuda-fastmath, and build/hairsim-cpu (the oracle).

  (a) stage by stage: the CPU's frame k is fed through --input into the GPU for stage k+1
      only, and the GPU's frame is compared with the CPU's frame k+1; the whole run too.
      Every variant x block size x precision, strict build.
  (b) DESIGN §3 invariants on GPU outputs (every variant, every build).
  (c) bit-identical output across repeated runs and across block sizes (and, strict build,
      across variants).
  (d) a state too large for the GPU: exit status 3, "GPU memory" in the message, no file.
  (e) --block-size 48: exit status 2.
  (f) fused and soa give identical bits; the normal build's fused vs the strict build's.
  (g) --measure-bandwidth --json prints a positive copy_gbps.
Plus: the fused JSON record, repeats (save/restore), end-to-end, odd sizes, w = 0, and a
state past 2^31 elements.

The measured errors are written to build/gpu_test_errors.json (for recalibrating the
tolerances below; they were calibrated from one run on an H100 with nvcc 13.0).
"""
import json
import subprocess
from pathlib import Path

import h5py
import numpy as np
import pytest

from conftest import BUILD, CPU_BIN, CUDA_BIN, CUDA_FASTMATH_BIN, CUDA_STRICT_BIN

pytestmark = pytest.mark.gpu

VARIANTS = ("paper", "soa", "fused")
BLOCKS = (32, 64, 128, 256, 512, 1024)
PRECISIONS = ("fp32", "fp64")
STAGES = ("init", "collide", "wind", "collide")
BUILDS = {"normal": CUDA_BIN, "strict": CUDA_STRICT_BIN, "fastmath": CUDA_FASTMATH_BIN}

# The scene of the comparisons: the CLI's geometry (R = 10, h = 0.1, L = 30, m = 1), a wind
# that makes collide move many points after it (checked below, so every path runs).
N, P, SEED = 4000, 32, 20240607
R, H, L = 10.0, 0.1, 30.0
WIND = ("--wind-strength", "0.6", "--wind-angle", "3.0")

# ---- tolerances: ONE place. Error of a point = its Euclidean distance between the two
# states, divided by the hair length L. A frame passes when at most MAX_OVER_FRACTION of
# its points are over the tolerance (a coarser comparison can take the other side of a
# discrete decision of the model, e.g. a draped strand starts to hang one point earlier,
# moving the rest of that strand; same-precision fp64 allows none). NaN never passes.
#
# strict GPU vs CPU: the only differences are CUDA's sinf/cosf/asinf/atan2f (1-2 ulp) against
# glibc's; the drape accumulates asin over P-1 steps and wind carries it along. collide uses
# no transcendental function, so a strict collide from the CPU's frame is bit-identical to
# the CPU's (asserted). Measured on an H100 (this file's scene, every variant x block size):
# worst 8.3e-7 L in fp32 (init), 1.8e-15 L in fp64; no point over. Tolerances about 10x.
TOL_STRICT = {"fp32": 1e-5, "fp64": 2e-14}
# normal build (FMA contraction) vs strict build: each contracted a*b+c rounds once instead
# of twice. Measured: 8.9e-7 L (fp32), 3.3e-15 L (fp64); tolerances about 10x.
TOL_FMA = {"fp32": 1e-5, "fp64": 5e-14}
# No point was over tolerance in the measurements; the fp32 allowance is kept for a
# discrete decision taken the other way in other scenes (as harness/tolerances.py).
MAX_OVER_FRACTION = {"fp32": 1e-3, "fp64": 0.0}

# Invariants (DESIGN §3), in units of the precision's epsilon times the largest coordinate
# scale R + L for segments and times rc for the shell, as tests/invariants_check.py for the
# CPU (the collide test itself allows 16 eps rc). Measured on an H100: segments within
# 0.55 eps (R+L) (normal, strict; fp32 and fp64), 1.2 (fastmath fp32); shell depth at most
# 12.6 eps rc (fp32, any build; the 16 eps allowance), 2.4 (fp64). fast math (fp32 only:
# __sinf/__cosf, approximate division and square root) gets a 2x looser bound.
SEGMENT_EPS = {"normal": 16, "strict": 16, "fastmath": 32}
SHELL_EPS = {"normal": 32, "strict": 32, "fastmath": 64}

ERRORS = {}  # measured maximum errors, written to build/gpu_test_errors.json


@pytest.fixture(scope="session", autouse=True)
def _write_measurements():
    yield
    if ERRORS:
        try:
            (BUILD / "gpu_test_errors.json").write_text(json.dumps(ERRORS, indent=1, sort_keys=True) + "\n")
        except OSError:
            pass


# ---- helpers ---------------------------------------------------------------------------------
def run(binary, *args, check=True, timeout=300):
    cmd = [str(binary), *[str(a) for a in args]]
    p = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout)
    if check and p.returncode != 0:
        raise AssertionError(f"{' '.join(cmd)} exited {p.returncode}: {p.stderr.strip()}")
    return p


def scene_args(precision, strands=N, points=P):
    return ["--strands", strands, "--points", points, "--seed", SEED, "--precision", precision, *WIND, "--quiet"]


class State:
    def __init__(self, path):
        with h5py.File(path, "r") as f:
            prm = f["parameters"].attrs
            self.n, self.p = int(prm["n_strands"]), int(prm["points_per_strand"])
            self.R, self.h, self.L = float(prm["head_radius"]), float(prm["hair_offset"]), float(prm["hair_length"])
            self.flags = prm["flags"].decode() if isinstance(prm["flags"], bytes) else str(prm["flags"])
            v = f["particles/hair/position/value"]
            self.dtype = v.dtype
            self.frames = v[:].reshape(v.shape[0], self.n, self.p, 3)
            dec = lambda a: [s.decode() if isinstance(s, bytes) else str(s) for s in a]
            self.stages = dec(f["parameters/stage"][:])
            self.fused = dec(f["parameters/fused"][:])
            self.moved = f["parameters/moved_points"][:]


def record(key, value):
    ERRORS[key] = max(float(value), ERRORS.get(key, 0.0))


def compare(gpu, cpu, precision, what, tol=None, key=None):
    """Asserts two frames [N][P][3] agree; returns the maximum error / L."""
    a, b = gpu.astype(np.float64), cpu.astype(np.float64)
    assert a.shape == b.shape, f"{what}: shapes {a.shape} vs {b.shape}"
    assert np.isfinite(a).all(), f"{what}: NaN or Inf in the GPU state"
    d = np.linalg.norm(a - b, axis=-1) / L
    tol = TOL_STRICT[precision] if tol is None else tol
    over = int((d > tol).sum())
    allowed = int(MAX_OVER_FRACTION[precision] * d.size)
    worst = float(d.max())
    record(key or what, worst)
    assert over <= allowed, (f"{what}: {over} of {d.size} points are more than {tol:g} L apart (allowed {allowed}); "
                             f"worst {worst:.3g} L at strand {np.unravel_index(d.argmax(), d.shape)}")
    return worst


def bits_equal(a, b):
    return a.dtype == b.dtype and a.shape == b.shape and a.tobytes() == b.tobytes()


def check_invariants(s, build="strict"):
    """DESIGN §3 on every frame of a state."""
    fr = s.frames
    eps = float(np.finfo(s.dtype).eps)
    assert np.isfinite(fr).all(), "NaN or Inf in a frame"
    root0 = fr[0, :, 0, :]
    rc = np.hypot(root0[:, 1].astype(np.float64), root0[:, 2].astype(np.float64)) + s.h
    ell = s.L / (s.p - 1)
    for f in range(fr.shape[0]):
        assert bits_equal(fr[f, :, 0, :], root0), f"frame {f} ({s.stages[f]}): a root moved"
        x = fr[f, :, :, 0]
        assert bits_equal(x, np.repeat(fr[0, :, :1, 0], s.p, axis=1)), f"frame {f} ({s.stages[f]}): x changed"
        st = fr[f].astype(np.float64)
        seg = np.linalg.norm(np.diff(st, axis=1), axis=2)
        worst = float(np.abs(seg - ell).max())
        record(f"invariant segment/(eps(R+L)) {build} {s.dtype}", worst / (eps * (s.R + s.L)))
        assert worst <= SEGMENT_EPS[build] * eps * (s.R + s.L), f"frame {f}: a segment length is off by {worst:g}"
        if s.stages[f] == "collide":
            r = np.hypot(st[:, 1:, 1], st[:, 1:, 2])
            depth = float((rc[:, None] - r).max())
            record(f"invariant shell depth/(eps rc) {build} {s.dtype}", depth / (eps * rc.max()))
            assert (rc[:, None] * (1 - SHELL_EPS[build] * eps) - r).max() <= 0, \
                f"frame {f}: a point is {depth:g} inside its shell"


# ---- shared runs (each made once per session) ------------------------------------------------
_CACHE = {}


@pytest.fixture(scope="session")
def work(tmp_path_factory):
    return tmp_path_factory.mktemp("gpu")


@pytest.fixture(scope="session")
def cpu_ref(work):
    """precision -> (the CPU's whole run, {n: a file with its first n frames})."""
    def get(precision):
        key = ("cpu", precision)
        if key not in _CACHE:
            full = work / f"cpu_{precision}.h5"
            run(CPU_BIN, *scene_args(precision), "--variant", "ref", "--stages", ",".join(STAGES), "--output", full)
            prefix = {}
            for n in range(1, len(STAGES)):
                prefix[n] = work / f"cpu_{precision}_{n}.h5"
                run(CPU_BIN, *scene_args(precision), "--variant", "ref", "--stages", ",".join(STAGES[:n]),
                    "--output", prefix[n])
            _CACHE[key] = (full, prefix)
        return _CACHE[key]
    return get


@pytest.fixture(scope="session")
def gpu_run(work):
    """(build, variant, block, precision) -> the GPU's whole run of STAGES (a State)."""
    def get(build, variant, block, precision, tag=""):
        key = ("gpu", build, variant, block, precision, tag)
        if key not in _CACHE:
            out = work / f"gpu_{build}_{variant}_{block}_{precision}{tag}.h5"
            run(BUILDS[build], *scene_args(precision), "--stages", ",".join(STAGES), "--variant", variant,
                "--block-size", block, "--output", out)
            _CACHE[key] = State(out)
        return _CACHE[key]
    return get


# ---- (a) stage by stage against the CPU, every variant x block size x precision ---------------
@pytest.mark.parametrize("precision", PRECISIONS)
@pytest.mark.parametrize("block", BLOCKS)
@pytest.mark.parametrize("variant", VARIANTS)
def test_stage_by_stage_matches_cpu(tmp_path, cpu_ref, gpu_run, variant, block, precision):
    full, prefix = cpu_ref(precision)
    cpu = State(full)
    assert cpu.moved[1] >= 0 and cpu.moved[3] > 0, "the scene must make collide move points after the wind"
    common = ["--variant", variant, "--block-size", block, "--quiet", *WIND]
    tag = f"{variant} b{block} {precision}"

    # init from nothing
    out = tmp_path / "init.h5"
    run(CUDA_STRICT_BIN, *scene_args(precision), "--stages", "init", "--variant", variant, "--block-size", block,
        "--output", out)
    g = State(out)
    compare(g.frames[0], cpu.frames[0], precision, f"init [{tag}]", key=f"strict-vs-cpu init {precision}")
    # roots use only +, -, *, sqrt: bit-identical to the CPU without contraction
    assert bits_equal(g.frames[0][:, 0, :], cpu.frames[0][:, 0, :]), f"init [{tag}]: roots differ from the CPU's"

    # each further stage alone, from the CPU's previous frame
    for n in (1, 3):
        out = tmp_path / f"collide{n}.h5"
        run(CUDA_STRICT_BIN, "--input", prefix[n], "--stages", "collide", *common, "--output", out)
        g = State(out)
        assert g.frames.shape[0] == n + 1
        assert bits_equal(g.frames[:n], cpu.frames[:n]), "the input frames must be copied unchanged"
        compare(g.frames[n], cpu.frames[n], precision, f"collide frame {n} [{tag}]",
                key=f"strict-vs-cpu collide {precision}")
        # collide: + - x / sqrt only, all IEEE in the strict build: the CPU's bits
        assert bits_equal(g.frames[n], cpu.frames[n]), f"collide frame {n} [{tag}]: not bit-identical to the CPU"
        assert int(g.moved[n]) == int(cpu.moved[n])

    # wind, then collide (for fused: one kernel, whose wind frame is the kept intermediate)
    out = tmp_path / "windcollide.h5"
    run(CUDA_STRICT_BIN, "--input", prefix[2], "--stages", "wind,collide", *common, "--output", out)
    g = State(out)
    assert g.stages == ["init", "collide", "wind", "collide"]
    assert g.fused[2:] == (["wind+collide", "into-previous"] if variant == "fused" else ["", ""])
    compare(g.frames[2], cpu.frames[2], precision, f"wind frame 2 [{tag}]", key=f"strict-vs-cpu wind {precision}")
    compare(g.frames[3], cpu.frames[3], precision, f"wind+collide frame 3 [{tag}]",
            key=f"strict-vs-cpu wind+collide {precision}")

    # the whole run
    g = gpu_run("strict", variant, block, precision)
    assert g.stages == list(STAGES)
    for f in range(len(STAGES)):
        compare(g.frames[f], cpu.frames[f], precision, f"whole run frame {f} [{tag}]",
                key=f"strict-vs-cpu whole run {precision}")


# ---- (b) invariants ---------------------------------------------------------------------------
@pytest.mark.parametrize("precision", PRECISIONS)
@pytest.mark.parametrize("build", list(BUILDS))
@pytest.mark.parametrize("variant", VARIANTS)
def test_invariants_on_gpu_output(gpu_run, variant, build, precision):
    s = gpu_run(build, variant, 256, precision)
    check_invariants(s, build)
    assert s.moved[3] > 0


@pytest.mark.parametrize("precision", PRECISIONS)
def test_invariants_strong_wind_other_angles(tmp_path, precision):
    for build in ("normal", "fastmath"):
        for angle in (0.0, 1.0, -2.5, 7.0, 1.5707963267948966):
            out = tmp_path / f"w_{build}_{angle}.h5"
            run(BUILDS[build], "--strands", 3000, "--points", 24, "--seed", 5, "--precision", precision,
                "--wind-strength", 1, "--wind-angle", angle, "--stages", "init,collide,wind,collide,wind,collide",
                "--output", out, "--quiet")
            check_invariants(State(out), build)


# ---- (c) determinism ------------------------------------------------------------------------
@pytest.mark.parametrize("precision", PRECISIONS)
@pytest.mark.parametrize("variant", VARIANTS)
def test_bits_repeat_and_do_not_depend_on_block_size(gpu_run, variant, precision):
    for build in ("strict", "normal"):
        ref = gpu_run(build, variant, 256, precision)
        again = gpu_run(build, variant, 256, precision, tag="-again")
        assert bits_equal(ref.frames, again.frames), f"{build} {variant}: two runs differ"
        for block in BLOCKS:
            s = gpu_run(build, variant, block, precision)
            assert bits_equal(ref.frames, s.frames), f"{build} {variant}: block {block} differs from block 256"
            assert list(s.moved) == list(ref.moved)


@pytest.mark.parametrize("precision", PRECISIONS)
def test_strict_variants_identical(gpu_run, precision):
    """Same arithmetic in every variant (only the layout and the kernel split differ)."""
    ref = gpu_run("strict", "paper", 256, precision)
    for variant in ("soa", "fused"):
        s = gpu_run("strict", variant, 256, precision)
        assert bits_equal(ref.frames, s.frames), f"strict build: {variant} differs from paper"


# ---- (d) memory refusal, (e) bad block size ----------------------------------------------------
def test_state_too_large_is_refused(tmp_path):
    out = tmp_path / "huge.h5"
    p = run(CUDA_BIN, "--strands", 100000000000, "--points", 64, "--output", out, check=False)
    assert p.returncode == 3, (p.returncode, p.stderr)
    assert "GPU memory" in p.stderr or "host memory" in p.stderr, p.stderr
    assert p.stderr.startswith("hairsim-cuda: error: ") and p.stderr.count("\n") == 1, p.stderr
    assert list(tmp_path.iterdir()) == [], "a refused run must leave no file"


def test_bad_block_size_is_refused(tmp_path):
    p = run(CUDA_BIN, "--block-size", 48, "--output", tmp_path / "x.h5", check=False)
    assert p.returncode == 2, (p.returncode, p.stderr)
    assert "--block-size" in p.stderr
    assert list(tmp_path.iterdir()) == []


# ---- (f) fused vs soa, normal vs strict --------------------------------------------------------
@pytest.mark.parametrize("precision", PRECISIONS)
@pytest.mark.parametrize("build", list(BUILDS))
def test_fused_and_soa_agree(gpu_run, build, precision):
    """Same arithmetic, different layout and kernel split. Bit-identical in the strict
    build. With contraction on (normal, fastmath) nvcc leaves plain mul/add pairs in the
    PTX where a product has several uses (collide's intersection: hh·uz serves y1 and y2),
    and ptxas fuses them per kernel by its own heuristics, so the fused kernel and the two
    separate ones may round such a pair differently (docs/cuda.md): there they must agree
    within TOL_FMA, and the number of values that differ is recorded."""
    a = gpu_run(build, "fused", 256, precision)
    b = gpu_run(build, "soa", 256, precision)
    if build == "strict":
        assert bits_equal(a.frames, b.frames), "strict build: fused and soa differ"
        assert list(a.moved) == list(b.moved)
        return
    record(f"fused-vs-soa {build} {precision}: values differing", int((a.frames != b.frames).sum()))
    tol = TOL_FMA[precision] if build == "normal" else 1e-3
    for f in range(len(STAGES)):
        compare(a.frames[f], b.frames[f], precision, f"{build} fused vs soa frame {f}", tol=tol,
                key=f"fused-vs-soa {build} {precision}")


@pytest.mark.parametrize("precision", PRECISIONS)
def test_normal_build_close_to_strict(gpu_run, precision):
    a = gpu_run("normal", "fused", 256, precision)
    b = gpu_run("strict", "fused", 256, precision)
    for f in range(len(STAGES)):
        compare(a.frames[f], b.frames[f], precision, f"normal vs strict frame {f}", tol=TOL_FMA[precision],
                key=f"normal-vs-strict {precision}")
    assert "math-mode=normal" in a.flags and "math-mode=strict" in b.flags


def test_fastmath_build_records_its_flags(gpu_run):
    s = gpu_run("fastmath", "fused", 256, "fp32")
    assert "use_fast_math" in s.flags and "math-mode=fastmath" in s.flags
    ref = gpu_run("strict", "fused", 256, "fp32")
    d = np.linalg.norm(s.frames.astype(np.float64) - ref.frames.astype(np.float64), axis=-1) / L
    record("fastmath-vs-strict fp32 (max)", float(d.max()))
    record("fastmath-vs-strict fp32 (p99)", float(np.quantile(d, 0.99)))


# ---- (g) bandwidth ------------------------------------------------------------------------------
def test_measure_bandwidth_json():
    p = run(CUDA_BIN, "--measure-bandwidth", "--json")
    rec = json.loads(p.stdout)
    assert rec["backend"] == "cuda" and rec["copy_gbps"] > 0 and rec["bytes"] > 0, rec
    assert rec["device"] and rec["device"] != "unknown CUDA device", rec
    record("copy_gbps", rec["copy_gbps"])


# ---- the record, repeats, end-to-end, odd sizes, w = 0, large states -----------------------------
@pytest.mark.parametrize("variant", VARIANTS)
def test_json_record(variant, cpu_ref):
    p = run(CUDA_STRICT_BIN, *scene_args("fp32"), "--variant", variant, "--block-size", 128, "--json",
            "--end-to-end")
    rec = json.loads(p.stdout)
    cpu = State(cpu_ref("fp32")[0])
    assert rec["backend"] == "cuda" and rec["variant"] == variant and rec["block_size"] == 128
    assert [s["stage"] for s in rec["stages"]] == list(STAGES)
    fused = [s["fused"] for s in rec["stages"]]
    if variant == "fused":
        assert fused == [None, None, "wind+collide", "into-previous"] or fused == ["", "", "wind+collide", "into-previous"]
        assert rec["stages"][3]["median_ms"] == 0
    else:
        assert "wind+collide" not in fused
    for f in (1, 3):
        assert abs(rec["stages"][f]["moved_points"] - int(cpu.moved[f])) <= MAX_OVER_FRACTION["fp32"] * N * P
    for s in rec["stages"]:
        assert s["median_ms"] >= 0
    assert rec["stages"][0]["median_ms"] > 0
    assert rec["end_to_end_ms"] > 0 and rec["d2h_ms"] > 0
    assert rec["device"] and rec["driver"], rec
    assert "math-mode=strict" in rec["flags"]


@pytest.mark.parametrize("variant", VARIANTS)
@pytest.mark.parametrize("precision", PRECISIONS)
def test_repeats_restore_the_state(tmp_path, gpu_run, variant, precision):
    """--repeat/--warmup run each stage several times from a saved copy: same bits."""
    out = tmp_path / "rep.h5"
    run(CUDA_STRICT_BIN, *scene_args(precision), "--stages", ",".join(STAGES), "--variant", variant,
        "--block-size", 256, "--repeat", 3, "--warmup", 2, "--end-to-end", "--output", out)
    assert bits_equal(State(out).frames, gpu_run("strict", variant, 256, precision).frames)


@pytest.mark.parametrize("variant", VARIANTS)
@pytest.mark.parametrize("precision", PRECISIONS)
def test_odd_sizes_through_the_transposes(tmp_path, variant, precision):
    """N and P that fill neither a warp nor a 32 x 32 transpose tile; --input load and
    fetch through the staging buffer; a block size that is not a power of two."""
    for strands, points in ((1037, 7), (1, 2), (33, 45)):
        cpu = tmp_path / f"cpu_{strands}_{points}.h5"
        pre = tmp_path / f"pre_{strands}_{points}.h5"
        run(CPU_BIN, *scene_args(precision, strands, points), "--variant", "ref", "--stages", ",".join(STAGES),
            "--output", cpu)
        run(CPU_BIN, *scene_args(precision, strands, points), "--variant", "ref", "--stages", "init,collide",
            "--output", pre)
        out = tmp_path / f"gpu_{strands}_{points}.h5"
        run(CUDA_STRICT_BIN, "--input", pre, "--stages", "wind,collide", *WIND, "--variant", variant,
            "--block-size", 96, "--quiet", "--output", out)
        c, g = State(cpu), State(out)
        assert bits_equal(g.frames[:2], c.frames[:2])
        for f in (2, 3):
            compare(g.frames[f], c.frames[f], precision, f"odd size {strands}x{points} frame {f} [{variant}]",
                    key=f"strict-vs-cpu odd sizes {precision}")
        # a collide alone from the file: load (transpose in), fetch (transpose out)
        out2 = tmp_path / f"gpu2_{strands}_{points}.h5"
        run(CUDA_STRICT_BIN, "--input", pre, "--stages", "collide", "--variant", variant, "--quiet", "--output", out2)
        g2 = State(out2)
        assert bits_equal(g2.frames[:2], c.frames[:2])
        check_invariants(g2, "strict")


@pytest.mark.parametrize("variant", VARIANTS)
def test_zero_wind_is_skipped(tmp_path, variant):
    out = tmp_path / "w0.h5"
    p = run(CUDA_STRICT_BIN, "--strands", 2000, "--points", 16, "--wind-strength", 0, "--variant", variant,
            "--output", out, "--json", "--quiet")
    rec = json.loads(p.stdout)
    assert rec["stages"][2]["skipped"] is True and rec["stages"][2]["fused"] in (None, "")
    s = State(out)
    assert bits_equal(s.frames[2], s.frames[1]), "a skipped wind must leave its frame unchanged"
    check_invariants(s, "strict")


def test_state_past_2_to_the_31_elements():
    """N·P·3 > 2^31: 64-bit indexing in the strand-major (paper) and point-major (fused)
    kernels; the moved-point counts of the two layouts must agree exactly."""
    strands, points = 23_000_000, 32  # 2.2e9 elements, 8.8 GB fp32
    args = ["--strands", strands, "--points", points, "--seed", SEED, *WIND, "--json", "--quiet"]
    moved = {}
    for variant in ("paper", "fused"):
        p = run(CUDA_STRICT_BIN, *args, "--variant", variant, check=False, timeout=600)
        if p.returncode == 3:
            pytest.skip(f"not enough GPU memory for the 2^31-element test: {p.stderr.strip()}")
        assert p.returncode == 0, p.stderr
        moved[variant] = [s["moved_points"] for s in json.loads(p.stdout)["stages"]]
    assert moved["paper"] == moved["fused"], moved
    assert moved["fused"][3] > 0
