"""The simd variant of the CPU backend: `hairsim-cpu --variant simd` against the
`ref` oracle, one stage at a time (the ref state after frame k fed through --input into
simd for the next stage only) and whole runs; the invariants of docs/model.md §2.7 on its outputs; bits
independent of the thread count, of repeats and of resuming; nil stages; the refusal on a
CPU without AVX2; the vector math really vectorised; the bandwidth record.

TOLERANCE: the "simd" pair of harness/core/tolerances.py (the measurements behind it are in
docs/cpu_simd.md); every comparison goes through harness diff. simd computes with the free
arithmetic (one reciprocal where ref divides; docs/cpu_simd.md), so collide too is judged
by the tolerance, and its moved-point count by MOVED_COUNT_FRACTION.

Not compared point for point: whole runs with strong wind at angles other than the default,
where the shorter-arc rule of the wind is discontinuous at an exactly opposite segment and
an input that differs by rounding (the init/collide before it) can turn a near-opposite
segment the other way (docs/cpu_simd.md, "A discontinuity, not an error"). Those runs are
checked for the invariants, and the wind stage itself from the same input is compared.
"""

import json
import math
import os
import platform
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from test_stability import scene_args, scenes

from harness.core import tolerances
from support import synthetic
from support.invariants_check import assert_invariants
from support.statecheck import State, assert_equivalent, assert_threads_change_no_bit, run, run_json, tmp_leftovers

SEEDS = [1, 7, 123456789]
PAPER = ["init", "collide", "wind", "collide"]
# x86-64-v3, as /proc/cpuinfo names it (abm = lzcnt)
V3_FLAGS = ("avx", "avx2", "fma", "bmi1", "bmi2", "f16c", "movbe", "abm")


# x86-64-v4 adds these (the simd variant's second build, docs/cpu_simd.md "Two builds")
V4_FLAGS = ("avx512f", "avx512vl", "avx512bw", "avx512dq", "avx512cd")


def _cpu_flags():
    """The CPU's flags as /proc/cpuinfo names them, or the reason they cannot be read."""
    try:
        text = Path("/proc/cpuinfo").read_text()
    except OSError as e:
        return f"cannot read /proc/cpuinfo ({e})"
    for line in text.splitlines():
        if line.startswith("flags"):
            return set(line.split(":", 1)[1].split())
    return set()


def _no_simd_reason(wanted=V3_FLAGS, level="x86-64-v3", what="hairsim-cpu refuses --variant simd"):
    """None where this machine can run the simd variant (its `level` build), else why not."""
    if platform.machine() not in ("x86_64", "AMD64"):
        return f"the simd variant is built for x86_64 only (this is {platform.machine()})"
    flags = _cpu_flags()
    if isinstance(flags, str):
        return flags
    missing = [f for f in wanted if f not in flags]
    if missing:
        return f"this CPU lacks {', '.join(missing)} ({level}), so {what}"
    return None


NO_SIMD = _no_simd_reason()
needs_simd = pytest.mark.skipif(NO_SIMD is not None, reason=f"simd test skipped: {NO_SIMD}")
NO_V4 = NO_SIMD or _no_simd_reason(V3_FLAGS + V4_FLAGS, "x86-64-v4", "the simd variant's AVX-512 build cannot run")
# the two builds, forced through HAIRBENCH_SIMD_ISA (without it the CPU's widest runs)
ISAS = [
    pytest.param("avx2", id="avx2"),
    pytest.param("avx512", id="avx512", marks=pytest.mark.skipif(NO_V4 is not None, reason=f"{NO_V4}")),
]


def assert_close(ref_path, simd_path, precision, frames, what):
    """harness diff of simd against ref under the "simd" pair (tolerances.named_pair)."""
    return assert_equivalent(
        ref_path, simd_path, frames=frames, tolerance=tolerances.named_pair("simd", precision), what=what
    )


