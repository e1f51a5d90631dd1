"""Colliders and friction (docs/model.md §3.17) in the C reference: known answers.

Free particles are strands of two points whose stretch constraint is made powerless (compliance
1e12: α̃ ≈ 1e17, so a constraint moves its point by C/α̃ ≈ 1e-16 cm), placed by a HAIR groom with
a given head centre, so each test puts its particles exactly where its answer is known:
- stick–slip on an inclined plane: a resting particle stays when tan θ ≤ μ_s and otherwise
  slides with the discrete motion of g·(sin θ − μ_k·cos θ) (position-based friction gives the
  exact per-substep acceleration, so after n substeps s = a·h²·n(n+1)/2);
- a capsule's projection lands every point at the analytic distance r from the axis segment;
- a sphere given as a mesh SDF converges to the analytic sphere as its grid is refined;
- a particle on the head sphere turning under it: frictionless it stays where it is, with a
  large μ_s it turns with the head, Q(t)·X̄;
- the bounded depenetration: a particle started inside leaves at the speed named; one resting on
  a collider that moves faster than that is still moved out in full;
- a resumed run with colliders continues bit for bit; bad colliders files are refused in one line.
"""

import math

import numpy as np
import pytest

from harness.core import tolerances
from harness.io.grooms import write_hair
from harness.io.meshes import icosphere, write_obj
from harness.io.trajectory import open_trajectory
from support.statecheck import run

FREE = ["--stretch-compliance", "1e12", "--no-collider", "--points", "2", "--iterations", "1"]


def words(v):
    """Numbers as a colliders file's words, exact in double."""
    return " ".join(repr(float(c)) for c in v)


def particles(tmp_path, points, roots=None, name="g.hair"):
    """A groom of two-point strands whose free points are `points`; roots 20 cm out along +x."""
    pts = np.asarray(points, float)
    roots = np.asarray(roots, float) if roots is not None else pts + np.array([20.0, 0.0, 0.0])
    path = tmp_path / name
    write_hair(path, [np.stack([r, p]) for r, p in zip(roots, pts)])
    return path


def simulate(cpu_bin, tmp_path, groom, *args, frames=1, out="o.h5", precision="fp64"):
    path = tmp_path / out
    head = ["--groom", groom, "--head-center", "0,0,0", "--head-radius", "1", "--stages", "init,simulate"]
    run(cpu_bin, *head, "--precision", precision, "--frames", frames, "--velocities", "all", *args,
        "--output", path, "--quiet")  # fmt: skip
    return path


def free_points(path):
    with open_trajectory(path) as t:
        return np.stack([t.frame(f).reshape(t.n_strands, 2, 3)[:, 1] for f in range(t.n_frames)])


@pytest.mark.parametrize("mu_s,mu_k,slides", [(0.7, 0.5, False), (0.3, 0.2, True), (0.0, 0.0, True)])
def test_stick_slip_on_an_inclined_plane(cpu_bin, tmp_path, mu_s, mu_k, slides):
    theta = math.radians(30.0)
    n = np.array([0.0, math.cos(theta), math.sin(theta)])  # the plane through the origin, tilted toward +z
    cols = tmp_path / "plane.txt"
    cols.write_text(f"plane body 0 0 0 {words(n)} mu_s {mu_s!r} mu_k {mu_k!r}\n")
    groom = particles(tmp_path, [[0.0, 0.0, 0.0]])
    S, F = 10, 15  # h = 1/600 s, 150 substeps, 0.25 s
    path = simulate(cpu_bin, tmp_path, groom, *FREE, "--substeps", S, "--colliders", cols, frames=F)
    x = free_points(path)[-1, 0]
    downhill = np.array([0.0, -math.sin(theta), math.cos(theta)])
    along, off = float(x @ downhill), float(x @ n)
    assert abs(off) < 1e-9, f"the particle left the plane by {off} cm"
    if not slides:
        assert abs(along) < 1e-9, f"a particle with tan θ < μ_s moved {along} cm"
        return
    h, m = 1.0 / 60.0 / S, S * F
    a = 981.0 * (math.sin(theta) - mu_k * math.cos(theta))
    want = a * h * h * m * (m + 1) / 2.0
    assert along == pytest.approx(want, rel=1e-9), f"slid {along} cm, want {want} (a = {a} cm/s²)"


def test_capsule_projects_to_the_analytic_surface(cpu_bin, tmp_path):
    rng = np.random.default_rng(7)
    a, b, r = np.array([1.0, -2.0, 0.5]), np.array([4.0, 3.0, -1.0]), 1.5
    ab = b - a
    t = rng.uniform(-0.3, 1.3, 300)
    # points inside the capsule: about the axis (or past its ends), closer than r
    d = rng.normal(size=(300, 3))
    d /= np.linalg.norm(d, axis=1)[:, None]
    pts = a + np.clip(t, 0, 1)[:, None] * ab + d * rng.uniform(0.05, 0.95 * r, 300)[:, None]
    cols = tmp_path / "capsule.txt"
    cols.write_text(f"capsule head {words(a)} {words(b)} {r!r}\n")
    path = simulate(cpu_bin, tmp_path, particles(tmp_path, pts), *FREE, "--gravity", "0", "--colliders", cols)
    x = free_points(path)[-1]
    s = np.clip(((x - a) @ ab) / (ab @ ab), 0.0, 1.0)
    dist = np.linalg.norm(x - (a + s[:, None] * ab), axis=1)
    assert np.max(np.abs(dist - r)) < 1e-12


