"""xpbd's collision step once a substep (docs/model.md §3.6, `--collide-once`) in the C reference.

- with one iteration a substep it is the collision step as it was: the same bits as no flag, on the
  default body with friction, the bounded depenetration and the grid, both CPU variants and
  precisions; with two it changes the hair (not vacuous);
- a known answer where the two orders part: a particle held by a rigid segment to a fixed root and
  pressed into a plane ends on the plane, the segment stretched by what the plane pushed; colliding
  in every iteration, the later iterations pull it back along the segment (analytic in both);
- stick–slip on an inclined plane holds as with the collision step in every iteration;
- the flag is in /parameters and the JSON record, a resumed run takes it from its file and continues
  bit for bit; ftl and rigid refuse it in one line with the usage exit status, as do the scene files'
  wrong values.
"""

import math

import numpy as np
import pytest

from harness import HarnessError
from harness.core import scenes
from harness.core.paths import ROOT
from harness.io.grooms import write_hair
from harness.io.trajectory import open_trajectory
from support.statecheck import run, run_json
from support.statecheck import same_trajectory_bits as same_bits
from support.statecheck import trajectory as state

BODY = ["--colliders", ROOT / "configs" / "bodies" / "default.colliders", "--friction", "0.3,0.2",
        "--depenetration-speed", "200", "--grid", "16", "--grid-friction", "0.05,0.01"]  # fmt: skip
SCENE = ["--strands", "64", "--points", "16", "--stages", "init,collide,simulate", "--substeps", "4",
         "--bend-compliance", "1e-6", "--shape-compliance", "1e-4", "--head-motion", "nod", "--motion-frequency", "2",
         "--motion-amplitude", "0.3", "--wind-speed", "150", "--drag", "0.5"]  # fmt: skip


def sim(cpu_bin, out, *args, frames=3):
    run(cpu_bin, *SCENE, *map(str, args), "--frames", frames, "--velocities", "all", "--output", out, "--quiet")
    return out


@pytest.mark.parametrize("variant", ["ref", "simd"])
@pytest.mark.parametrize("precision", ["fp32", "fp64"])
def test_one_iteration_collides_as_before_and_two_part(cpu_bin, tmp_path, variant, precision):
    args = [*BODY, "--precision", precision, "--variant", variant]
    for it in (1, 2):
        every = sim(cpu_bin, tmp_path / f"every{it}.h5", *args, "--iterations", it)
        once = sim(cpu_bin, tmp_path / f"once{it}.h5", *args, "--iterations", it, "--collide-once")
        assert int(state(once)[3]["collide_once"]) == 1 and int(state(every)[3]["collide_once"]) == 0
        if it == 1:
            assert same_bits(every, once), f"{variant} {precision}: --collide-once changed a bit at I = 1"
        else:
            moved = np.abs(state(every)[0] - state(once)[0]).max()
            assert moved > 1e-3, f"{variant} {precision}: --collide-once at I = 2 moved the hair {moved} cm"


# A two-point strand: the root fixed at (2, 0, 0) (off the head's centre), its free point (x0, y0) from
# it (ℓ = |(x0, y0)|, the stretch rigid), gravity 0 and no head sphere; a plane y = y_p above y0 pushes
# the point up to it. With I iterations and the collision step in the last alone, the point ends on the
# plane at x0 (the segment shortened). With the collision step in every iteration, each later
# iteration's stretch pulls it back to the circle of radius ℓ along its ray from the root and the plane
# lifts it again: it ends on the plane at another x.
def segment_and_plane(cpu_bin, tmp_path, x0, y0, y_plane, iterations, once):
    groom = tmp_path / f"g{once}.hair"
    write_hair(groom, [np.array([[2.0, 0.0, 0.0], [2.0 + x0, y0, 0.0]])])
    cols = tmp_path / "plane.txt"
    cols.write_text(f"plane body 0 {y_plane!r} 0 0 1 0\n")
    out = tmp_path / f"o{iterations}{once}.h5"
    run(cpu_bin, "--groom", groom, "--head-center", "0,0,0", "--head-radius", "1", "--stages", "init,simulate",
        "--precision", "fp64", "--no-collider", "--gravity", "0", "--points", "2", "--substeps", "1",
        "--iterations", iterations, "--colliders", cols, "--frames", 1, *(["--collide-once"] if once else []),
        "--output", out, "--quiet")  # fmt: skip
    with open_trajectory(out) as t:
        return t.frame(t.n_frames - 1).reshape(2, 3)[1] - np.array([2.0, 0.0, 0.0])


