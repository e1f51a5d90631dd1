"""The dynamic model's C reference (docs/model.md §3): invariants on every frame, declared
features at zero strength, determinism (threads, resume, frame split), fp32 against fp64,
--output-every, observables, and `harness stepdiff`. Files are read only through the
harness (harness/io/trajectory.py, invariants_dynamic.py, diff_dynamic.py); every tolerance comes from
harness/core/tolerances.py. Small sizes: 64 strands × 16 points, ≤ 20 frames."""

import json

import numpy as np
import pytest

from harness.check import diff_dynamic, invariants_dynamic
from harness.cli.main import main as harness_main
from harness.core import runner, tolerances
from harness.io.trajectory import open_trajectory
from support.statecheck import run

SMALL = ["--strands", "64", "--points", "16"]
SIM = ["--stages", "init,collide,simulate"]
# every feature on (S = I = 2 keeps the runs short)
FULL = [
    "--substeps",
    "2",
    "--iterations",
    "2",
    "--bend-compliance",
    "1e-6",
    "--shape-compliance",
    "1e-4",
    "--shape-range",
    "0.5",
    "--drag",
    "0.5",
    "--damping",
    "0.5",
    "--wind-speed",
    "150",
    "--gust-amplitude",
    "0.5",
    "--gust-wavelength",
    "60",
    "--head-motion",
    "nod",
]
SOLVERS = ["xpbd", "ftl"]
PRECISIONS = ["fp32", "fp64"]


def simulate(cpu_bin, path, *args, frames=20):
    run(cpu_bin, *SIM, *SMALL, "--frames", frames, *args, "--output", path, "--quiet")
    return path


def same_bits(a, b, velocities=True):
    """Every common step bit-identical (harness diff --exact), and the last velocities too."""
    res = diff_dynamic.compare(a, b, exact=True)
    if not res.equivalent:
        return False
    if velocities:
        with open_trajectory(a) as ta, open_trajectory(b) as tb:
            if not np.array_equal(ta.velocity(-1).view(np.uint8), tb.velocity(-1).view(np.uint8)):
                return False
    return True


def features(path):
    with open_trajectory(path) as t:
        return set(t.features.split("+"))


def check_ok(path):
    with open_trajectory(path) as t:
        rep = invariants_dynamic.check(t)
    assert rep.ok, "; ".join(v.message for v in rep.all_violations()[:5])
    return rep


# ---- invariants ---------------------------------------------------------------------------


@pytest.mark.parametrize("precision", PRECISIONS)
@pytest.mark.parametrize("solver", SOLVERS)
@pytest.mark.parametrize("collider", [True, False], ids=["collider", "no-collider"])
def test_invariants_on_every_frame(cpu_bin, tmp_path, solver, precision, collider):
    """No NaN/Inf; roots bit-exactly at Q(t)·X̄0; no point inside the collider after a
    frame (collider on); ftl segments of length ℓ to rounding where the collider did not
    move them (every segment without the collider); observables agree with the positions."""
    out = simulate(
        cpu_bin,
        tmp_path / "s.h5",
        *FULL,
        "--solver",
        solver,
        "--precision",
        precision,
        "--velocities",
        "all",
        *([] if collider else ["--no-collider"]),
    )
    rep = check_ok(out)
    assert rep.worst_root == 0
    with open_trajectory(out) as t:
        assert t.is_dynamic and len(t.simulated) == 20 and t.head_motion == "nod"
        assert ("collide" in t.features) == collider
        # the roots really move (nod), so the root check compares against a moving target
        assert not np.array_equal(t.frame(-1)[:, 0, :], t.rest[:, 0, :])


@pytest.mark.parametrize("motion", ["shake", "tilt"])
def test_roots_follow_every_motion(cpu_bin, tmp_path, motion):
    out = simulate(
        cpu_bin,
        tmp_path / "s.h5",
        "--head-motion",
        motion,
        "--motion-amplitude",
        "0.7",
        "--solver",
        "ftl",
        "--precision",
        "fp64",
        frames=8,
    )
    check_ok(out)


