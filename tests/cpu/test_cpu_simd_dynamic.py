"""The simulate stage of the simd CPU variant (c_ref/simd/dynamics_simd*.{h,c}; docs/cpu_simd.md,
"The dynamic model") against the `ref` oracle (c_ref/dynamic/dynamics_impl.h).

simd computes the model with free arithmetic (reciprocal square roots, reciprocals of the
constant denominators), so it is judged as the GPU normal build is: one frame advanced from
the same input, compared with ref's next frame by harness.check.diff_dynamic.compare (the one-frame
rule DYN_STEP_K of harness/core/tolerances.py on positions and h·|Δv|, the observables within
what the states' difference allows, each file's invariants). ref writes a few frames with
--velocities all; simd steps from its last paper frame (velocities zero) and from its last
simulated frame but one. Every feature set, both solvers, fp32 and fp64.

Both variants start from the same ref `init,collide` state (--input): simd's own paper
stages differ from ref's by their libmvec rounding (tests/cpu/test_cpu_simd.py covers those).
N = 300 and 1000 are not multiples of the blocks (512/256 strands, 256 per dynamic block).
"""

import numpy as np
import pytest
from test_cpu_simd import ISAS, needs_simd, object_calls

from harness.check import diff_dynamic as dyndiff
from harness.core.paths import ROOT
from harness.io.trajectory import open_trajectory
from support.statecheck import run