def assert_moved_close(got, want, points, what):
    """Collide counts of two equivalent states: a point within rounding of the shell
    allowance may be moved by one and not the other (tolerances.MOVED_COUNT_FRACTION)."""
    assert abs(int(got) - int(want)) <= tolerances.MOVED_COUNT_FRACTION * points, (what, got, want)


def moved_from_frames(before, after):
    """Points a collide pass changed, counted from the frames: from the first point it
    changed to the tip of each strand (every later point is pulled)."""
    changed = (before != after).any(axis=2)
    first = np.where(changed.any(axis=1), changed.argmax(axis=1), changed.shape[1])
    return int((changed.shape[1] - first).sum())


def scene(points, seed, precision, strands=1000):
    return ["--strands", strands, "--points", points, "--seed", seed, "--precision", precision]


# ---- equivalence with ref ---------------------------------------------------------------


@needs_simd
@pytest.mark.parametrize("precision", ["fp32", "fp64"])
@pytest.mark.parametrize("points", [2, 3, 16, 64, 251])
@pytest.mark.parametrize("seed", SEEDS)
def test_whole_run_matches_ref_and_keeps_the_invariants(cpu_bin, tmp_path, precision, points, seed):
    ref, simd = tmp_path / "ref.h5", tmp_path / "simd.h5"
    args = scene(points, seed, precision)
    run(cpu_bin, *args, "--variant", "ref", "--output", ref, "--quiet")
    run(cpu_bin, *args, "--variant", "simd", "--output", simd, "--quiet")
    a, b = State(ref), State(simd)
    assert b.stages == PAPER and b.dtype == a.dtype
    assert_invariants(b)
    # roots (integer draws, IEEE arithmetic) and x (never changes) are ref's bits
    assert np.array_equal(b.frames[..., 0], a.frames[..., 0])
    assert np.array_equal(b.frames[:, :, 0, :], a.frames[:, :, 0, :])
    assert_close(ref, simd, precision, "all", f"P={points}, seed={seed}")
    for f in range(len(PAPER)):
        if PAPER[f] == "collide":  # the count covers the real strands only, not the padding
            assert b.moved[f] == moved_from_frames(b.frames[f - 1], b.frames[f])


@needs_simd
@pytest.mark.parametrize("isa", ISAS)
@pytest.mark.parametrize("precision", ["fp32", "fp64"])
@pytest.mark.parametrize("points", [3, 33])
def test_each_build_matches_ref(cpu_bin, tmp_path, monkeypatch, isa, precision, points):
    """Both builds (x86-64-v3 and -v4, forced) pass the same rule against ref; the suite's other
    tests run the one this CPU picks."""
    monkeypatch.setenv("HAIRBENCH_SIMD_ISA", isa)
    ref, simd = tmp_path / "ref.h5", tmp_path / "simd.h5"
    args = scene(points, 7, precision, strands=1100)
    run(cpu_bin, *args, "--variant", "ref", "--output", ref, "--quiet")
    rec = run_json(cpu_bin, *args, "--variant", "simd", "--output", simd)
    assert ("-march=x86-64-v4" in rec["flags"]) == (isa == "avx512"), rec["flags"]
    b = State(simd)
    assert_invariants(b)
    assert np.array_equal(b.frames[..., 0], State(ref).frames[..., 0])
    assert_close(ref, simd, precision, "all", f"{isa} P={points}")
    for f in range(len(PAPER)):
        if PAPER[f] == "collide":
            assert b.moved[f] == moved_from_frames(b.frames[f - 1], b.frames[f])


@needs_simd
@pytest.mark.parametrize("value", ["sse2", "AVX2", "avx512 "])
def test_an_unknown_isa_request_is_refused(cpu_bin, tmp_path, monkeypatch, value):
    monkeypatch.setenv("HAIRBENCH_SIMD_ISA", value)
    out = tmp_path / "s.h5"
    p = run(cpu_bin, "--strands", 10, "--points", 8, "--variant", "simd", "--output", out, check=False)
    lines = p.stderr.strip().splitlines()
    assert p.returncode == 2 and len(lines) == 1 and "HAIRBENCH_SIMD_ISA must be avx2 or avx512" in lines[0]
    assert not out.exists() and tmp_leftovers(tmp_path) == []