def test_the_checks_can_fail(cpu_bin, tmp_path):
    """A root moved by one ULP, a point pushed into the head, and a stretch_max that
    disagrees with the positions are each reported (hand-damaged copies of a good file)."""
    import h5py

    good = simulate(
        cpu_bin, tmp_path / "good.h5", *FULL, "--solver", "ftl", "--precision", "fp64", "--no-collider", frames=4
    )
    check_ok(good)
    cases = {
        "roots": lambda f: _nudge(f, 0, 0),
        "ftl_segments": lambda f: _nudge(f, 5, 2, 1e-6),
        "observables": lambda f: f["observables/stretch_max/value"].__setitem__(1, 0.5),
    }
    for name, damage in cases.items():
        bad = tmp_path / f"{name}.h5"
        bad.write_bytes(good.read_bytes())
        with h5py.File(bad, "r+") as f:
            damage(f)
        with open_trajectory(bad) as t:
            rep = invariants_dynamic.check(t)
        assert name in {v.invariant for v in rep.violations}, [v.message for v in rep.violations]


def _nudge(f, strand_point, coord, by=None):
    v = f["particles/hair/position/value"]
    a = v[-1]
    x = a[strand_point, coord]
    a[strand_point, coord] = np.nextafter(x, np.inf) if by is None else x + by
    v[-1] = a


def test_penetration_is_reported(cpu_bin, tmp_path):
    import h5py

    good = simulate(cpu_bin, tmp_path / "good.h5", "--precision", "fp64", frames=2)
    bad = tmp_path / "bad.h5"
    bad.write_bytes(good.read_bytes())
    with h5py.File(bad, "r+") as f:
        v = f["particles/hair/position/value"]
        a = v[-1]
        a[3] = a[0] * 0.5  # point 3 of strand 0 halfway to the head's centre
        v[-1] = a
    with open_trajectory(bad) as t:
        kinds = {v.invariant for v in invariants_dynamic.check(t).violations}
    assert "collider" in kinds


def test_blown_up_run_is_detected_and_matches_the_observables(cpu_bin, tmp_path):
    """xpbd with S = I = 1 and no damping at 32 points blows up (measured: every strand by
    frame 60); the run still writes its file and record, flags the blow-up in its exit status
    (5) and its record's "blown_up", and the harness's own count from positions and velocities
    equals the file's."""
    out = tmp_path / "b.h5"
    size = ("--strands", 64, "--points", 32, "--frames", 30)
    p = run(cpu_bin, *SIM, *size, "--velocities", "all", "--output", out, "--json", "--quiet", check=False)
    assert p.returncode == runner.EXIT_BLOWN_UP, p.stderr
    assert json.loads(p.stdout)["blown_up"] is True
    with open_trajectory(out) as t:
        assert t.observables["blown_up"].any()
        rep = invariants_dynamic.check(t)
        assert not [v for v in rep.violations if v.invariant == "observables"]
        last = t.frame(-1)
        assert invariants_dynamic.observe(t, last, t.velocity(-1))[3] == int(t.observables["blown_up_strands"].iloc[-1])


# ---- a declared feature at zero strength ----------------------------------------------------

ZERO_CASES = [
    # (name, zero-strength flags, undeclared flags, features differ?, a non-zero variant)
    (
        "wind_speed_0",
        ["--drag", "0.5", "--wind-speed", "0"],
        ["--drag", "0.5"],
        False,
        ["--drag", "0.5", "--wind-speed", "150"],
    ),
    (
        "gust_amplitude_0",
        ["--drag", "0.5", "--wind-speed", "150", "--gust-amplitude", "0"],
        ["--drag", "0.5", "--wind-speed", "150"],
        False,
        ["--drag", "0.5", "--wind-speed", "150", "--gust-amplitude", "0.5"],
    ),
    ("motion_amplitude_0", ["--head-motion", "nod", "--motion-amplitude", "0"], [], True, ["--head-motion", "nod"]),
    ("damping_0", ["--damping", "0"], [], True, ["--damping", "0.5"]),
    (
        "shape_range_K0",
        ["--shape-compliance", "1e-4", "--shape-range", "0.01"],
        [],
        True,
        ["--shape-compliance", "1e-4"],
    ),
]