STRANDS = 300
FRAMES = 10
REF_FRAMES = 3
GUST = ["--wind-speed", 300, "--drag", 1, "--gust-amplitude", 0.8, "--gust-frequency", 3, "--gust-wavelength", 20]
# feature sets (docs/model.md §3.9): none, each alone (wind needs a drag, so it comes with
# one; gust needs wind), all but the gusts, all
FEATURES = {
    "none": ["--no-collider"],
    "bend": ["--no-collider", "--bend-compliance", 1e-6],
    "shape": ["--no-collider", "--shape-compliance", 1e-5, "--shape-range", 0.7],
    "wind+drag": ["--no-collider", "--wind-speed", 300, "--drag", 1],
    "gust": GUST,
    "motion": ["--no-collider", "--head-motion", "nod", "--motion-amplitude", 0.5],
    "collide": ["--collision-margin", 0.3],
    "drag": ["--no-collider", "--damping", 2],
    "stretch-compliance": ["--no-collider", "--stretch-compliance", 1e-7],
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
FEATURES["all"] = ALL
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


def simulate(cpu_bin, inp, out, variant, *args, frames=FRAMES, input_frame=None):
    """`frames` frames of `variant` from the last frame of inp (or its frame input_frame); out."""
    run(
        cpu_bin,
        "--input",
        inp,
        *(("--input-frame", input_frame) if input_frame is not None else ()),
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
    """positions [F][N][P][3], velocities, observables."""
    with open_trajectory(path) as s:
        pos = np.stack([s.frame(f) for f in range(s.n_frames)])
        vel = np.stack([s.velocity(i) for i in range(len(s.velocity_steps))])
        obs = {k: s.observables[k].to_numpy() for k in s.observables.columns if k not in ("step", "time")}
        assert s.stages[-1] == "simulate"
        return pos, vel, obs


def assert_same_bits(a, b, what):
    pa, va, oa = read(a)
    pb, vb, ob = read(b)
    assert pa.shape == pb.shape and pa.dtype == pb.dtype, what
    for f in range(len(pa)):
        bad = int((pa[f] != pb[f]).any(axis=2).any(axis=1).sum())
        assert bad == 0, f"{what}: frame {f}: {bad} strands differ; max |Δ| {np.abs(pa[f] - pb[f]).max():.3g}"
    assert np.array_equal(va, vb), f"{what}: velocities differ (max |Δ| {np.abs(va - vb).max():.3g})"
    assert oa.keys() == ob.keys()
    for k in oa:
        assert np.array_equal(oa[k], ob[k]), f"{what}: observable {k} differs: {oa[k]} vs {ob[k]}"


def assert_one_frame_rule(cpu_bin, inp, tmp_path, what, args, frames=REF_FRAMES, ref_args=()):
    """ref runs `frames` frames (with ref_args too: what a resumed run takes from its file, e.g.
    --colliders); simd steps one frame from two of them; each is judged by harness.dyndiff.compare
    against ref's next frame. Returns the worst max/u seen."""
    ref = simulate(cpu_bin, inp, tmp_path / "ref.h5", "ref", *args, *ref_args, "--velocities", "all", frames=frames)
    with open_trajectory(ref) as t:
        cand = dyndiff.step_candidates(t)
        steps = {k: int(t.step[k + 1]) for k in cand}
    assert len(cand) == frames, f"{what}: frames to step from: {cand}"
    worst = 0.0
    for k in (cand[0], cand[-2]):
        out = tmp_path / f"simd_{k}.h5"
        simulate(cpu_bin, ref, out, "simd", *args, "--velocities", "all", frames=1, input_frame=k)
        r = dyndiff.compare(ref, out, frames=[steps[k]], check_paper=False)
        f = r.frames[0]
        assert getattr(f, "velocity_compared", False), f"{what}: velocities of step {steps[k]} not compared"
        assert r.equivalent, f"{what}, from frame {k}: " + "; ".join(r.failures()[:5])
        worst = max(worst, f.max_k)
    return worst


@needs_simd
@pytest.mark.parametrize("precision", ["fp32", "fp64"])
@pytest.mark.parametrize("solver", ["xpbd", "ftl"])
@pytest.mark.parametrize("features", list(FEATURES))
def test_one_frame_within_the_rule(cpu_bin, inputs, tmp_path, precision, solver, features):
    points = 33 if features != "none" else 16
    inp = inputs(precision, points)
    assert_one_frame_rule(
        cpu_bin, inp, tmp_path, f"{precision} {solver} {features}", ["--solver", solver, *FEATURES[features]]
    )


@needs_simd
@pytest.mark.parametrize("isa", ISAS)
@pytest.mark.parametrize("precision", ["fp32", "fp64"])
@pytest.mark.parametrize("solver", ["xpbd", "ftl"])
def test_each_build_within_the_rule(cpu_bin, inputs, tmp_path, monkeypatch, isa, precision, solver):
    """Both builds (x86-64-v3 and -v4, forced), every feature: the suite's other tests run the
    one this CPU picks."""
    monkeypatch.setenv("HAIRBENCH_SIMD_ISA", isa)
    inp = inputs(precision, 33)
    assert_one_frame_rule(cpu_bin, inp, tmp_path, f"{isa} {precision} {solver}", ["--solver", solver, *ALL])


@needs_simd
@pytest.mark.parametrize("precision", ["fp32", "fp64"])
@pytest.mark.parametrize("points", [2, 3, 16])
def test_short_strands_within_the_rule(cpu_bin, inputs, tmp_path, precision, points):
    """P = 2 (no bend constraint), 3 (one), 16; every feature, both solvers."""
    inp = inputs(precision, points)
    for solver in ("xpbd", "ftl"):
        assert_one_frame_rule(cpu_bin, inp, tmp_path, f"{precision} P={points} {solver}", ["--solver", solver, *ALL])


@needs_simd
def test_a_wrong_frame_fails_the_rule(cpu_bin, inputs, tmp_path):
    """The judge is not vacuous: simd's frame with one point moved by 1e-3 cm (about 35
    units ε·E·S·I here, the rule allows 4) is over."""
    import h5py

    ref = simulate(cpu_bin, inputs("fp32", 16), tmp_path / "ref.h5", "ref", "--velocities", "all", frames=REF_FRAMES)
    out = tmp_path / "moved.h5"
    run(
        cpu_bin,
        *("--input", ref, "--input-frame", 2, "--stages", "simulate", "--frames", 1, "--variant", "simd", *SOLVE),
        *("--velocities", "all", "--output", out, "--force", "--quiet"),
    )
    with open_trajectory(ref) as t:
        step = int(t.step[3])
    assert dyndiff.compare(ref, out, frames=[step], check_paper=False).equivalent
    with h5py.File(out, "r+") as f:
        f["particles/hair/position/value"][-1, 5 * 16 + 10, 1] += np.float32(1e-3)
    r = dyndiff.compare(ref, out, frames=[step], check_paper=False)
    assert not r.equivalent and any("1 point(s) over tolerance" in m for m in r.failures()), r.failures()


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


# §3.16 the hair–hair grid (friction and volume), which simd takes the reference's way (docs/cpu_simd.md)
GRID = ["--grid", 16, "--grid-friction", "0.05,0.01", "--grid-volume", 2000]


@needs_simd
@pytest.mark.parametrize("precision", ["fp32", "fp64"])
@pytest.mark.parametrize("solver", ["xpbd", "ftl"])
@pytest.mark.parametrize("rebuild", ["frame", "substep", "held"])
def test_the_grid_within_the_rule(cpu_bin, inputs, tmp_path, precision, solver, rebuild):
    """Every feature and the grid at each rebuild: one frame of simd within the rule of ref's."""
    inp = inputs(precision, 33)
    args = ["--solver", solver, *ALL, *GRID, "--grid-rebuild", rebuild]
    assert_one_frame_rule(cpu_bin, inp, tmp_path, f"{precision} {solver} grid {rebuild}", args)


@needs_simd
@pytest.mark.parametrize("rebuild", ["substep", "held"])
def test_the_grid_gives_the_same_bits_on_any_thread_count(cpu_bin, inputs, tmp_path, rebuild):
    """The grid's integer sums from the point-major rows: --threads 1/2/3 give the same bits."""
    inp = inputs("fp32", 16, 1000)
    args = ["--solver", "xpbd", *ALL, *GRID, "--grid-rebuild", rebuild, "--velocities", "all"]
    one = simulate(cpu_bin, inp, tmp_path / "t1.h5", "simd", *args, "--threads", 1, frames=4)
    for extra in (["--threads", 2], ["--threads", 3]):
        other = simulate(cpu_bin, inp, tmp_path / "tn.h5", "simd", *args, *extra, frames=4)
        assert_same_bits(one, other, f"grid {rebuild} {extra}")


def assert_moves_like_ref(cpu_bin, inp, tmp_path, world, floor):
    """`world` is applied, not only accepted: simd's frames with it differ from without it by what
    ref's do (ref's effect above `floor` cm)."""
    args = ["--solver", "xpbd", *ALL, "--velocities", "all"]
    runs = {
        (v, w): read(simulate(cpu_bin, inp, tmp_path / f"{v}{w}.h5", v, *args, *(world if w else []), frames=3))[0]
        for v in ("ref", "simd")
        for w in (0, 1)
    }
    effect_ref = np.abs(runs["ref", 1] - runs["ref", 0]).max()
    effect_simd = np.abs(runs["simd", 1] - runs["simd", 0]).max()
    assert effect_ref > floor, effect_ref
    assert abs(effect_simd - effect_ref) < 1e-6 * effect_ref, (effect_simd, effect_ref)


@needs_simd
def test_the_grid_moves_the_hair(cpu_bin, inputs, tmp_path):
    assert_moves_like_ref(cpu_bin, inputs("fp64", 16), tmp_path, GRID, 1e-3)


# §3.17 the default body (capsules and a head-mesh SDF) with friction and a bounded depenetration
COLLIDERS = ["--colliders", ROOT / "configs" / "bodies" / "default.colliders"]  # a resumed run keeps its file's
BODY = ["--friction", "0.3,0.2"]
BODIES = {
    "body": [*BODY, "--depenetration-speed", 200],
    "body-unbounded": BODY,
    "body-sway": [*BODY, "--depenetration-speed", 200, "--body-motion", "sway", "--body-amplitude", 3],
    "head-friction": ["--friction", "0.4,0.3"],  # no --colliders: the head sphere's friction alone
    "body-and-grid": [*BODY, "--depenetration-speed", 200, *GRID, "--grid-rebuild", "held"],
    # §3.17 the collision step in sweeps: with the head sphere's friction and the bound, and with its
    # plain projection (which simd then takes inside the sweep, not collide_lanes')
    "body-sweeps": [*BODY, "--depenetration-speed", 200, "--collider-sweeps", 4],
    "body-plain-sweeps": ["--collider-sweeps", 4],
    # §3.17 the colliders as contact planes found once a frame; with the grid built every substep the
    # frame runs a substep at a time, and each point's planes are carried between the calls. Both with
    # the bound: without it a few fp64 points end 2e-13 cm over the rule from friction's stick–slip
    # choice, with the exact colliders as with planes (measured with the grid built every substep)
    "body-planes": [*BODY, "--depenetration-speed", 200, "--contact-planes", 5],
}
BODIES["body-planes-substep"] = [*BODIES["body-planes"], *GRID, "--grid-rebuild", "substep"]


@needs_simd
@pytest.mark.parametrize("precision", ["fp32", "fp64"])
@pytest.mark.parametrize("solver", ["xpbd", "ftl"])
@pytest.mark.parametrize("body", list(BODIES))
def test_the_colliders_within_the_rule(cpu_bin, inputs, tmp_path, precision, solver, body):
    """Every feature, the head nodding, and the body's colliders: one frame of simd within the rule
    of ref's (the observables' penetration among them)."""
    inp = inputs(precision, 33)
    args = ["--solver", solver, *ALL, *BODIES[body]]
    cols = COLLIDERS if body != "head-friction" else []
    assert_one_frame_rule(cpu_bin, inp, tmp_path, f"{precision} {solver} {body}", args, ref_args=cols)


# --collide-once (docs/model.md §3.6, xpbd alone): the collision step in a substep's last iteration alone,
# with the exact colliders, and with the planes and the grid built every substep (a substep a call)
ONCE = {
    "body-once": [*BODIES["body"], "--collide-once"],
    "body-planes-substep-once": [*BODIES["body-planes-substep"], "--collide-once"],
}


@needs_simd
@pytest.mark.parametrize("precision", ["fp32", "fp64"])
@pytest.mark.parametrize("body", list(ONCE))
def test_colliding_once_within_the_rule(cpu_bin, inputs, tmp_path, precision, body):
    args = ["--solver", "xpbd", *ALL, *ONCE[body]]
    assert_one_frame_rule(cpu_bin, inputs(precision, 33), tmp_path, f"{precision} {body}", args, ref_args=COLLIDERS)


@needs_simd
def test_the_colliders_move_the_hair(cpu_bin, inputs, tmp_path):
    assert_moves_like_ref(cpu_bin, inputs("fp64", 16), tmp_path, [*COLLIDERS, *BODIES["body"]], 1e-2)


@needs_simd
@pytest.mark.parametrize("body", ["body-sweeps", "body-plain-sweeps"])
def test_the_sweeps_move_the_hair_as_refs_do(cpu_bin, inputs, tmp_path, body):
    """4 sweeps against 1 on the default body (its shoulders overlap its neck): simd's frames move by
    what ref's do (the sweeps are the reference's own hb_collide_sweeps in both)."""
    inp = inputs("fp64", 16)
    args = ["--solver", "xpbd", *ALL, *COLLIDERS, *BODIES[body], "--velocities", "all"]
    runs = {
        (v, n): read(simulate(cpu_bin, inp, tmp_path / f"{v}{n}.h5", v, *args, "--collider-sweeps", n, frames=3))[0]
        for v in ("ref", "simd")
        for n in (1, 4)
    }
    effect_ref = np.abs(runs["ref", 4] - runs["ref", 1]).max()
    effect_simd = np.abs(runs["simd", 4] - runs["simd", 1]).max()
    assert effect_ref > 1e-3, effect_ref
    assert abs(effect_simd - effect_ref) < 1e-6 * effect_ref, (effect_simd, effect_ref)


@needs_simd
@pytest.mark.parametrize("body", ["body-sway", "body-planes"])
def test_the_colliders_give_the_same_bits_on_any_thread_count(cpu_bin, inputs, tmp_path, body):
    inp = inputs("fp32", 16, 1000)
    args = ["--solver", "xpbd", *ALL, *COLLIDERS, *BODIES[body], "--velocities", "all"]
    one = simulate(cpu_bin, inp, tmp_path / "t1.h5", "simd", *args, "--threads", 1, frames=4)
    other = simulate(cpu_bin, inp, tmp_path / "t3.h5", "simd", *args, "--threads", 3, frames=4)
    assert_same_bits(one, other, f"{body} --threads 3")


@needs_simd
def test_the_contact_planes_move_the_hair_as_refs_do(cpu_bin, inputs, tmp_path):
    """Planes against the exact colliders on the default body: simd's frames move by what ref's do
    (the planes are the reference's own hb_contact_find, carry and hb_collide_sweeps in both)."""
    inp = inputs("fp64", 16)
    args = ["--solver", "xpbd", *ALL, *COLLIDERS, *BODIES["body"], "--velocities", "all"]
    runs = {
        (v, planes): read(
            simulate(cpu_bin, inp, tmp_path / f"{v}{planes}.h5", v, *args, *(["--contact-planes", 5] if planes else []),
                     frames=3)
        )[0]
        for v in ("ref", "simd")
        for planes in (False, True)
    }  # fmt: skip
    effect_ref = np.abs(runs["ref", True] - runs["ref", False]).max()
    effect_simd = np.abs(runs["simd", True] - runs["simd", False]).max()
    assert effect_ref > 1e-3, effect_ref
    assert abs(effect_simd - effect_ref) < 1e-6 * effect_ref, (effect_simd, effect_ref)


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
    mid = simulate(cpu_bin, whole, tmp_path / "mid.h5", "simd", *args, frames=7, input_frame=4)
    pm, vm = read(mid)[:2]
    assert np.array_equal(pw[-1], pm[-1]) and np.array_equal(vw[-1], vm[-1])


@pytest.mark.parametrize("name, isa", [("dynamics_simd.o", "_ZGVd"), ("dynamics_simd_v4.o", "_ZGVe")])
def test_dynamics_simd_object_calls_only_the_vector_sine(cpu_bin, name, isa):
    """The gust sine of each build of dynamics_simd.c is libmvec's at its width (_ZGVd…: AVX2,
    _ZGVe…: AVX-512); a scalar sin would mean the velocity loop was not vectorised."""
    called = object_calls(cpu_bin, name)
    assert not {"sinf", "sin", "sqrtf", "sqrt", "sincosf", "sincos"} & called, sorted(called)
    for f in ("sinf", "sin"):
        assert any(c.startswith(isa) and c.endswith("_" + f) for c in called), f"no {isa} vector call to {f}"


@needs_simd
def test_simd_lists_simulate(cpu_bin):
    import json

    listing = json.loads(run(cpu_bin, "--list-variants").stdout)
    simd = [v for v in listing["variants"] if v["name"] == "simd"][0]
    assert "simulate" in simd["stages"]
