"""The simulate stage of the simd CPU variant (c_ref/dynamics_simd*.{h,c}; docs/cpu_simd.md,
"The dynamic model") against the `ref` oracle (c_ref/dynamics_impl.h).

simd evaluates the dynamic model with ref's operations in ref's order (docs/model.md §3.10):
no FMA contraction, IEEE sqrt and division, selects where ref branches. So from the same
input state it must give ref's bits wherever no libm function is called, i.e. without
gusts: positions of every frame, velocities and observables (the per-strand observables
are ref's bits and are combined over ref's chunks in ref's order). With gusts the sine is
libmvec's (≤ 4 ulp) and the runs are compared with harness/core/tolerances.py's SIMD_DYN_GUST
(the measurement behind it is written there).

Both variants start from the same ref `init,collide` state (--input): simd's own paper
stages differ from ref's by their libmvec rounding (tests/cpu/test_cpu_simd.py covers those).
N = 300 and 1000 are not multiples of the blocks (512/256 strands, 64 per dynamic block).
"""

import platform
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest
from test_cpu_simd import NO_SIMD, needs_simd

from harness.core.tolerances import SIMD_DYN_GUST, SIMD_DYN_GUST_MAX_FRAMES
from harness.io.trajectory import open_trajectory
from support.statecheck import run

STRANDS = 300
FRAMES = 10
GUST = ["--wind-speed", 300, "--drag", 1, "--gust-amplitude", 0.8, "--gust-frequency", 3, "--gust-wavelength", 20]
# feature sets (docs/model.md §3.9): none, each alone (wind needs a drag, so it comes with
# one; gust needs wind), all but the gusts, all
FEATURES = {
    "none": ["--no-collider"],
    "bend": ["--no-collider", "--bend-compliance", 1e-6],
    "shape": ["--no-collider", "--shape-compliance", 1e-5, "--shape-range", 0.7],
    "wind+drag": ["--no-collider", "--wind-speed", 300, "--drag", 1],
    "motion": ["--no-collider", "--head-motion", "nod", "--motion-amplitude", 0.5],
    "collide": ["--collision-margin", 0.3],
    "drag": ["--no-collider", "--damping", 2],
    "all-but-gust": [
        "--bend-compliance",
        1e-6,
        "--shape-compliance",
        1e-5,
        "--wind-speed",
        300,
        "--drag",
        1,
        "--damping",
        0.5,
        "--head-motion",
        "shake",
    ],
}
ALL = FEATURES["all-but-gust"] + ["--gust-amplitude", 0.8, "--gust-frequency", 3, "--gust-wavelength", 20]
SOLVE = ["--substeps", 3, "--iterations", 2]


@pytest.fixture(scope="module")
def inputs(cpu_bin, tmp_path_factory):
    """ref init,collide states: (precision, points, strands) → path."""
    d = tmp_path_factory.mktemp("simd_dyn_inputs")
    made = {}

    def get(precision, points, strands=STRANDS):
        key = (precision, points, strands)
        if key not in made:
            path = d / f"in_{precision}_{points}_{strands}.h5"
            run(
                cpu_bin,
                "--stages",
                "init,collide",
                "--strands",
                strands,
                "--points",
                points,
                "--precision",
                precision,
                "--seed",
                7,
                "--output",
                path,
                "--quiet",
            )
            made[key] = path
        return made[key]

    return get


def simulate(cpu_bin, inp, out, variant, *args, frames=FRAMES):
    run(
        cpu_bin,
        "--input",
        inp,
        "--stages",
        "simulate",
        "--frames",
        frames,
        "--variant",
        variant,
        *SOLVE,
        *args,
        "--output",
        out,
        "--force",
        "--quiet",
    )
    return out


def read(path):
    """positions [F][N][P][3], velocities, observables, the scene's E = R + h + L and h."""
    with open_trajectory(path) as s:
        pos = np.stack([s.frame(f) for f in range(s.n_frames)])
        vel = np.stack([s.velocity(i) for i in range(len(s.velocity_steps))])
        obs = {k: s.observables[k].to_numpy() for k in s.observables.columns if k not in ("step", "time")}
        p = s.params
        extent = float(p["head_radius"]) + float(p["hair_offset"]) + float(p["hair_length"])
        h = float(p["frame_dt"]) / float(p["substeps"])
        assert s.stages[-1] == "simulate"
        return pos, vel, obs, extent, h, s.segment_length