@pytest.mark.parametrize("solver", SOLVERS)
@pytest.mark.parametrize("name,zero,undeclared,declared,live", ZERO_CASES, ids=[c[0] for c in ZERO_CASES])
def test_zero_strength_gives_the_bits_of_undeclared(cpu_bin, tmp_path, solver, name, zero, undeclared, declared, live):
    """wind U = 0 and gust A_g = 0: the rule (§3.9) evaluates no wind / no sine, so the two
    runs execute the same code (the features attribute is the same, asserted): the test is
    that the switch really leaves it out. nod with A = 0, --damping 0 and a shape range
    giving K = 0: the feature is declared (features differ, asserted) and its code runs
    with a nil effect (identity rotation, divide by 1, an empty shape loop), which must not
    change a bit. Each case also runs the feature at non-zero strength and requires that
    to differ, so the comparison is live."""
    common = ["--solver", solver, "--precision", "fp32", "--substeps", "2"]
    a = simulate(cpu_bin, tmp_path / "zero.h5", *common, *zero, frames=10)
    b = simulate(cpu_bin, tmp_path / "none.h5", *common, *undeclared, frames=10)
    c = simulate(cpu_bin, tmp_path / "live.h5", *common, *live, frames=10)
    assert (features(a) != features(b)) == declared, (features(a), features(b))
    assert same_bits(a, b)
    assert not same_bits(a, c)


# ---- determinism ---------------------------------------------------------------------------


@pytest.mark.parametrize("precision", PRECISIONS)
@pytest.mark.parametrize("solver", SOLVERS)
def test_thread_count_does_not_change_a_bit(cpu_bin, tmp_path, solver, precision):
    paths = [
        simulate(
            cpu_bin,
            tmp_path / f"t{n}.h5",
            *FULL,
            "--solver",
            solver,
            "--precision",
            precision,
            "--threads",
            n,
            frames=10,
        )
        for n in (1, 2, 3)
    ]
    for p in paths[1:]:
        assert same_bits(paths[0], p)
        with open_trajectory(paths[0]) as a, open_trajectory(p) as b:
            assert a.observables.equals(b.observables)


@pytest.mark.parametrize("solver", SOLVERS)
def test_resume_gives_the_bits_of_one_run(cpu_bin, tmp_path, solver):
    """10 frames in one run = 6 frames, then 4 resumed from the file's last frame = 4
    resumed from frame 6 (--input-frame) of a 10-frame file written with --velocities all."""
    args = [*FULL, "--solver", solver, "--precision", "fp64"]
    whole = simulate(cpu_bin, tmp_path / "whole.h5", *args, "--velocities", "all", frames=10)
    first = simulate(cpu_bin, tmp_path / "first.h5", *args, frames=6)
    rest = tmp_path / "rest.h5"
    run(cpu_bin, "--input", first, "--stages", "simulate", "--frames", 4, "--output", rest, "--quiet")
    assert same_bits(whole, rest)
    with open_trajectory(whole) as t:
        k = t.frame_at_step(t.paper_frames - 1 + 6)
    mid = tmp_path / "mid.h5"
    run(
        cpu_bin, "--input", whole, "--input-frame", k, "--stages", "simulate", "--frames", 4, "--output", mid, "--quiet"
    )
    assert same_bits(whole, mid)
    with open_trajectory(whole) as a, open_trajectory(rest) as b:
        assert np.array_equal(a.step, b.step) and np.array_equal(a.time, b.time)
        assert a.observables.equals(b.observables)


@pytest.mark.parametrize("solver", SOLVERS)
def test_frame_split_does_not_change_a_bit(cpu_bin, tmp_path, solver):
    """Δt = 1/30 with S = 2 and Δt = 1/60 with S = 1 run the same substeps (times come from
    the global substep index, §3.4): equal bits at the common times t = k/30."""
    args = [
        "--solver",
        solver,
        "--precision",
        "fp32",
        "--head-motion",
        "shake",
        "--drag",
        "0.5",
        "--wind-speed",
        "150",
        "--gust-amplitude",
        "0.5",
        "--bend-compliance",
        "1e-6",
    ]
    a = simulate(cpu_bin, tmp_path / "a.h5", *args, "--frame-dt", repr(1 / 30), "--substeps", 2, frames=6)
    b = simulate(cpu_bin, tmp_path / "b.h5", *args, "--frame-dt", repr(1 / 60), "--substeps", 1, frames=12)
    with open_trajectory(a) as ta, open_trajectory(b) as tb:
        sa, sb = ta.simulated, tb.simulated
        assert len(sa) == 6 and len(sb) == 12
        for i, f in enumerate(sa):
            g = sb[2 * i + 1]
            assert ta.time[f] == tb.time[g]  # k·fl(1/30) = 2k·fl(1/60) exactly
            assert np.array_equal(ta.frame(f), tb.frame(g))
        assert np.array_equal(ta.velocity(-1), tb.velocity(-1))


