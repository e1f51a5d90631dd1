"""A groom file's head given instead of fitted (docs/model.md §3.15, --head-center): a groom whose
roots are not near one sphere is refused without it and runs with it, the given centre is the
origin of the state (a translated groom with its translated centre gives the same bits), the fit
is what a given centre equal to the fitted one gives, the JSON record and /parameters say which
head was used, bad values are refused in one line, and the scene key reaches the binary.

Every HAIR file is written by the test (tests/cpu/test_grooms.py hair_bytes); its coordinates are
small multiples of powers of two, so translating them by the centres used here is exact in fp32."""

import json

import numpy as np
import pytest
from test_grooms import hair_bytes, radial_strands

from harness.core import scenes
from harness.io.trajectory import open_trajectory
from support.statecheck import run, tmp_leftovers

SHIFT = (1.5, -2.25, 3.0)
PHYSICS = ["--frames", 4, "--substeps", 2, "--bend-compliance", 1e-6, "--shape-compliance", 1e-4,
           "--head-motion", "nod", "--wind-speed", 150, "--drag", 0.5]  # fmt: skip


def off_sphere_strands(shift=(0.0, 0.0, 0.0)):
    """Six straight strands along the axes with roots at 10 cm, the first moved out to 20 cm (a lock
    off the scalp: the roots lie on no sphere within 5%), translated by `shift`."""
    s = radial_strands((0, 0, 0), 10.0, [4.0] * 6, [5] * 6)
    s[0] = [(2 * x, 2 * y, 2 * z) for x, y, z in s[0]]
    return [[tuple(np.add(p, shift)) for p in strand] for strand in s]


def groom(cpu_bin, path, *args, check=True):
    return run(cpu_bin, "--groom", path, "--points", 5, "--json", "--quiet", *args, check=check)


def centre_arg(c):
    return ",".join(repr(float(x)) for x in c)


@pytest.fixture
def off_sphere(tmp_path):
    path = tmp_path / "lock.hair"
    path.write_bytes(hair_bytes(off_sphere_strands()))
    return path


def test_off_sphere_groom_refused_without_centre_runs_with_it(cpu_bin, tmp_path, off_sphere):
    out = tmp_path / "o.h5"
    p = groom(cpu_bin, off_sphere, "--stages", "init", "--output", out, check=False)
    assert p.returncode == 2 and "do not lie near one sphere" in p.stderr and not out.exists(), p.stderr
    rec = json.loads(groom(cpu_bin, off_sphere, "--head-center", "0,0,0", "--stages", "init", "--output", out).stdout)
    g = rec["groom"]
    assert g["head"] == "given" and g["head_center"] == [0.0, 0.0, 0.0] and g["fit_offset"] is None
    assert rec["head_radius"] == 10.0  # the smallest root distance from the given centre
    with open_trajectory(out) as t:
        assert t.params["groom_head"] == "given" and list(t.params["groom_head_center"]) == [0.0, 0.0, 0.0]
        assert t.params["head_radius"] == 10.0
        np.testing.assert_array_equal(t.frame(0)[0, 0], [20.0, 0.0, 0.0])
    out2 = tmp_path / "r.h5"
    args = ("--head-center", "0,0,0", "--head-radius", "9.5", "--stages", "init,simulate", *PHYSICS, "--output", out2)
    rec = json.loads(groom(cpu_bin, off_sphere, *args).stdout)
    assert rec["head_radius"] == 9.5
    with open_trajectory(out2) as t:
        assert t.params["head_radius"] == 9.5 and t.collide_radius == 9.5
        assert not np.array_equal(t.frame(-1), t.frame(0))


@pytest.mark.parametrize("precision", ["fp32", "fp64"])
def test_given_centre_is_the_origin(cpu_bin, tmp_path, precision):
    """The groom translated by c and run with --head-center c gives the bits of the untranslated groom
    run with --head-center 0,0,0, init and simulated frames; any other centre gives other bits."""
    a_file, b_file = tmp_path / "a.hair", tmp_path / "b.hair"
    a_file.write_bytes(hair_bytes(off_sphere_strands()))
    b_file.write_bytes(hair_bytes(off_sphere_strands(SHIFT)))
    common = ["--stages", "init,simulate", *PHYSICS, "--precision", precision]
    outs = {k: tmp_path / f"{k}.h5" for k in ("a", "b", "wrong")}
    groom(cpu_bin, a_file, "--head-center", "0,0,0", *common, "--output", outs["a"])
    rec = json.loads(groom(cpu_bin, b_file, "--head-center", centre_arg(SHIFT), *common, "--output", outs["b"]).stdout)
    assert rec["groom"]["head_center"] == list(SHIFT) and rec["head_radius"] == 10.0
    groom(cpu_bin, b_file, "--head-center", "0,0,0", *common, "--output", outs["wrong"])
    with open_trajectory(outs["a"]) as ta, open_trajectory(outs["b"]) as tb, open_trajectory(outs["wrong"]) as tw:
        assert len(ta.simulated) == 4 and not np.array_equal(ta.frame(-1), ta.frame(0))
        for f in range(ta.n_frames):
            assert np.array_equal(ta.frame(f), tb.frame(f)), f"frame {f}"
        assert list(tb.params["groom_head_center"]) == list(SHIFT)
        np.testing.assert_allclose(tw.frame(0) - ta.frame(0), np.broadcast_to(SHIFT, ta.frame(0).shape), atol=1e-6)