def assert_same_bits(a, b, what):
    pa, va, oa = read(a)[:3]
    pb, vb, ob = read(b)[:3]
    assert pa.shape == pb.shape and pa.dtype == pb.dtype, what
    for f in range(len(pa)):
        bad = int((pa[f] != pb[f]).any(axis=2).any(axis=1).sum())
        assert bad == 0, f"{what}: frame {f}: {bad} strands differ; max |Δ| {np.abs(pa[f] - pb[f]).max():.3g}"
    assert np.array_equal(va, vb), f"{what}: velocities differ (max |Δ| {np.abs(va - vb).max():.3g})"
    assert oa.keys() == ob.keys()
    for k in oa:
        assert np.array_equal(oa[k], ob[k]), f"{what}: observable {k} differs: {oa[k]} vs {ob[k]}"


@needs_simd
@pytest.mark.parametrize("precision", ["fp32", "fp64"])
@pytest.mark.parametrize("solver", ["xpbd", "ftl"])
@pytest.mark.parametrize("features", list(FEATURES))
def test_without_gusts_simd_is_ref_bit_for_bit(cpu_bin, inputs, tmp_path, precision, solver, features):
    points = 33 if features != "none" else 16
    inp = inputs(precision, points)
    args = ["--solver", solver, *FEATURES[features]]
    a = simulate(cpu_bin, inp, tmp_path / "ref.h5", "ref", *args)
    b = simulate(cpu_bin, inp, tmp_path / "simd.h5", "simd", *args)
    assert_same_bits(a, b, f"{precision} {solver} {features}")


@needs_simd
@pytest.mark.parametrize("precision", ["fp32", "fp64"])
@pytest.mark.parametrize("points", [2, 3, 16])
def test_short_strands_bit_for_bit(cpu_bin, inputs, tmp_path, precision, points):
    """P = 2 (no bend constraint), 3 (one), 16; all features but the gusts, both solvers."""
    inp = inputs(precision, points)
    for solver in ("xpbd", "ftl"):
        args = ["--solver", solver, *FEATURES["all-but-gust"]]
        a = simulate(cpu_bin, inp, tmp_path / "ref.h5", "ref", *args, frames=4)
        b = simulate(cpu_bin, inp, tmp_path / "simd.h5", "simd", *args, frames=4)
        assert_same_bits(a, b, f"{precision} P={points} {solver}")


@needs_simd
@pytest.mark.parametrize("precision", ["fp32", "fp64"])
@pytest.mark.parametrize("solver", ["xpbd", "ftl"])
@pytest.mark.parametrize("features", ["gust", "all"])
def test_with_gusts_simd_is_within_the_tolerance(cpu_bin, inputs, tmp_path, precision, solver, features):
    assert FRAMES <= SIMD_DYN_GUST_MAX_FRAMES  # the tolerance's horizon
    inp = inputs(precision, 33)
    args = ["--solver", solver, *(GUST if features == "gust" else ALL), "--velocities", "all"]
    pa, va, oa, extent, h, ell = read(simulate(cpu_bin, inp, tmp_path / "ref.h5", "ref", *args))
    pb, vb, ob, _, _, _ = read(simulate(cpu_bin, inp, tmp_path / "simd.h5", "simd", *args))
    t = SIMD_DYN_GUST
    eps = float(np.finfo(pa.dtype).eps)
    assert np.isfinite(pb).all() and np.isfinite(vb).all()
    assert np.array_equal(pa[:2], pb[:2])  # the input's frames
    dx = float(np.abs(pa.astype(np.float64) - pb).max())
    assert dx <= t.position_k * eps * extent, f"positions: {dx / (eps * extent):.2f} ε·E > {t.position_k}"
    dv = float(np.abs(va.astype(np.float64) - vb).max())
    assert dv <= t.velocity_k * eps * extent / h, f"velocities: {dv / (eps * extent / h):.2f} ε·E/h > {t.velocity_k}"
    ke = np.abs(oa["kinetic_energy"] - ob["kinetic_energy"]) / (eps * oa["kinetic_energy"])
    assert ke.max() <= t.kinetic_energy_k, f"kinetic energy: {ke.max():.2f} ε relative > {t.kinetic_energy_k}"
    st = np.abs(oa["stretch_max"] - ob["stretch_max"]).max() / (eps * extent / ell)
    assert st <= t.stretch_k, f"stretch_max: {st:.2f} ε·E/ℓ > {t.stretch_k}"
    pen = np.abs(oa["penetration_max"] - ob["penetration_max"]).max() / (eps * extent)
    assert pen <= t.penetration_k, f"penetration_max: {pen:.2f} ε·E > {t.penetration_k}"
    assert np.array_equal(oa["blown_up_strands"], ob["blown_up_strands"])