@pytest.mark.parametrize("solver", SOLVERS)
def test_fp32_agrees_with_fp64_over_a_short_horizon(cpu_bin, tmp_path, solver):
    n = tolerances.DYN_FP32_VS_FP64_FRAMES
    a = simulate(cpu_bin, tmp_path / "a.h5", *FULL, "--solver", solver, "--precision", "fp32", frames=n)
    b = simulate(cpu_bin, tmp_path / "b.h5", *FULL, "--solver", solver, "--precision", "fp64", frames=n)
    res = diff_dynamic.compare(a, b)
    sims = [f for f in res.frames if f.stage == "simulate"]
    assert len(sims) == n and all(f.nonfinite == 0 for f in sims)
    worst = max(f.max_rel_L for f in sims)
    assert 0 < worst <= tolerances.DYN_FP32_VS_FP64_REL_L, worst


def test_output_every_writes_every_kth_frame_and_the_last(cpu_bin, tmp_path):
    every = simulate(cpu_bin, tmp_path / "k.h5", *FULL, "--output-every", 3, frames=10)
    whole = simulate(cpu_bin, tmp_path / "w.h5", *FULL, frames=10)
    with open_trajectory(every) as t:
        assert [t.simulated_index(f) for f in t.simulated] == [3, 6, 9, 10]
        assert len(t.observables) == 10  # observables for every frame, written or not
        assert list(t.velocity_steps) == [t.step[-1]]
    res = diff_dynamic.compare(whole, every, exact=True)  # compared at the common steps
    assert res.equivalent and len([f for f in res.frames if f.stage == "simulate"]) == 4
    check_ok(every)


@pytest.mark.parametrize("solver", SOLVERS)
def test_observables_agree_with_positions(cpu_bin, tmp_path, solver):
    out = simulate(
        cpu_bin, tmp_path / "s.h5", *FULL, "--solver", solver, "--precision", "fp32", "--velocities", "all", frames=10
    )
    with open_trajectory(out) as t:
        obs = t.observables.set_index("step")
        for f in t.simulated:
            stretch, pen, ke, blown = invariants_dynamic.observe(t, t.frame(f), t.velocity_at_step(int(t.step[f])))
            row = obs.loc[int(t.step[f])]
            assert stretch == row["stretch_max"] and pen == row["penetration_max"]
            assert blown == row["blown_up_strands"] == 0
            assert abs(ke - row["kinetic_energy"]) <= tolerances.DYN_KINETIC_REL * ke
            assert stretch > 0 and ke > 0


# ---- harness diff and stepdiff on dynamic files -----------------------------------------------


@pytest.fixture(scope="module")
def reference(cpu_bin, tmp_path_factory):
    d = tmp_path_factory.mktemp("stepdiff")
    out = {}
    for precision in PRECISIONS:
        out[precision] = d / f"ref_{precision}.h5"
        run(
            cpu_bin,
            *SIM,
            *SMALL,
            "--frames",
            6,
            *FULL,
            "--precision",
            precision,
            "--velocities",
            "all",
            "--output",
            out[precision],
            "--quiet",
        )
    return out


def test_diff_of_dynamic_files(reference, capsys):
    assert harness_main(["diff", str(reference["fp64"]), str(reference["fp64"])]) == 0
    text = capsys.readouterr().out
    assert "observables (A, B, B − A)" in text and "simulate" in text


def test_diff_of_dynamic_files_with_other_physics_fails(cpu_bin, reference, tmp_path, capsys):
    other = simulate(
        cpu_bin, tmp_path / "g.h5", *FULL, "--gravity", "900", "--precision", "fp64", "--velocities", "all", frames=6
    )
    assert harness_main(["diff", str(reference["fp64"]), str(other)]) == 1
    text = capsys.readouterr().out
    assert "note: parameters differ: gravity" in text and "NOT EQUIVALENT" in text
    small = simulate(cpu_bin, tmp_path / "n.h5", "--strands", "65", frames=2)
    assert harness_main(["diff", str(reference["fp64"]), str(small)]) == 2