@pytest.mark.parametrize("iterations", [1, 2, 3])
def test_a_segment_pressed_into_a_plane(cpu_bin, tmp_path, iterations):
    x0, y0, yp = 0.5, -0.75, -0.5  # exact in the HAIR file's fp32; the point 0.25 below the plane
    once = segment_and_plane(cpu_bin, tmp_path, x0, y0, yp, iterations, True)
    every = segment_and_plane(cpu_bin, tmp_path, x0, y0, yp, iterations, False)
    # the point starts at its rest length, so the stretch moves nothing before the plane lifts it straight
    # up (once, or in the first iteration); each later stretch pulls (x, y_p) back to the circle along its
    # ray from the root, and the plane lifts that again
    assert once == pytest.approx([x0, yp, 0.0], abs=1e-12)
    ell, x = math.hypot(x0, y0), x0
    for _ in range(iterations - 1):
        x = ell * x / math.hypot(x, yp)
    assert every == pytest.approx([x, yp, 0.0], abs=1e-12)
    assert (iterations == 1) == (abs(every[0] - once[0]) < 1e-12)


@pytest.mark.parametrize("mu_s,mu_k,slides", [(0.7, 0.5, False), (0.3, 0.2, True)])
def test_stick_slip_on_an_inclined_plane_colliding_once(cpu_bin, tmp_path, mu_s, mu_k, slides):
    """A free particle (its stretch powerless) on a plane at 30°: as with the collision step in every
    iteration (tests/cpu/test_colliders.py), at I = 3 with the step in the last alone."""
    theta = math.radians(30.0)
    n = np.array([0.0, math.cos(theta), math.sin(theta)])
    cols = tmp_path / "plane.txt"
    cols.write_text(f"plane body 0 0 0 {' '.join(repr(float(c)) for c in n)} mu_s {mu_s!r} mu_k {mu_k!r}\n")
    groom = tmp_path / "g.hair"
    write_hair(groom, [np.array([[20.0, 0.0, 0.0], [0.0, 0.0, 0.0]])])
    S, F = 10, 15
    out = tmp_path / "o.h5"
    run(cpu_bin, "--groom", groom, "--head-center", "0,0,0", "--head-radius", "1", "--stages", "init,simulate",
        "--precision", "fp64", "--stretch-compliance", "1e12", "--no-collider", "--points", "2", "--iterations", 3,
        "--collide-once", "--substeps", S, "--colliders", cols, "--frames", F, "--output", out, "--quiet")  # fmt: skip
    with open_trajectory(out) as t:
        x = t.frame(t.n_frames - 1).reshape(2, 3)[1]
    downhill = np.array([0.0, -math.sin(theta), math.cos(theta)])
    assert abs(float(x @ n)) < 1e-9
    along = float(x @ downhill)
    if not slides:
        assert abs(along) < 1e-9
        return
    h, m = 1.0 / 60.0 / S, S * F
    want = 981.0 * (math.sin(theta) - mu_k * math.cos(theta)) * h * h * m * (m + 1) / 2.0
    assert along == pytest.approx(want, rel=1e-9)


def test_recorded_and_resumed_bit_for_bit(cpu_bin, tmp_path):
    args = [*BODY, "--iterations", 2, "--collide-once"]
    whole = sim(cpu_bin, tmp_path / "whole.h5", *args, frames=3)
    first = sim(cpu_bin, tmp_path / "first.h5", *args, frames=2)
    rec = run_json(cpu_bin, "--input", first, "--stages", "simulate", "--frames", 1, "--velocities", "all",
                   "--output", tmp_path / "rest.h5")  # fmt: skip
    assert int(state(tmp_path / "rest.h5")[3]["collide_once"]) == 1  # taken from the input's /parameters
    entry = next(s for s in rec["stages"] if s["stage"] == "simulate")
    assert entry["collide_once"] is True
    assert state(tmp_path / "rest.h5")[0][-1].tobytes() == state(whole)[0][-1].tobytes()


@pytest.mark.parametrize("solver", ["ftl", "rigid"])
def test_other_solvers_refuse_it(cpu_bin, tmp_path, solver):
    out = tmp_path / "o.h5"
    p = run(cpu_bin, *SCENE, "--solver", solver, "--collide-once", "--frames", 1, "--output", out, check=False)
    assert p.returncode == 2
    assert p.stderr.strip().count("\n") == 0 and "--collide-once needs --solver xpbd" in p.stderr
    assert not out.exists()


def test_scene_files_take_it_as_a_switch(tmp_path):
    text = 'model = "dynamic"\n[dynamics]\nframes = 1\ncollide_once = {}\n'
    on, off = tmp_path / "on.toml", tmp_path / "off.toml"
    on.write_text(text.format("true"))
    off.write_text(text.format("false"))
    assert "--collide-once" in scenes.load_scene(str(on)).flags()
    assert "--collide-once" not in scenes.load_scene(str(off)).flags()
    bad = tmp_path / "bad.toml"
    bad.write_text(text.format('"yes"'))
    with pytest.raises(HarnessError, match="collide_once must be true or false"):
        scenes.load_scene(str(bad))