@needs_simd
@pytest.mark.parametrize("precision", ["fp32", "fp64"])
def test_threads_and_repeats_give_the_same_bits(cpu_bin, inputs, tmp_path, precision):
    """--threads 1/2/3 and --repeat 3 (save/restore of positions and velocities) give the
    bits of one thread, one repeat; N = 1000: two layout blocks, the last one partial."""
    inp = inputs(precision, 16, 1000)
    args = ["--solver", "xpbd", *ALL, "--velocities", "all"]
    one = simulate(cpu_bin, inp, tmp_path / "t1.h5", "simd", *args, "--threads", 1, frames=5)
    for extra in (["--threads", 2], ["--threads", 3], ["--threads", 2, "--repeat", 3]):
        other = simulate(cpu_bin, inp, tmp_path / "tn.h5", "simd", *args, *extra, frames=5)
        assert_same_bits(one, other, f"{precision} {extra}")


@needs_simd
@pytest.mark.parametrize("solver", ["xpbd", "ftl"])
def test_resume_gives_the_same_bits(cpu_bin, inputs, tmp_path, solver):
    """10 frames in one run = 5 frames, then 5 more from its last frame = 10 frames, then
    resumed from frame 3 (--input-frame, velocities of every frame stored)."""
    inp = inputs("fp32", 16)
    args = ["--solver", solver, *ALL, "--velocities", "all"]
    whole = simulate(cpu_bin, inp, tmp_path / "whole.h5", "simd", *args, frames=10)
    half = simulate(cpu_bin, inp, tmp_path / "half.h5", "simd", *args, frames=5)
    rest = simulate(cpu_bin, half, tmp_path / "rest.h5", "simd", *args, frames=5)
    pw, vw, ow = read(whole)[:3]
    pr, vr, orr = read(rest)[:3]
    assert np.array_equal(pw[-1], pr[-1]) and np.array_equal(vw[-1], vr[-1])
    assert np.array_equal(ow["kinetic_energy"][-5:], orr["kinetic_energy"][-5:])
    # from simulated frame 3 of the whole run (file frame paper_frames − 1 + 3 = 4)
    mid = tmp_path / "mid.h5"
    run(
        cpu_bin,
        "--input",
        whole,
        "--input-frame",
        4,
        "--stages",
        "simulate",
        "--frames",
        7,
        "--variant",
        "simd",
        *SOLVE,
        *args,
        "--output",
        mid,
        "--force",
        "--quiet",
    )
    pm, vm = read(mid)[:2]
    assert np.array_equal(pw[-1], pm[-1]) and np.array_equal(vw[-1], vm[-1])


def test_dynamics_simd_object_calls_only_the_vector_sine(cpu_bin):
    """The gust sine of dynamics_simd.o is libmvec's (_ZGV…sin/sinf); a scalar sin would mean
    the velocity loop was not vectorised."""
    obj = Path(cpu_bin).parent / "obj" / "dynamics_simd.o"
    if platform.machine() != "x86_64":
        pytest.skip(f"simd test skipped: {NO_SIMD}")
    if not obj.exists():
        pytest.skip(f"{obj} not found (the binary was not built by this Makefile)")
    if shutil.which("objdump") is None:
        pytest.skip("objdump not found (binutils)")
    text = subprocess.run(["objdump", "-dr", str(obj)], capture_output=True, text=True, check=True).stdout
    called = {
        line.split()[-1].split("-")[0].split("+")[0]
        for line in text.splitlines()
        if "R_X86_64_PLT32" in line or "R_X86_64_PC32" in line
    }
    if "__asan_init" in called or any(c.startswith("__ubsan_") for c in called):
        pytest.skip("a sanitizer build (make sanitize): its instrumentation keeps the loops scalar")
    assert not {"sinf", "sin", "sqrtf", "sqrt", "sincosf", "sincos"} & called, sorted(called)
    for f in ("sinf", "sin"):
        assert any(c.startswith("_ZGV") and c.endswith("_" + f) for c in called), f"no vector call to {f}"


@needs_simd
def test_simd_lists_simulate(cpu_bin):
    import json

    listing = json.loads(run(cpu_bin, "--list-variants").stdout)
    simd = [v for v in listing["variants"] if v["name"] == "simd"][0]
    assert "simulate" in simd["stages"]