def test_diff_refuses_other_solvers_and_other_frame_counts(cpu_bin, reference, tmp_path, capsys):
    """As the paper model: files that cannot be compared exit 2 with one line naming why."""
    fp64 = str(reference["fp64"])
    common = [*FULL, "--precision", "fp64", "--velocities", "all"]
    ftl = simulate(cpu_bin, tmp_path / "ftl.h5", *common, "--solver", "ftl", frames=4)
    shorter = simulate(cpu_bin, tmp_path / "short.h5", *common, frames=4)
    for other, why in ((ftl, "different solvers: A is xpbd, B is ftl"), (shorter, "frame counts differ")):
        capsys.readouterr()
        assert harness_main(["diff", fp64, str(other)]) == 2
        err = capsys.readouterr().err
        assert why in err and err.count("\n") == 1 and err.startswith("harness: error: cannot compare:")
    # a part of the shorter run is still comparable
    assert harness_main(["diff", fp64, str(shorter), "--frames", "last"]) == 0
    assert harness_main(["diff", fp64, str(shorter), "--frame", "3"]) == 0


def _stepdiff(reference, cpu_bin, *args):
    """`harness stepdiff` of reference against cpu_bin with args; its exit status."""
    return harness_main(["stepdiff", "--reference", str(reference), "--binary", str(cpu_bin), *args])


def test_stepdiff_frame_ranges_refuse_what_cannot_be_stepped(cpu_bin, reference, capsys):
    """A frame that cannot be stepped from is an error whether named alone or in a range."""
    with open_trajectory(reference["fp64"]) as t:
        cand = diff_dynamic.step_candidates(t)
        n = t.n_frames
    assert 0 not in cand and cand
    for frames in ("0", "0..2", f"{n}", f"{cand[0]}..{n + 3}", f"..{n}"):
        assert _stepdiff(reference["fp64"], cpu_bin, "--frames", frames) == 2, frames
        err = capsys.readouterr().err
        assert "cannot be stepped from" in err and err.count("\n") == 1, frames
    assert diff_dynamic.parse_frame_range(f"{cand[0]}..{cand[1]}", cand) == cand[:2]
    assert diff_dynamic.parse_frame_range(f"{cand[-2]}..", cand) == cand[-2:]


def test_stepdiff_thread_counts(cpu_bin, reference, capsys):
    code = _stepdiff(reference["fp64"], cpu_bin, "--exact", "--", "--threads", "1")
    assert code == 0, capsys.readouterr().out
    assert "EQUIVALENT" in capsys.readouterr().out


def test_stepdiff_fp32_with_a_tighter_rule(cpu_bin, reference, capsys):
    """fp32 against itself passes even the exact rule, one frame at a time, from frame 2 on."""
    code = _stepdiff(reference["fp32"], cpu_bin, "--frames", "3..", "--exact", "--", "--threads", "2")
    assert code == 0, capsys.readouterr().out


def test_stepdiff_different_physics_fails(cpu_bin, reference, capsys):
    """A resumed run keeps its physics: the binary refuses the other flag (exit 2)."""
    code = _stepdiff(reference["fp64"], cpu_bin, "--frames", "2", "--", "--gravity", "500")
    assert code == 2
    assert "--gravity does not match" in capsys.readouterr().err


def test_stepdiff_catches_a_wrong_frame(cpu_bin, reference, tmp_path, capsys):
    """A reference whose frame 4 was moved by 100 times the rule's limit fails at frame 3."""
    import h5py

    bad = tmp_path / "bad.h5"
    bad.write_bytes(reference["fp64"].read_bytes())
    with open_trajectory(reference["fp64"]) as t:
        substeps, iterations = int(t.dynamic_params["substeps"]), int(t.dynamic_params["iterations"])
        E = tolerances.extent(float(t.params["head_radius"]), float(t.params["hair_offset"]), t.hair_length)
    limit = tolerances.DYN_STEP_K[("fp64", "fp64")] * tolerances.EPS["fp64"] * E * substeps * iterations
    with h5py.File(bad, "r+") as f:
        v = f["particles/hair/position/value"]
        a = v[4]
        a[37, 1] += 100 * limit
        v[4] = a
    code = _stepdiff(bad, cpu_bin, "--frames", "3")
    assert code == 1, capsys.readouterr().out
    assert _stepdiff(bad, cpu_bin, "--frames", "2") == 0