@needs_simd
@pytest.mark.skipif(NO_V4 is None, reason="this CPU has AVX-512: the refusal of avx512 cannot happen here")
def test_avx512_request_refused_without_it(cpu_bin, monkeypatch):
    monkeypatch.setenv("HAIRBENCH_SIMD_ISA", "avx512")
    p = run(cpu_bin, "--strands", 10, "--points", 8, "--variant", "simd", check=False)
    assert p.returncode == 2 and "needs an x86-64-v4 CPU (AVX-512)" in p.stderr


@needs_simd
@pytest.mark.parametrize("precision", ["fp32", "fp64"])
@pytest.mark.parametrize("points", [2, 3, 16, 64, 251])
@pytest.mark.parametrize("seed", SEEDS)
def test_each_stage_from_the_ref_state_matches_ref(cpu_bin, tmp_path, precision, points, seed):
    """The ref state after frame k goes through --input into simd for stage k+1 only, so
    each stage is compared without the drift of the stages before it."""
    args = scene(points, seed, precision)
    whole = tmp_path / "ref.h5"
    run(cpu_bin, *args, "--output", whole, "--quiet")
    a = State(whole)
    init = tmp_path / "init.h5"
    run(cpu_bin, *args, "--variant", "simd", "--stages", "init", "--output", init, "--quiet")
    assert_close(whole, init, precision, [0], "init")
    for k in range(1, len(PAPER)):
        prefix, one = tmp_path / f"prefix{k}.h5", tmp_path / f"simd{k}.h5"
        run(cpu_bin, *args, "--stages", ",".join(PAPER[:k]), "--output", prefix, "--quiet")
        run(cpu_bin, "--input", prefix, "--variant", "simd", "--stages", PAPER[k], "--output", one, "--quiet")
        b = State(one)
        assert b.frames.shape[0] == k + 1 and np.array_equal(b.frames[:k], a.frames[:k])
        assert_close(whole, one, precision, [k], f"{PAPER[k]} (frame {k}) from the ref state")
        if PAPER[k] == "collide":
            assert_moved_close(b.moved[k], a.moved[k], b.frames[k].shape[0] * points, f"collide (frame {k})")


@needs_simd
@pytest.mark.parametrize("precision", ["fp32", "fp64"])
def test_strong_wind_at_other_angles(cpu_bin, tmp_path, precision):
    """w = 1 at several angles: the wind stage from the ref state matches ref, and whole
    simd runs with repeated wind keep the invariants (see the module comment for why those
    are not compared point for point)."""
    base = [*scene(24, 3, precision), "--wind-strength", 1]
    for angle in (0.0, 1.0, -2.5, 7.0, math.pi / 2, -math.pi / 2, math.pi):
        w = ["--wind-angle", angle]
        prefix, ref, one, whole = (tmp_path / f"{n}{angle}.h5" for n in ("p", "r", "s", "w"))
        run(cpu_bin, *base, *w, "--stages", "init,collide", "--output", prefix, "--quiet")
        run(cpu_bin, "--input", prefix, *w, "--stages", "wind", "--output", ref, "--quiet")
        run(cpu_bin, "--input", prefix, *w, "--stages", "wind", "--variant", "simd", "--output", one, "--quiet")
        assert_close(ref, one, precision, [2], f"wind at psi={angle}")
        run(
            cpu_bin,
            *base,
            *w,
            "--variant",
            "simd",
            "--stages",
            "init,collide,wind,collide,wind,collide",
            "--output",
            whole,
            "--quiet",
        )
        assert_invariants(State(whole))