def test_mesh_sdf_converges_to_the_analytic_sphere(cpu_bin, tmp_path):
    radius = 5.0
    v, f = icosphere(5, radius=radius)
    write_obj(tmp_path / "sphere.obj", v, f)
    rng = np.random.default_rng(3)
    d = rng.normal(size=(400, 3))
    pts = d / np.linalg.norm(d, axis=1)[:, None] * rng.uniform(4.8, 4.95, 400)[:, None]  # inside every grid's band
    groom = particles(tmp_path, pts, roots=pts * 5.0)
    errs = []
    for n in (16, 32, 64, 128):
        cols = tmp_path / f"mesh{n}.txt"
        cols.write_text(f"mesh head sphere.obj {n} band 4\n")
        path = simulate(cpu_bin, tmp_path, groom, *FREE, "--gravity", "0", "--colliders", cols, out=f"m{n}.h5")
        x = free_points(path)[-1]
        errs.append(float(np.max(np.abs(np.linalg.norm(x, axis=1) - radius))))
    orders = [math.log2(errs[i] / errs[i + 1]) for i in range(len(errs) - 1)]
    assert all(e1 < e0 for e0, e1 in zip(errs, errs[1:])), f"errors do not fall with the grid: {errs}"
    assert orders[0] > 1.0 and orders[1] > 1.0, f"convergence orders {orders} (errors {errs})"
    assert errs[-1] < 0.01 * radius


@pytest.mark.parametrize("mu", [0.0, 2.0])
def test_particle_on_a_nodding_head(cpu_bin, tmp_path, mu):
    top = np.array([[0.0, 10.0, 0.0]])
    groom = particles(tmp_path, top, roots=[[20.0, 0.0, 0.0]])
    args = [*FREE[:2], "--points", "2", "--iterations", "1", "--substeps", "8", "--head-motion", "nod"]
    args += ["--friction", f"{mu},{mu}"] if mu > 0 else []
    path = run_head(cpu_bin, tmp_path, groom, args)
    x = free_points(path)
    with open_trajectory(path) as t:
        times = np.asarray(t.time)
    if mu == 0.0:  # a sphere turning about its centre does not move its surface: the particle stays
        assert np.max(np.abs(x[:, 0] - top[0])) < 1e-9
    else:
        assert_turns_with_the_nod(x[:, 0], times)


def assert_turns_with_the_nod(x, times, f0=8):
    """A particle's positions x (one a frame) turned with the nodding head: after the start's slip
    (the nod starts at full speed, an impulse no finite friction passes on) it keeps its place on
    the head, Q(t)·Q(t0)ᵀ·x(t0) from frame f0."""
    theta = 0.25 * np.sin(2 * np.pi * times)
    turn = theta - theta[f0]
    c, s = np.cos(turn), np.sin(turn)
    y0, z0 = x[f0, 1], x[f0, 2]
    want = np.stack([np.full_like(turn, x[f0, 0]), c * y0 - s * z0, s * y0 + c * z0], axis=1)
    moved = np.max(np.linalg.norm(want[f0:] - x[f0], axis=1))
    assert moved > 1.0
    assert np.max(np.linalg.norm(x[f0:] - want[f0:], axis=1)) < 1e-3 * moved


def test_bounded_depenetration_leaves_at_the_speed_it_names(cpu_bin, tmp_path):
    # a particle started D deep in a still plane, no gravity: it leaves at V, depth D − n·V·h after
    # n substeps (the rule that took min(δ, V·h) from each substep's depth sped it up: V, 2V, 3V, …)
    D, V, S, F = 2.0, 30.0, 10, 3
    cols = tmp_path / "plane.txt"
    cols.write_text("plane body 0 0 0 0 1 0\n")
    groom = particles(tmp_path, [[0.0, -D, 0.0]])
    path = simulate(cpu_bin, tmp_path, groom, *FREE, "--gravity", "0", "--substeps", S, "--colliders", cols,
                    "--depenetration-speed", V, frames=F)  # fmt: skip
    depth = -free_points(path)[:, 0, 1]
    vh = V / 60.0 / S
    want = D - vh * S * np.arange(F + 1)
    assert np.max(np.abs(depth - want)) < 1e-12, f"depths {depth}, want {want}"


