"""The colliders as contact planes (`--contact-planes M`, docs/model.md §3.17) in the C reference:
known answers, with the free particles of test_colliders.py.

- a plane collider is its own contact plane: stick–slip on an inclined plane keeps the analytic
  answer;
- a point inside a capsule meets the tangent plane at its nearest surface point, so one step puts
  it at the analytic distance r from the axis, as the exact projection does;
- the margin: a particle farther than M from every collider at a frame's start finds no plane and
  falls into a floor during that frame; the next frame finds it inside and moves it out, while a
  margin that holds the fall keeps it out throughout;
- a point in a corner of two colliders meets both planes (the HB_CONTACT_K nearest) and ends out of both;
- a plane carried with its collider through the frame: a particle on a rising body floor rides it,
  one on a turning head-frame floor stays on it, and one with a large μ_s on a head-frame sphere
  turns with the head;
- the bits do not depend on the thread count, a resumed run continues bit for bit, and a bad margin
  or a margin without colliders is refused in one line (simd runs the planes: test_cpu_simd_dynamic.py).
"""

import numpy as np
import pytest
from test_colliders import FREE, assert_turns_with_the_nod, free_points, particles, run_head, simulate, words

from harness.check import invariants_dynamic
from harness.io.meshes import icosphere, write_obj
from harness.io.trajectory import open_trajectory
from support.statecheck import run


def test_stick_slip_keeps_the_analytic_answer(cpu_bin, tmp_path):
    theta = np.radians(30.0)
    n = np.array([0.0, np.cos(theta), np.sin(theta)])
    cols = tmp_path / "plane.txt"
    cols.write_text(f"plane body 0 0 0 {words(n)} mu_s 0.3 mu_k 0.2\n")
    groom = particles(tmp_path, [[0.0, 0.0, 0.0]])
    S, F = 10, 15
    path = simulate(cpu_bin, tmp_path, groom, *FREE, "--substeps", S, "--colliders", cols, "--contact-planes", 1,
                    frames=F)  # fmt: skip
    x = free_points(path)[-1, 0]
    downhill = np.array([0.0, -np.sin(theta), np.cos(theta)])
    h, m = 1.0 / 60.0 / S, S * F
    want = 981.0 * (np.sin(theta) - 0.2 * np.cos(theta)) * h * h * m * (m + 1) / 2.0
    assert abs(float(x @ n)) < 1e-9
    assert float(x @ downhill) == pytest.approx(want, rel=1e-9)


def test_capsule_plane_puts_a_point_on_the_analytic_surface(cpu_bin, tmp_path):
    rng = np.random.default_rng(11)
    a, b, r = np.array([1.0, -2.0, 0.5]), np.array([4.0, 3.0, -1.0]), 1.5
    ab = b - a
    d = rng.normal(size=(200, 3))
    d /= np.linalg.norm(d, axis=1)[:, None]
    pts = a + np.clip(rng.uniform(-0.3, 1.3, 200), 0, 1)[:, None] * ab + d * rng.uniform(0.05, 0.95 * r, 200)[:, None]
    cols = tmp_path / "capsule.txt"
    cols.write_text(f"capsule head {words(a)} {words(b)} {r!r}\n")
    path = simulate(cpu_bin, tmp_path, particles(tmp_path, pts), *FREE, "--gravity", "0", "--substeps", 1,
                    "--colliders", cols, "--contact-planes", 1)  # fmt: skip
    x = free_points(path)[-1]
    s = np.clip(((x - a) @ ab) / (ab @ ab), 0.0, 1.0)
    dist = np.linalg.norm(x - (a + s[:, None] * ab), axis=1)
    assert np.max(np.abs(dist - r)) < 1e-12


@pytest.mark.parametrize("margin,caught", [(0.05, False), (1.0, True)])
def test_the_margin_decides_which_points_meet_a_plane_this_frame(cpu_bin, tmp_path, margin, caught):
    # from rest 0.1 cm above a floor, gravity takes a particle 0.15 cm down in one frame (S = 4)
    cols = tmp_path / "floor.txt"
    cols.write_text("plane body 0 0 0 0 1 0\n")
    groom = particles(tmp_path, [[0.0, 0.1, 0.0]])
    path = simulate(cpu_bin, tmp_path, groom, *FREE, "--substeps", 4, "--colliders", cols, "--contact-planes",
                    margin, frames=3)  # fmt: skip
    y = free_points(path)[:, 0, 1]
    if caught:
        assert np.min(y) >= -1e-15, f"heights {y}"
    else:
        assert y[1] < -0.01, f"a particle beyond the margin was met by a plane: heights {y}"
        assert y[2] >= -1e-15 and y[3] >= -1e-15, f"the next frame did not move it out: heights {y}"
    exact = simulate(cpu_bin, tmp_path, groom, *FREE, "--substeps", 4, "--colliders", cols, frames=3, out="e.h5")
    assert np.min(free_points(exact)[:, 0, 1]) >= -1e-15