def test_fitted_head_is_a_given_centre_at_the_fit(cpu_bin, tmp_path):
    """A groom on a sphere centred off the origin: the record says the head was fitted and where
    (the %.17g centre reads back exactly); given that centre back, the run has the same head radius,
    the same bits and the same resampling, only the record's head says given."""
    strands = radial_strands((1.0, 2.0, 3.0), 10.0, [8.0, 4.0, 16.0, 2.0, 8.0, 12.0], [5, 3, 17, 2, 33, 7])
    path = tmp_path / "g.hair"
    path.write_bytes(hair_bytes(strands))
    fit, given = tmp_path / "fit.h5", tmp_path / "given.h5"
    common = ["--points", 9, "--stages", "init,simulate", *PHYSICS]
    rf = json.loads(run(cpu_bin, "--groom", path, *common, "--json", "--quiet", "--output", fit).stdout)
    assert rf["groom"]["head"] == "fitted" and rf["groom"]["fit_offset"] <= 1e-5
    np.testing.assert_allclose(rf["groom"]["head_center"], [1.0, 2.0, 3.0], atol=1e-5)
    c = centre_arg(rf["groom"]["head_center"])
    rg = json.loads(
        run(cpu_bin, "--groom", path, "--head-center", c, *common, "--json", "--quiet", "--output", given).stdout
    )
    assert rg["groom"]["head"] == "given" and rg["groom"]["head_center"] == rf["groom"]["head_center"]
    assert rg["head_radius"] == rf["head_radius"] and rg["groom"]["resample_error"] == rf["groom"]["resample_error"]
    with open_trajectory(fit) as tf, open_trajectory(given) as tg:
        assert tf.params["groom_head"] == "fitted"
        assert list(tf.params["groom_head_center"]) == rf["groom"]["head_center"]
        for f in range(tf.n_frames):
            assert np.array_equal(tf.frame(f), tg.frame(f)), f"frame {f}"


BAD = [
    (["--head-center", "abc"], "--head-center needs three numbers X,Y,Z"),
    (["--head-center", "1,x,3"], "--head-center needs a decimal number"),
    (["--head-center", "1,2"], "--head-center needs three numbers X,Y,Z"),
    (["--head-center", "1,2,3,4"], "--head-center needs three numbers X,Y,Z"),
    (["--head-center", "1,,3"], "--head-center needs three numbers X,Y,Z"),
    (["--head-center", ""], "--head-center needs three numbers X,Y,Z"),
    (["--head-center", "nan,0,0"], "--head-center must be finite"),
    (["--head-center", "0,0,inf"], "--head-center must be finite"),
    (["--head-center", "-10,0,0"], "a root lies at the given head's centre"),
    (["--head-center", "0,0,0", "--head-radius", "0"], "--head-radius must be a finite number > 0"),
    (["--head-center", "0,0,0", "--head-radius", "-3"], "--head-radius must be a finite number > 0"),
    (["--head-center", "0,0,0", "--head-radius", "nan"], "--head-radius must be finite"),
    (["--head-radius", "12"], "--head-radius needs --head-center"),
    (["--head-center", "0,0,0", "--hair-length", "12"], "the file decides the head and the strands"),
]


@pytest.mark.parametrize("args, words", BAD, ids=[" ".join(a) for a, _ in BAD])
def test_bad_head_refused(cpu_bin, tmp_path, off_sphere, args, words):
    out = tmp_path / "out.h5"
    p = groom(cpu_bin, off_sphere, *args, "--stages", "init,simulate", "--output", out, check=False)
    assert p.returncode == 2 and p.stdout == "", p.stderr
    lines = p.stderr.strip().splitlines()
    assert len(lines) == 1 and words in lines[0], p.stderr
    assert not out.exists() and not tmp_leftovers(tmp_path)