def test_bounded_depenetration_keeps_hair_on_a_collider_moving_faster(cpu_bin, tmp_path):
    # a particle resting on a plane that rises at u = A_b·f_b = 20 cm/s, four times the bound
    # V = 5 cm/s: it was outside at each substep's start, so it is moved out in full and rides the
    # plane (the rule that bounded every projection let it sink by (u − V)·t, 5 cm at 0.33 s)
    A, f_b, V, F = 10.0, 2.0, 5.0, 20
    cols = tmp_path / "plane.txt"
    cols.write_text("plane body 0 0 0 0 1 0\n")
    groom = particles(tmp_path, [[0.0, -A, 0.0]])
    rise = ["--body-motion", "rise", "--body-amplitude", A, "--body-frequency", f_b]
    path = simulate(cpu_bin, tmp_path, groom, *FREE, "--substeps", 8, "--colliders", cols, *rise,
                    "--depenetration-speed", V, frames=F)  # fmt: skip
    with open_trajectory(path) as t:
        times = np.asarray(t.time)
    plane = -A * np.clip(1.0 - f_b * times, 0.0, None)
    y = free_points(path)[:, 0, 1]
    eps = np.finfo(np.float64).eps
    assert np.max(plane - y) <= tolerances.DYN_PENETRATION_K * eps * A, f"depths {plane - y}"
    assert y[-1] - y[0] > 0.9 * A * f_b * times[-1]  # it rose with the plane, faster than V


def run_head(cpu_bin, tmp_path, groom, args):
    path = tmp_path / "head.h5"
    run(cpu_bin, "--groom", groom, "--head-center", "0,0,0", "--head-radius", "10", "--stages", "init,simulate",
        "--precision", "fp64", "--frames", 30, *args, "--output", path, "--quiet")  # fmt: skip
    return path


def test_resume_with_colliders_and_a_mesh_is_bit_for_bit(cpu_bin, tmp_path):
    v, f = icosphere(2, radius=4.0, center=(0.0, -14.0, 0.0))
    write_obj(tmp_path / "chin.obj", v, f)
    cols = tmp_path / "body.txt"
    cols.write_text("capsule body 0 -10 0 0 -25 0 4 mu_s 0.3 mu_k 0.2\nmesh head chin.obj 24 mu_s 0.2\n")
    common = ["--strands", "60", "--points", "12", "--substeps", "4", "--iterations", "2", "--bend-compliance", "1e-6",
              "--head-motion", "nod", "--friction", "0.3,0.2", "--depenetration-speed", "200"]  # fmt: skip
    whole, part, rest = tmp_path / "w.h5", tmp_path / "p.h5", tmp_path / "r.h5"
    sim = ["--stages", "init,collide,simulate", *common, "--colliders", cols]
    run(cpu_bin, *sim, "--frames", 4, "--output", whole, "--quiet")
    run(cpu_bin, *sim, "--frames", 2, "--output", part, "--quiet")
    (tmp_path / "chin.obj").unlink()  # the file holds the mesh's field: the resume needs no mesh
    run(cpu_bin, "--input", part, "--stages", "simulate", "--frames", 2, "--output", rest, "--quiet")
    with open_trajectory(whole) as a, open_trajectory(rest) as b:
        assert np.array_equal(a.frame(a.n_frames - 1).view(np.uint8), b.frame(b.n_frames - 1).view(np.uint8))
    p = run(cpu_bin, "--input", part, "--stages", "simulate", "--frames", 1, "--colliders", cols, "--output",
            tmp_path / "x.h5", "--quiet", check=False)  # fmt: skip
    assert p.returncode == 2 and "--colliders does not match the input file's simulation" in p.stderr


@pytest.mark.parametrize(
    "text,message",
    [
        ("cube head 0 0 0 1\n", "unknown collider 'cube'"),
        ("sphere arm 0 0 0 1\n", "the frame must be head or body"),
        ("sphere head 0 0 0 -1\n", "the radius must be > 0"),
        ("capsule body 0 0 0 0 0 0 1\n", "a capsule's two ends must differ"),
        ("plane body 0 0 0 0 0 0\n", "a plane's normal must not be zero"),
        ("sphere head 0 0 0 1 mu_s 0.1 mu_k 0.3\n", "friction needs 0 <= mu_k <= mu_s"),
        ("sphere head 0 0 nan 1\n", "must be finite"),
        ("sphere head 0 0 1e999 1\n", "must be finite"),
        ("sphere head 0 0 0x10 1\n", "needs a decimal number"),
        ("mesh head missing.obj 32\n", "missing.obj"),
        ("# nothing\n", "declares no collider"),
    ],
)
def test_bad_colliders_files_are_refused_in_one_line(cpu_bin, tmp_path, text, message):
    cols = tmp_path / "c.txt"
    cols.write_text(text)
    out = tmp_path / "o.h5"
    p = run(cpu_bin, "--stages", "init,collide,simulate", "--strands", "10", "--colliders", cols, "--output", out,
            check=False)  # fmt: skip
    assert p.returncode == 2 and message in p.stderr and len(p.stderr.strip().splitlines()) == 1, p.stderr
    assert not out.exists()


def test_open_mesh_is_refused(cpu_bin, tmp_path):
    v, f = icosphere(1)
    write_obj(tmp_path / "open.obj", v, f[:-1])  # one face removed: its three edges lose their partner
    cols = tmp_path / "c.txt"
    cols.write_text("mesh body open.obj 16\n")
    p = run(cpu_bin, "--stages", "init,collide,simulate", "--strands", "10", "--colliders", cols, check=False)
    assert p.returncode == 2 and "not a closed, consistently oriented surface" in p.stderr