@needs_simd
@pytest.mark.parametrize("strands", [1, 7, 513])
def test_partial_blocks_match_ref(cpu_bin, tmp_path, strands):
    """Fewer strands than a block, and one more than a block: the padding lanes are never
    read back."""
    for precision in ("fp32", "fp64"):
        ref, simd = tmp_path / f"r{precision}.h5", tmp_path / f"s{precision}.h5"
        args = scene(16, 5, precision, strands=strands)
        run(cpu_bin, *args, "--output", ref, "--quiet")
        run(cpu_bin, *args, "--variant", "simd", "--output", simd, "--quiet")
        a, b = State(ref), State(simd)
        assert b.frames.shape == a.frames.shape
        assert_invariants(b)
        assert_close(ref, simd, precision, "all", f"{strands} strands")


@needs_simd
def test_fp32_simd_agrees_with_fp64_ref(cpu_bin, tmp_path):
    """harness diff's fp32↔fp64 rule (measurements: docs/cpu_simd.md)."""
    a_path, b_path = tmp_path / "fp32.h5", tmp_path / "fp64.h5"
    run(cpu_bin, "--strands", 20000, "--points", 32, "--variant", "simd", "--output", a_path, "--quiet")
    run(cpu_bin, "--strands", 20000, "--points", 32, "--precision", "fp64", "--output", b_path, "--quiet")
    assert_equivalent(a_path, b_path, what="simd fp32 vs ref fp64")


@needs_simd
@settings(
    max_examples=40,
    deadline=None,
    derandomize=True,
    suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow],
)
@given(s=scenes())
def test_each_stage_matches_ref_across_the_scene_space(cpu_bin, tmp_path_factory, s):
    """The stability suite's scene space (tests/cpu/test_stability.py): every stage from the
    ref state matches ref, and whole simd runs keep the invariants. (Measured over 284 of
    its scenes: docs/cpu_simd.md.)"""
    d = tmp_path_factory.mktemp("space")
    args = scene_args(s)
    p = run(cpu_bin, *args, "--output", d / "ref.h5", "--quiet", check=False)
    if p.returncode != 0:  # a scene ref refuses (cleanly: tests/cpu/test_stability.py checks that)
        return
    a = State(d / "ref.h5")
    run(cpu_bin, *args, "--variant", "simd", "--output", d / "simd.h5", "--quiet")
    assert_invariants(State(d / "simd.h5"))
    run(cpu_bin, *args, "--variant", "simd", "--stages", "init", "--output", d / "s0.h5", "--quiet")
    assert_close(d / "ref.h5", d / "s0.h5", a.precision, [0], f"init of {s}")
    wind = ["--wind-strength", repr(s["w"]), "--wind-angle", repr(s["psi"])]
    for k in range(1, len(PAPER)):
        prefix, one = d / f"p{k}.h5", d / f"s{k}.h5"
        run(cpu_bin, *args, "--stages", ",".join(PAPER[:k]), "--output", prefix, "--quiet")
        run(cpu_bin, "--input", prefix, *wind, "--stages", PAPER[k], "--variant", "simd", "--output", one, "--quiet")
        b = State(one)
        if b.skipped[k]:
            assert np.array_equal(b.frames[k], b.frames[k - 1])
        else:
            assert_close(d / "ref.h5", one, a.precision, [k], f"{PAPER[k]} of {s}")


# ---- edge states made by hand (the stability suite's), through --input -------------------