@pytest.mark.parametrize("groom_args", [[], ["--groom", "curly"]], ids=["drape", "curly"])
def test_head_center_needs_a_groom_file(cpu_bin, tmp_path, groom_args):
    out = tmp_path / "out.h5"
    p = run(cpu_bin, *groom_args, "--head-center", "0,0,0", "--strands", 4, "--points", 5, "--output", out,
            check=False)  # fmt: skip
    assert p.returncode == 2 and len(p.stderr.strip().splitlines()) == 1, p.stderr
    assert "--head-center needs --groom FILE" in p.stderr and not out.exists()


SCENE = (
    'model = "dynamic"\nstages = ["init", "simulate"]\ngroom = "lock.hair"\n{head}[hair]\npoints = 5\n'
    "[dynamics]\nframes = 2\n[constraints]\nbend_compliance = 1e-6\n"
)


def test_scene_head_center_through_harness_run(tmp_path, off_sphere):
    """`[head] center` (and radius) in a scene with a groom file reach the binary through `harness
    run`; without the centre the same scene is refused by the binary's fit."""
    from harness.cli.main import main as harness_main

    given = tmp_path / "given.toml"
    given.write_text(SCENE.format(head=f"[head]\ncenter = [{centre_arg((0, 0, 0))}]\nradius = 9.75\nmotion = 'nod'\n"))
    flags = scenes.load_scene(str(given)).flags()
    assert flags[flags.index("--head-center") + 1] == "0.0,0.0,0.0"
    assert flags[flags.index("--head-radius") + 1] == "9.75"
    out = tmp_path / "given.h5"
    assert harness_main(["run", str(given), "--output", str(out)]) == 0
    with open_trajectory(out) as t:
        assert t.params["groom_head"] == "given" and t.params["head_radius"] == 9.75 and len(t.simulated) == 2
    fitted = tmp_path / "fitted.toml"
    fitted.write_text(SCENE.format(head=""))
    assert "--head-center" not in scenes.load_scene(str(fitted)).flags()
    out2 = tmp_path / "fitted.h5"
    assert harness_main(["run", str(fitted), "--output", str(out2)]) != 0 and not out2.exists()


@pytest.mark.parametrize(
    "data, words",
    [
        ({"groom": "g.hair", "head": {"center": [1, 2]}}, "head.center must be a list of three numbers"),
        ({"groom": "g.hair", "head": {"center": [1, 2, "x"]}}, "head.center[2] must be a number"),
        ({"groom": "g.hair", "head": {"center": [1, 2, float("nan")]}}, "head.center[2] is NaN"),
        ({"groom": "g.hair", "head": {"radius": 12.0}}, "head.radius with a groom file needs head.center"),
        ({"groom": "curly", "head": {"center": [0, 0, 0]}}, 'head.center needs groom = "FILE"'),
        ({"head": {"center": [0, 0, 0]}}, 'head.center needs groom = "FILE"'),
    ],
)
def test_scene_head_center_refused(data, words):
    with pytest.raises(scenes.SceneError) as e:
        scenes.scene_from_dict({"model": "dynamic", "stages": ["init", "simulate"], **data}, "x", "scene x")
    assert words in str(e.value)


def test_the_stability_map_runs_on_a_users_groom(tmp_path, off_sphere):
    """`harness stability --scene FILE` runs substeps against iterations over a user's groom scene,
    named after it, and its report reads the shared axes; --scene with --slice is refused."""
    from harness.cli.main import main as harness_main
    from harness.render import stability_dynamic_report as stability_report
    from harness.studies import stability_dynamic as stability
    from harness.studies import stability_slices_dynamic as stability_slices

    scene = tmp_path / "mylock.toml"
    scene.write_text(SCENE.format(head=f"[head]\ncenter = [{centre_arg((0, 0, 0))}]\n"))
    rows, _, _ = stability.measure(scene=str(scene), quick=True, strands=2, frames=2, jobs=2, gpu="no",
                                   log=lambda *_: None)  # fmt: skip
    assert {r["slice"] for r in rows} == {"mylock-substeps-iterations"}
    assert {(int(r["row"]), int(r["col"])) for r in rows} == {(s, i) for s in (1, 4, 16, 64) for i in (1, 8, 128)}
    assert all(r["verdict"] in stability_slices.VERDICTS for r in rows), {r["verdict"] for r in rows}
    assert stability_report.axis_of("mylock-substeps-iterations", "--iterations") == ("I", "")
    assert harness_main(["stability", "--scene", str(scene), "--slice", "motion", "--out", str(tmp_path / "s")]) == 2
    assert not (tmp_path / "s").exists()