def test_a_point_in_a_corner_meets_both_planes(cpu_bin, tmp_path):
    cols = tmp_path / "corner.txt"
    cols.write_text("plane body 0 0 0 0 1 0\nplane body 0 0 0 1 0 0\n")  # a floor and a wall
    pts = [[-0.5, -0.3, 0.0], [-0.2, -0.6, 1.0], [0.4, -0.1, -1.0]]
    path = simulate(cpu_bin, tmp_path, particles(tmp_path, pts), *FREE, "--gravity", "0", "--substeps", 1,
                    "--colliders", cols, "--contact-planes", 1)  # fmt: skip
    x = free_points(path)[-1]
    assert np.min(x[:, :2]) >= -1e-15, x
    assert np.allclose(x[:, 2], [0.0, 1.0, -1.0], atol=1e-15)


def test_a_head_collider_plane_turns_with_the_head(cpu_bin, tmp_path):
    top = np.array([[0.0, 10.0, 0.0]])
    cols = tmp_path / "skull.txt"
    cols.write_text("sphere head 0 0 0 10 mu_s 2 mu_k 2\n")
    groom = particles(tmp_path, top, roots=[[20.0, 0.0, 0.0]])
    args = [*FREE, "--substeps", "8", "--head-motion", "nod", "--colliders", cols, "--contact-planes", "1"]
    path = run_head(cpu_bin, tmp_path, groom, args)
    with open_trajectory(path) as t:
        times = np.asarray(t.time)
    assert_turns_with_the_nod(free_points(path)[:, 0], times)


def test_a_rising_body_floor_carries_its_plane(cpu_bin, tmp_path):
    # a particle resting on a body-frame floor that rises at A_b·f_b = 20 cm/s: its plane rides with
    # the floor through the frame's substeps (a plane left where the frame found it would let the
    # particle sink 0.33 cm a frame)
    A, f_b = 10.0, 2.0
    cols = tmp_path / "floor.txt"
    cols.write_text("plane body 0 0 0 0 1 0 mu_s 1 mu_k 1\n")
    groom = particles(tmp_path, [[0.0, -A, 0.0]])
    rise = ["--body-motion", "rise", "--body-amplitude", A, "--body-frequency", f_b]
    path = simulate(cpu_bin, tmp_path, groom, *FREE, "--substeps", 8, "--colliders", cols, *rise,
                    "--contact-planes", 1, frames=20)  # fmt: skip
    with open_trajectory(path) as t:
        times = np.asarray(t.time)
    floor = -A * np.clip(1.0 - f_b * times, 0.0, None)
    y = free_points(path)[:, 0, 1]
    assert np.max(floor - y) < 1e-12, f"depths {floor - y}"
    assert y[-1] - y[0] > 0.9 * A * f_b * times[-1]


def test_a_head_plane_turns_with_the_head(cpu_bin, tmp_path):
    # a particle 10 cm along z on a head-frame floor 5 cm below the centre; the nod turns the floor
    # about x, so at the frame's end it lies at d − n·x = −5 − (cos θ·y + sin θ·z) = 0 only where the
    # plane was turned with the head at every substep (left as found, it would sink up to 0.26 cm)
    cols = tmp_path / "shelf.txt"
    cols.write_text("plane head 0 -5 0 0 1 0 mu_s 3 mu_k 3\n")
    groom = particles(tmp_path, [[0.0, -5.0, 10.0]], roots=[[20.0, -5.0, 10.0]])
    args = [*FREE, "--substeps", "8", "--head-motion", "nod", "--colliders", cols, "--contact-planes", "1"]
    path = run_head(cpu_bin, tmp_path, groom, args)
    x = free_points(path)[:, 0]
    with open_trajectory(path) as t:
        theta = 0.25 * np.sin(2 * np.pi * np.asarray(t.time))
    depth = -5.0 - (np.cos(theta) * x[:, 1] + np.sin(theta) * x[:, 2])
    assert np.max(depth) < 1e-9, f"depths {depth}"
    assert np.ptp(x[:, 1]) > 1.0  # it moved with the head