@needs_simd
@pytest.mark.parametrize("precision", ["fp32", "fp64"])
def test_exactly_opposite_segments_turn_through_plus_y(cpu_bin, tmp_path, precision):
    P, ell = 4, 1.0
    toward_face = [(0.0, 0.0, 10.0 + k * ell) for k in range(P)]  # φ = 0, wind ψ = π
    toward_back = [(1.0, 0.0, -math.sqrt(99.0) - k * ell) for k in range(P)]  # φ = π, wind ψ = 0
    src = synthetic.crafted_state(tmp_path / "crafted.h5", [toward_face, toward_back], precision, L=(P - 1) * ell)
    for strand, angle in ((0, math.pi), (1, 0.0)):
        ref, simd = tmp_path / f"r{strand}.h5", tmp_path / f"s{strand}.h5"
        common = ["--input", src, "--stages", "wind", "--wind-strength", 1, "--wind-angle", angle, "--quiet"]
        run(cpu_bin, *common, "--output", ref)
        run(cpu_bin, *common, "--variant", "simd", "--output", simd)
        b = State(simd)
        assert (b.frames[-1, strand, 1:, 1] > 0).all(), b.frames[-1, strand]  # lifted, not pushed down
        assert_close(ref, simd, precision, [-1], f"opposite wind, strand {strand}")


@needs_simd
@pytest.mark.parametrize("precision", ["fp32", "fp64"])
def test_collide_at_the_slice_poles_matches_ref(cpu_bin, tmp_path, precision):
    """Roots at r0 = 0, at θ0 = π and θ0 = −π/2 with points planted inside the shell (the
    d = 0 and zero-length branches of collide as selects)."""
    P, ell = 5, 1.0
    r0_zero = [(10.0, -k * 0.6, -k * 0.8) for k in range(P)]
    back = [(6.0, 0.0, -8.0)] + [(6.0, -0.5 * k, -8.0 + 0.8660254037844386 * k) for k in range(1, P)]
    below = [(6.0, -8.0, 0.0)] + [(6.0, -8.0 + 0.8 * k, 0.6 * k) for k in range(1, P)]
    coincident = [(6.0, -8.0, 0.0), (6.0, -8.0, 0.0)] + [(6.0, -8.0 - k, 0.0) for k in range(1, P - 1)]
    src = synthetic.crafted_state(
        tmp_path / "crafted.h5", [r0_zero, back, below, coincident], precision, L=(P - 1) * ell
    )
    ref, simd = tmp_path / "r.h5", tmp_path / "s.h5"
    run(cpu_bin, "--input", src, "--stages", "collide", "--output", ref, "--quiet")
    run(cpu_bin, "--input", src, "--stages", "collide", "--variant", "simd", "--output", simd, "--quiet")
    a, b = State(ref), State(simd)
    assert np.isfinite(b.frames).all()
    # the hand-made frame breaks the invariants harness diff checks, so the rule of the
    # "simd" pair directly: roots are identical, so u = ε·P·E
    u = tolerances.EPS[precision] * P * tolerances.extent(10.0, 0.1, (P - 1) * ell)
    err = np.abs(b.frames[-1].astype(np.float64) - a.frames[-1].astype(np.float64)).max()
    assert err <= tolerances.named_pair("simd", precision).point_k * u, (err, u)
    assert b.moved[-1] == a.moved[-1] > 0


# ---- bits that must not change -------------------------------------------------------------


@needs_simd
@pytest.mark.parametrize("precision", ["fp32", "fp64"])
def test_thread_count_does_not_change_a_bit(cpu_bin, tmp_path, precision):
    flags = ("--strands", 3001, "--points", 20, "--precision", precision, "--variant", "simd")
    assert_threads_change_no_bit(cpu_bin, tmp_path, *flags)


@needs_simd
def test_repeats_and_warmups_do_not_change_the_result(cpu_bin, tmp_path):
    for precision in ("fp32", "fp64"):
        a, b = tmp_path / f"a{precision}.h5", tmp_path / f"b{precision}.h5"
        args = ["--strands", 700, "--points", 16, "--hair-length", 10, "--precision", precision, "--variant", "simd"]
        run(cpu_bin, *args, "--output", a, "--quiet")
        run(cpu_bin, *args, "--repeat", 4, "--warmup", 2, "--output", b, "--quiet")
        sa, sb = State(a), State(b)
        assert np.array_equal(sa.frames, sb.frames) and list(sa.moved) == list(sb.moved)