# ---- dynamic scenes and `harness run` ----------------------------------------------------------


def test_shipped_dynamic_scenes_load():
    from harness.core import scenes

    d = scenes.load_scene("dynamic")
    assert d.model == "dynamic" and d.stages[-1] == "simulate"
    flags = d.flags()
    for flag in (
        "--solver",
        "--substeps",
        "--bend-compliance",
        "--shape-compliance",
        "--wind-speed",
        "--gust-amplitude",
        "--head-motion",
        "--drag",
        "--damping",
    ):
        assert flag in flags, flag
    assert "--no-collider" not in flags
    s = scenes.load_scene("still-dynamic").flags()
    for flag in ("--bend-compliance", "--shape-compliance", "--wind-speed", "--no-collider"):
        assert flag not in s, flag
    assert s[s.index("--head-motion") + 1] == "still"
    # a paper scene has no dynamic flags
    assert "--frames" not in scenes.load_scene("paper").flags()


def test_harness_run_prints_observables(cpu_bin, tmp_path, capsys):
    out = tmp_path / "d.h5"
    code = harness_main(["run", "dynamic", "--strands", "64", "--points", "16", "--frames", "40", "--output", str(out)])
    text = capsys.readouterr().out
    assert code == 0
    assert "stretch_max" in text and "(one frame in 2 and the last" in text
    assert "blown up: no; invariants: all hold" in text
    with open_trajectory(out) as t:
        assert len(t.observables) == 40 and t.features == "bend+shape+wind+gust+motion+collide+drag"


def _step_limit(path):
    with open_trajectory(path) as t:
        substeps, iterations = int(t.dynamic_params["substeps"]), int(t.dynamic_params["iterations"])
        E = tolerances.extent(float(t.params["head_radius"]), float(t.params["hair_offset"]), t.hair_length)
        h = float(t.dynamic_params["frame_dt"]) / substeps
        steps = [int(s) for s in t.velocity_steps]
    return tolerances.DYN_STEP_K[("fp64", "fp64")] * tolerances.EPS["fp64"] * E * substeps * iterations, h, steps


def test_stepdiff_judges_velocities(cpu_bin, reference, tmp_path, capsys):
    """A stored velocity of frame 4 off by 100 times the rule (on h·|Δv|) fails the step
    into frame 4; positions alone would pass it."""
    import h5py

    limit, h, steps = _step_limit(reference["fp64"])
    with open_trajectory(reference["fp64"]) as t:
        i = steps.index(int(t.step[4]))  # the velocity frame stored with position frame 4
    bad = tmp_path / "badv.h5"
    bad.write_bytes(reference["fp64"].read_bytes())
    with h5py.File(bad, "r+") as f:
        v = f["particles/hair/velocity/value"]
        a = v[i]
        a[37, 1] += 100 * limit / h
        v[i] = a
    assert _stepdiff(bad, cpu_bin, "--frames", "3") == 1
    capsys.readouterr()
    assert _stepdiff(bad, cpu_bin, "--frames", "2") == 0


def test_diff_judges_observables(reference, tmp_path):
    """An observable that the two states' difference cannot explain is a failure, named."""
    import h5py

    bad = tmp_path / "bado.h5"
    bad.write_bytes(reference["fp64"].read_bytes())
    with h5py.File(bad, "r+") as f:
        o = f["observables/kinetic_energy/value"]
        o[2] = o[2] * 1.5 + 1.0
    with open_trajectory(bad) as t:
        step = int(t.observables["step"].iloc[2])
    r = diff_dynamic.compare(reference["fp64"], bad, frames=[step], check_paper=False)
    assert not r.equivalent
    assert any("kinetic_energy" in m for m in r.failures()), r.failures()
    same = diff_dynamic.compare(reference["fp64"], reference["fp64"], frames=[step], check_paper=False)
    assert same.equivalent and not same.failures()