def body_run(cpu_bin, tmp_path, name, *args, frames=4):
    cols = tmp_path / "body.txt"
    cols.write_text(
        "capsule body 0 -10 0 0 -25 0 4 mu_s 0.3 mu_k 0.2\ncapsule body 3 -14 0 12 -16 0 4 mu_s 0.3 mu_k 0.2\n"
        "sphere head 0 -12 3 3 mu_s 0.2\n"
    )
    out = tmp_path / name
    run(cpu_bin, "--stages", "init,collide,simulate", "--strands", 60, "--points", 12, "--substeps", 4,
        "--iterations", 2, "--bend-compliance", "1e-6", "--head-motion", "nod", "--body-motion", "sway",
        "--colliders", cols, "--contact-planes", 3, "--depenetration-speed", 200, "--frames", frames,
        "--output", out, "--quiet", *args)  # fmt: skip
    return out


def last_bits(path):
    with open_trajectory(path) as t:
        return t.frame(t.n_frames - 1).view(np.uint8)


def test_bits_do_not_depend_on_threads_and_a_resume_continues(cpu_bin, tmp_path):
    one = body_run(cpu_bin, tmp_path, "t1.h5", "--threads", 1)
    two = body_run(cpu_bin, tmp_path, "t2.h5", "--threads", 2)
    assert np.array_equal(last_bits(one), last_bits(two))
    part = body_run(cpu_bin, tmp_path, "p.h5", frames=2)
    rest = tmp_path / "r.h5"
    run(cpu_bin, "--input", part, "--stages", "simulate", "--frames", 2, "--output", rest, "--quiet")
    assert np.array_equal(last_bits(one), last_bits(rest))
    with open_trajectory(rest) as t:
        assert float(t.dynamic_params["contact_margin"]) == 3.0


def test_ftl_hair_sliding_off_a_plane_passes_the_dynamic_checks(cpu_bin, tmp_path):
    """a point within M of a collider at a frame's start meets its plane all frame, and hair slides along
    a plane far beyond a curved collider: the checks count such a point as moved by a collider where
    they hold ftl's segments at ℓ (in this scene tips end 5 cm from the capsule whose plane moved them)"""
    v, f = icosphere(3, radius=4.0, center=(0.0, -9.0, 5.0), scale=(1.0, 0.8, 1.0))
    write_obj(tmp_path / "chin.obj", v, f)
    cols = tmp_path / "body.txt"
    cols.write_text(
        "capsule body 0 -10 -1 0 -24 -1 4.5 mu_s 0.3 mu_k 0.2\n"
        "capsule body -4 -24 -2 -19 -27 -2 5.5 mu_s 0.3 mu_k 0.2\n"
        "sphere head 0 4 9 2 mu_s 0.5\nplane body 0 -45 0 0 1 0\nmesh head chin.obj 32 band 4 mu_s 0.2 mu_k 0.1\n"
    )
    out = tmp_path / "ftl.h5"
    run(cpu_bin, "--stages", "init,collide,simulate", "--strands", 300, "--points", 24, "--substeps", 4,
        "--iterations", 2, "--bend-compliance", "1e-6", "--shape-compliance", "1e-4", "--shape-range", 0.5,
        "--drag", 0.5, "--wind-speed", 150, "--head-motion", "nod", "--friction", "0.4,0.3",
        "--depenetration-speed", 150, "--colliders", cols, "--contact-planes", 3, "--solver", "ftl",
        "--precision", "fp32", "--frames", 3, "--velocities", "all", "--output", out, "--quiet")  # fmt: skip
    with open_trajectory(out) as t:
        rep = invariants_dynamic.check(t, exact=True, paper=False)
    assert not rep.violations, [v.message for v in rep.violations[:3]]


@pytest.mark.parametrize(
    "args,message",
    [
        (["--contact-planes", "2"], "--contact-planes needs --colliders"),
        (["--colliders", "C", "--contact-planes", "0"], "--contact-planes must be > 0"),
    ],
)
def test_bad_contact_planes_are_refused_in_one_line(cpu_bin, tmp_path, args, message):
    cols = tmp_path / "c.txt"
    cols.write_text("sphere head 0 -12 0 3\n")
    out = tmp_path / "o.h5"
    args = [str(cols) if a == "C" else a for a in args]
    p = run(cpu_bin, "--stages", "init,collide,simulate", "--strands", 10, *args, "--output", out, check=False)
    assert p.returncode == 2 and message in p.stderr and len(p.stderr.strip().splitlines()) == 1, p.stderr
    assert not out.exists()