@needs_simd
def test_resume_gives_the_same_bits_as_one_run(cpu_bin, tmp_path):
    """load and fetch (canonical ↔ point-major) lose nothing: a run split over files is one run."""
    whole, first, rest = tmp_path / "whole.h5", tmp_path / "first.h5", tmp_path / "rest.h5"
    args = ["--strands", 1100, "--points", 32, "--variant", "simd"]
    run(cpu_bin, *args, "--output", whole, "--quiet")
    run(cpu_bin, *args, "--stages", "init", "--output", first, "--quiet")
    run(cpu_bin, "--input", first, "--variant", "simd", "--stages", "collide,wind,collide", "--output", rest, "--quiet")
    assert np.array_equal(State(whole).frames, State(rest).frames)


@needs_simd
@pytest.mark.parametrize("isa", ISAS)
@pytest.mark.parametrize("precision", ["fp32", "fp64"])
def test_fused_wind_collide_is_the_two_stages_bit_for_bit(cpu_bin, tmp_path, monkeypatch, isa, precision):
    """A wind followed by collide runs as one pass (the record says so); its two frames and
    moved count are those of the stages run apart (a wind that ends the run is not fused),
    in either build."""
    monkeypatch.setenv("HAIRBENCH_SIMD_ISA", isa)
    args = ["--strands", 1100, "--points", 24, "--hair-length", 10, "--precision", precision, "--variant", "simd"]
    fused, apart, rest = tmp_path / "fused.h5", tmp_path / "apart.h5", tmp_path / "rest.h5"
    rec = run_json(cpu_bin, *args, "--output", fused)
    assert [s["fused"] for s in rec["stages"]] == [None, None, "wind+collide", "into-previous"]
    assert rec["stages"][3]["moved_points"] > 0
    run(cpu_bin, *args, "--stages", "init,collide,wind", "--output", apart, "--quiet")
    run(cpu_bin, "--input", apart, "--variant", "simd", "--stages", "collide", "--output", rest, "--quiet")
    a, b = State(fused), State(rest)
    assert np.array_equal(a.frames, b.frames)
    assert list(a.moved)[3] == list(b.moved)[3] == rec["stages"][3]["moved_points"]


@needs_simd
def test_wind_zero_is_not_run_and_changes_nothing(cpu_bin, tmp_path):
    out = tmp_path / "s.h5"
    rec = json.loads(
        run(
            cpu_bin,
            "--strands",
            300,
            "--points",
            16,
            "--hair-length",
            10,
            "--wind-strength",
            0,
            "--variant",
            "simd",
            "--output",
            out,
            "--json",
            "--quiet",
        ).stdout
    )
    wind = rec["stages"][2]
    assert wind["stage"] == "wind" and wind["skipped"] is True and wind["times_ms"] == []
    s = State(out)
    assert s.skipped.tolist() == [0, 0, 1, 0]
    assert np.array_equal(s.frames[2], s.frames[1])
    assert np.array_equal(s.frames[3], s.frames[1])
    assert s.moved[3] == 0


# ---- what the variant records and how it is built ------------------------------------------


@needs_simd
@pytest.mark.parametrize("isa", ISAS)
def test_records_say_simd_and_its_flags(cpu_bin, tmp_path, monkeypatch, isa):
    """The flags of the record and of the file name the build that ran."""
    monkeypatch.setenv("HAIRBENCH_SIMD_ISA", isa)
    out = tmp_path / "s.h5"
    rec = run_json(
        cpu_bin,
        "--strands",
        500,
        "--points",
        16,
        "--hair-length",
        10,
        "--variant",
        "simd",
        "--repeat",
        2,
        "--output",
        out,
    )
    assert rec["backend"] == "cpu" and rec["variant"] == "simd"
    march = {"avx2": "-march=x86-64-v3", "avx512": "-march=x86-64-v4 -mprefer-vector-width=512"}[isa]
    for flag in ("-ffp-contract=off", march, "-fno-math-errno", "-fno-trapping-math"):
        assert flag in rec["flags"], flag
    other = {"avx2": "-march=x86-64-v4", "avx512": "-march=x86-64-v3"}[isa]
    assert other not in rec["flags"]
    assert "-ffast-math" not in rec["flags"]
    assert all(len(s["times_ms"]) == 2 for s in rec["stages"] if s["fused"] != "into-previous")
    s = State(out)
    assert s.params["variant"] == "simd" and s.params["flags"] == rec["flags"]


def object_calls(cpu_bin, name):
    """The functions that build/obj/simd/NAME calls (objdump's relocations); skips where there is
    no such x86-64 object or no objdump, and for a sanitizer build (its loops stay scalar)."""
    obj = Path(cpu_bin).parent / "obj" / "simd" / name
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
    return called


@pytest.mark.parametrize("name, isa", [("model_simd.o", "_ZGVd"), ("model_simd_v4.o", "_ZGVe")])
def test_simd_object_calls_libmvec_and_no_scalar_math(cpu_bin, name, isa):
    """Every sin/cos/asin/atan2 of the simd file is a vector call of its build's width
    (_ZGVd…: AVX2, _ZGVe…: AVX-512); a scalar call (or a sincos, which GCC makes of a sin and
    a cos of one angle) would mean a loop was not vectorised."""
    called = object_calls(cpu_bin, name)
    scalar = {"sinf", "cosf", "asinf", "atan2f", "sin", "cos", "asin", "atan2", "sincosf", "sincos"} & called
    assert not scalar, f"scalar math calls left in {name}: {sorted(scalar)}"
    # fp32's sin and cos are c_ref/paper/fast_trig.h's inline polynomials (docs/cpu_simd.md)
    for f in ("asinf", "atan2f", "sin", "cos", "asin", "atan2"):
        assert any(c.startswith(isa) and c.endswith("_" + f) for c in called), f"no {isa} vector call to {f}"


def test_refused_with_one_clear_line_without_avx2(cpu_bin, tmp_path):
    """HAIRBENCH_SIMD_PRETEND_NO_AVX2=1 takes the path of a CPU without x86-64-v3."""
    out = tmp_path / "s.h5"
    env = dict(os.environ, HAIRBENCH_SIMD_PRETEND_NO_AVX2="1")
    cmd = [cpu_bin, "--strands", 10, "--points", 8, "--hair-length", 5, "--variant", "simd", "--output", out]
    p = subprocess.run([str(a) for a in cmd], capture_output=True, text=True, env=env, timeout=60)
    assert p.returncode != 0
    lines = p.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("hairsim-cpu: error: --variant simd needs an x86-64-v3 CPU")
    assert not out.exists() and tmp_leftovers(tmp_path) == []
    # ref is not affected by it
    run(cpu_bin, "--strands", 10, "--points", 8, "--hair-length", 5, "--output", out, "--quiet", check=True)


@pytest.mark.skipif(NO_SIMD is None, reason="this CPU has x86-64-v3: the real refusal cannot happen here")
def test_refused_on_this_cpu(cpu_bin, tmp_path):
    p = run(cpu_bin, "--strands", 10, "--points", 8, "--hair-length", 5, "--variant", "simd", check=False)
    assert p.returncode != 0 and "needs an x86-64-v3 CPU" in p.stderr


def test_bandwidth_record_has_copy_and_triad(cpu_bin):
    rec = json.loads(run(cpu_bin, "--measure-bandwidth", "--threads", 2, "--json").stdout)
    assert rec["backend"] == "cpu"
    assert rec["bytes"] == 2 * 2**26 * 8 and rec["triad_bytes"] == 3 * 2**26 * 8
    assert rec["copy_gbps"] > 0 and rec["triad_gbps"] > 0 and rec["threads"] == 2
    assert isinstance(rec["device"], str) and rec["device"]
