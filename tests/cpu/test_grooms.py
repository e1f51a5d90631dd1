"""Grooms (docs/model.md §3.15): the HAIR file read back through --groom, its arc-length
resampling (exact for straight strands, within its stated bound for helices), the head
sphere fitted to the roots, bad files refused in one line, the curly groom's rest shape at
rest, and the per-segment path giving the uniform path's bits where every ℓ_k = ℓ.

Every file here is written by the test from the HAIR layout (a 128-byte header: "HAIR",
strand count, point count, array bits, default segments, thickness, transparency, colour,
88 bytes of text; then the flagged arrays in order: segments as uint16, points as float32
xyz, thickness, transparency, colour)."""

import json
import math
import struct

import numpy as np
import pytest
from test_cpu_simd import needs_simd
from test_cpu_simd_dynamic import ALL, SOLVE

from harness.check import diff_dynamic as dyndiff
from harness.core import scenes
from harness.io.trajectory import open_trajectory
from support.statecheck import run, tmp_leftovers

SEGMENTS, POINTS, THICKNESS = 1, 2, 4


def hair_bytes(strands, flags=SEGMENTS | POINTS, count_points=None, default_segments=0, thickness=False):
    """A HAIR file holding `strands` (lists of xyz points), as the published layout lays it out."""
    pts = [p for s in strands for p in s]
    n_points = len(pts) if count_points is None else count_points
    flags |= THICKNESS if thickness else 0
    head = struct.pack("<4sIIII", b"HAIR", len(strands), n_points, flags, default_segments)
    head += struct.pack("<ff3f", 0.01, 0.0, 0.5, 0.5, 0.5) + b"test groom".ljust(88, b"\0")
    assert len(head) == 128
    body = b""
    if flags & SEGMENTS:
        body += struct.pack(f"<{len(strands)}H", *[len(s) - 1 for s in strands])
    body += np.asarray(pts, dtype="<f4").tobytes()
    if thickness:
        body += np.full(len(pts), 0.01, dtype="<f4").tobytes()
    return head + body


def radial_strands(centre, radius, lengths, points):
    """Straight strands along the outward normals of six roots on a sphere (the axes), of the
    given lengths, each sampled at `points` points (a list, one count a strand)."""
    normals = [(1, 0, 0), (-1, 0, 0), (0, 1, 0), (0, -1, 0), (0, 0, 1), (0, 0, -1)]
    out = []
    for n, length, m in zip(normals, lengths, points):
        n = np.asarray(n, float)
        t = np.linspace(0.0, length, m)
        out.append([tuple(np.asarray(centre) + (radius + ti) * n) for ti in t])
    return out


def groom_run(cpu_bin, path, *args, check=True):
    return run(cpu_bin, "--groom", path, "--json", "--quiet", *args, check=check)


def test_hair_read_back_straight_strands_exact(cpu_bin, tmp_path):
    """Six straight strands of different lengths and point counts around a head centred off the
    origin: the state is the strands moved to the fitted centre, resampled to P points equally
    spaced by arc length (exact for straight strands), roots first."""
    centre, R, P = (1.0, 2.0, 3.0), 10.0, 9
    lengths, counts = [8.0, 4.0, 16.0, 2.0, 8.0, 12.0], [5, 3, 17, 2, 33, 7]
    strands = radial_strands(centre, R, lengths, counts)
    groom = tmp_path / "straight.hair"
    groom.write_bytes(hair_bytes(strands, thickness=True))
    out = tmp_path / "s.h5"
    rec = json.loads(
        groom_run(cpu_bin, groom, "--points", P, "--stages", "init", "--precision", "fp64", "--output", out).stdout
    )
    assert rec["strands"] == 6 and rec["points"] == P
    assert rec["head_radius"] == pytest.approx(R, abs=1e-5)
    g = rec["groom"]
    assert g["file_strands"] == 6 and g["length_min"] == pytest.approx(2.0) and g["length_max"] == pytest.approx(16.0)
    assert g["resample_error"] <= 1e-12 * 16.0 and g["fit_offset"] <= 1e-5
    with open_trajectory(out) as t:
        x = t.frame(0)
    for i, (s, length) in enumerate(zip(strands, lengths)):
        root = np.asarray(s[0], np.float32).astype(np.float64) - np.asarray(centre)
        n = root / np.linalg.norm(root)
        want = root + np.outer(np.linspace(0.0, length, P), n)
        np.testing.assert_allclose(x[i], want, rtol=0, atol=1e-5, err_msg=f"strand {i}")


def helix(radius, pitch, length, n, axis_origin):
    """n points at equal arc length along a helix about +y through axis_origin, starting at
    axis_origin + (radius, 0, 0)."""
    c = pitch / (2 * math.pi)
    tau = np.linspace(0.0, length / math.hypot(radius, c), n)
    return np.stack([radius * np.cos(tau), c * tau, radius * np.sin(tau)], axis=1) + np.asarray(axis_origin)


def test_hair_helix_resampling_within_bound(cpu_bin, tmp_path):
    """Helices sampled densely in the file and resampled to P points: every file point lies
    within κ·Δs²/8 (+ the file polyline's own κ·δ²/8) of the resampled strand, κ = r/(r² + c²)
    the helix's curvature, Δs the resampled spacing, δ the file's; and the error is reported."""
    r, q, L, n, P = 1.0, 2.0, 20.0, 2001, 17
    strands = []
    for k in range(8):  # roots on a sphere of radius 10: helices about the local normal
        phi, theta = 2 * math.pi * k / 8, 0.3 + 0.15 * k
        n_out = np.array([math.cos(phi) * math.sin(theta), math.cos(theta), math.sin(phi) * math.sin(theta)])
        h = helix(r, q, L, n, (0, 0, 0))
        # rotate the helix's +y axis onto n_out, its start onto the root
        ax = np.cross([0, 1, 0], n_out)
        s, cth = np.linalg.norm(ax), n_out[1]
        ax = ax / s
        K = np.array([[0, -ax[2], ax[1]], [ax[2], 0, -ax[0]], [-ax[1], ax[0], 0]])
        rot = np.eye(3) + s * K + (1 - cth) * (K @ K)
        h = (h - h[0]) @ rot.T + 10.0 * n_out
        strands.append([tuple(p) for p in h])
    groom = tmp_path / "helix.hair"
    groom.write_bytes(hair_bytes(strands))
    rec = json.loads(groom_run(cpu_bin, groom, "--points", P, "--stages", "init", "--precision", "fp64").stdout)
    c = q / (2 * math.pi)
    kappa = r / (r * r + c * c)
    ds, delta = L / (P - 1), L / (n - 1)
    bound = kappa * ds * ds / 8 + kappa * delta * delta / 8
    err = rec["groom"]["resample_error"]
    assert 0.5 * kappa * ds * ds / 8 < err <= bound * (1 + 1e-6), (err, bound)


BAD_FILES = {
    "empty": lambda s: b"",
    "short_header": lambda s: hair_bytes(s)[:100],
    "not_hair": lambda s: b"RIAH" + hair_bytes(s)[4:],
    "no_strands": lambda s: hair_bytes([]),
    "truncated_points": lambda s: hair_bytes(s)[:-5],
    "wrong_counts": lambda s: hair_bytes(s, count_points=sum(len(x) for x in s) + 1),
    "nan": lambda s: hair_bytes([s[0][:1] + [(math.nan, 0.0, 0.0)] + s[0][2:]] + s[1:]),
    "zero_length_strand": lambda s: hair_bytes([[s[0][0]] * len(s[0])] + s[1:]),
    "single_point_strand": lambda s: hair_bytes([s[0][:1]] + s[1:]),
    "roots_off_sphere": lambda s: hair_bytes([[(x * 2, y * 2, z * 2) for x, y, z in s[0]]] + s[1:]),
    "no_points_array": lambda s: hair_bytes(s)[:12] + struct.pack("<I", SEGMENTS) + hair_bytes(s)[16:],
}
BAD_WORDS = {
    "empty": "is empty",
    "short_header": "truncated HAIR header",
    "not_hair": "not a HAIR file",
    "no_strands": "holds no strands",
    "truncated_points": "truncated",
    "wrong_counts": "wrong counts",
    "nan": "NaN",
    "zero_length_strand": "zero length",
    "single_point_strand": "zero length",
    "roots_off_sphere": "do not lie near one sphere",
    "no_points_array": "no points array",
}


@pytest.mark.parametrize("name", sorted(BAD_FILES))
def test_bad_hair_files_refused(cpu_bin, tmp_path, name):
    strands = radial_strands((0, 0, 0), 10.0, [4.0] * 6, [5] * 6)
    groom = tmp_path / f"{name}.hair"
    groom.write_bytes(BAD_FILES[name](strands))
    out = tmp_path / "out.h5"
    p = groom_run(cpu_bin, groom, "--points", 5, "--stages", "init,simulate", "--output", out, check=False)
    assert p.returncode == 2, p.stderr
    lines = p.stderr.strip().splitlines()
    assert len(lines) == 1 and BAD_WORDS[name] in lines[0], p.stderr
    assert not out.exists() and not tmp_leftovers(tmp_path)


@pytest.mark.parametrize(
    "args, words",
    [
        (["--groom", "curly", "--stages", "init,collide,simulate"], "a groom runs init then simulate"),
        (["--groom", "curly", "--stages", "init,simulate", "--lra"], "not defined for a groom"),
        (["--curl-radius", "2"], "need --groom curly"),
        (["--groom", "curly", "--curl-radius", "0", "--curl-pitch", "0", "--stages", "init"], "both 0"),
        (["--groom", "curly", "--curl-pitch", "-1"], "--curl-pitch must be >= 0"),
    ],
)
def test_groom_flags_refused(cpu_bin, tmp_path, args, words):
    out = tmp_path / "out.h5"
    p = run(cpu_bin, *args, "--strands", 4, "--points", 5, "--output", out, check=False)
    assert p.returncode == 2 and len(p.stderr.strip().splitlines()) == 1 and words in p.stderr, p.stderr
    assert not out.exists()


def test_groom_file_refuses_scene_geometry_flags(cpu_bin, tmp_path):
    groom = tmp_path / "g.hair"
    groom.write_bytes(hair_bytes(radial_strands((0, 0, 0), 10.0, [4.0] * 6, [5] * 6)))
    p = groom_run(cpu_bin, groom, "--head-radius", "12", "--stages", "init", check=False)
    assert p.returncode == 2 and "the file decides the head" in p.stderr


CURLY = ["--groom", "curly", "--strands", 12, "--points", 24, "--stages", "init,simulate", "--frames", 6]
REST_PHYSICS = ["--gravity", 0, "--bend-compliance", 0, "--shape-compliance", 1e-4, "--substeps", 4, "--iterations", 3]


def test_curly_rest_shape_is_at_rest(cpu_bin, tmp_path):
    """With gravity and wind off and the head still, the curly rest shape is an equilibrium of
    stretch (ℓ_k from the rest shape), bend and shape: in fp64 no point moves by one bit."""
    out = tmp_path / "curly.h5"
    run(cpu_bin, *CURLY, *REST_PHYSICS, "--precision", "fp64", "--output", out, "--velocities", "all", "--quiet")
    with open_trajectory(out) as t:
        x0 = t.frame(0)
        assert t.per_segment and np.array_equal(t.rest, x0)
        for f in t.simulated:
            assert np.array_equal(t.frame(f), x0), f"frame {f} moved"
        assert not np.any(t.velocity(-1))
        # the helix's chords are shorter than L/(P−1): the per-segment rest lengths are in use
        assert np.all(t.segment_rest() < t.hair_length / (t.points - 1))


def test_curly_moves_under_gravity_and_stays_valid(cpu_bin, tmp_path):
    """The curly scene's physics on a few strands: it moves, nothing blows up, and the dynamic
    invariants (observables recomputed with ℓ_k) hold."""
    from harness.check import invariants_dynamic

    out = tmp_path / "curly.h5"
    run(cpu_bin, *CURLY, "--bend-compliance", 1e-6, "--shape-compliance", 1e-4, "--head-motion", "nod", "--output", out)
    with open_trajectory(out) as t:
        assert not np.array_equal(t.frame(-1), t.frame(0))
        rep = invariants_dynamic.check(t)
        assert rep.ok, rep.violations[:3]


@pytest.mark.parametrize("solver", ["xpbd", "ftl"])
def test_per_segment_path_matches_uniform_path(cpu_bin, tmp_path, solver):
    """Straight grooms whose every segment is exactly ℓ = L/(P−1) (axis-aligned, integer
    coordinates): simulated through --groom (per-segment ℓ_k) and resumed from the groom's
    init state without it (uniform ℓ), every feature on, the two runs give the same bits."""
    P = 9
    groom = tmp_path / "axes.hair"
    groom.write_bytes(hair_bytes(radial_strands((0, 0, 0), 10.0, [8.0] * 6, [P] * 6)))
    physics = [
        "--solver", solver, "--frames", 5, "--substeps", 2, "--bend-compliance", 1e-6, "--shape-compliance", 1e-4,
        "--wind-speed", 150, "--drag", 0.5, "--gust-amplitude", 0.5, "--head-motion", "nod",
    ]  # fmt: skip
    a, init, b = tmp_path / "a.h5", tmp_path / "init.h5", tmp_path / "b.h5"
    run(cpu_bin, "--groom", groom, "--points", P, "--stages", "init,simulate", *physics, "--output", a, "--quiet")
    run(cpu_bin, "--groom", groom, "--points", P, "--stages", "init", "--output", init, "--quiet")
    run(cpu_bin, "--input", init, "--stages", "simulate", *physics, "--output", b, "--quiet")
    with open_trajectory(a) as ta, open_trajectory(b) as tb:
        assert ta.per_segment and not tb.per_segment
        assert np.array_equal(ta.segment_rest(), np.full((6, P - 1), tb.segment_rest()))
        moved = not np.array_equal(ta.frame(-1), ta.frame(0))
        assert moved and np.array_equal(ta.frame(-1), tb.frame(-1))


def test_curly_scene_flags():
    """configs/scenes/curly.toml: the groom and its helix reach the binary; a groom scene with a
    paper stage is refused naming the stage."""
    s = scenes.load_scene("curly")
    f = s.flags()
    assert f[:6] == ["--groom", "curly", "--curl-radius", "1.0", "--curl-pitch", "2.0"]
    assert s.stages == ("init", "simulate")
    with pytest.raises(scenes.SceneError, match="stage 'collide'"):
        scenes.scene_from_dict(
            {"model": "dynamic", "groom": "curly", "stages": ["init", "collide", "simulate"]}, "x", "scene x"
        )
    with pytest.raises(scenes.SceneError, match='need groom = "curly"'):
        scenes.scene_from_dict({"model": "dynamic", "hair": {"curl_radius": 2.0}}, "x", "scene x")


@needs_simd
@pytest.mark.parametrize("precision", ["fp32", "fp64"])
@pytest.mark.parametrize("solver", ["xpbd", "ftl"])
def test_simd_curly_within_the_rule(cpu_bin, tmp_path, precision, solver):
    """The simd variant on a curly groom (its ℓ_k as rows beside the bend rest lengths): one
    frame from ref's within the one-frame rule, as for the procedural scenes."""
    physics = ["--solver", solver, *ALL, *SOLVE]
    ref = tmp_path / "curly.h5"
    run(cpu_bin, "--groom", "curly", "--strands", 300, "--points", 33, "--stages", "init,simulate", "--frames", 3,
        "--precision", precision, *physics, "--velocities", "all", "--output", ref, "--quiet")  # fmt: skip
    with open_trajectory(ref) as t:
        cand = dyndiff.step_candidates(t)
        steps = {k: int(t.step[k + 1]) for k in cand}
    for k in (cand[0], cand[-2]):  # from the groom itself, and from a moving state
        out = tmp_path / f"simd_{k}.h5"
        run(cpu_bin, "--input", ref, "--input-frame", k, "--stages", "simulate", "--frames", 1, "--variant", "simd",
            *physics, "--velocities", "all", "--output", out, "--quiet")  # fmt: skip
        r = dyndiff.compare(ref, out, frames=[steps[k]], check_paper=False)
        assert r.frames[0].velocity_compared and r.equivalent, f"from frame {k}: " + "; ".join(r.failures()[:5])


def test_harness_hair_writer_read_back(cpu_bin, tmp_path):
    """harness/io/grooms.py's HAIR writer (what a converted USD groom becomes), read by the binary."""
    from harness.io import grooms

    strands = [np.asarray(s) for s in radial_strands((0, 0, 0), 10.0, [6.0] * 6, [4, 5, 6, 7, 3, 4])]
    path = grooms.write_hair(tmp_path / "w.hair", strands)
    with pytest.raises(Exception, match="exists"):
        grooms.write_hair(path, strands)
    rec = json.loads(groom_run(cpu_bin, path, "--points", 7, "--stages", "init", "--precision", "fp64").stdout)
    assert rec["strands"] == 6 and rec["groom"]["length_max"] == pytest.approx(6.0)


def test_usd_groom_converted(cpu_bin, tmp_path):
    """A USD BasisCurves groom written with usd-core, in metres and Z up, converted to HAIR
    (cm, Y up) and read by the binary: the strands come back 100× longer, along +y for a
    strand along +z."""
    pxr = pytest.importorskip("pxr", reason="usd-core is not installed (optional: USD grooms need it)")
    from pxr import Usd, UsdGeom, Vt  # noqa: F401

    from harness.io import grooms

    strands = radial_strands((0, 0, 0), 0.1, [0.06] * 6, [4] * 6)  # metres
    stage = Usd.Stage.CreateNew(str(tmp_path / "g.usda"))
    UsdGeom.SetStageMetersPerUnit(stage, 1.0)
    UsdGeom.SetStageUpAxis(stage, UsdGeom.Tokens.z)
    curves = UsdGeom.BasisCurves.Define(stage, "/hair")
    curves.CreateTypeAttr("linear")
    curves.CreatePointsAttr([tuple(map(float, p)) for s in strands for p in s])
    curves.CreateCurveVertexCountsAttr([len(s) for s in strands])
    stage.GetRootLayer().Save()
    assert pxr and grooms.convert(tmp_path / "g.usda", tmp_path / "g.hair") == 6
    out = tmp_path / "g.h5"
    rec = json.loads(groom_run(cpu_bin, tmp_path / "g.hair", "--points", 4, "--stages", "init", "--output", out).stdout)
    assert rec["head_radius"] == pytest.approx(10.0, rel=1e-5) and rec["groom"]["length_max"] == pytest.approx(6.0)
    with open_trajectory(out) as t:
        tip = t.frame(0)[4, -1]  # strand 4 runs along +z in the file: +y here
    np.testing.assert_allclose(tip, [0.0, 16.0, 0.0], atol=1e-4)


def test_usd_refused_without_usd_core(tmp_path):
    """Without usd-core a USD groom is refused in one line (skipped where usd-core is present)."""
    try:
        import pxr  # noqa: F401

        pytest.skip("usd-core is installed")
    except ImportError:
        pass
    from harness.cli.main import main as harness_main

    (tmp_path / "g.usda").write_text("#usda 1.0\n")
    assert harness_main(["groom", "convert", str(tmp_path / "g.usda"), str(tmp_path / "g.hair")]) != 0
    assert not (tmp_path / "g.hair").exists()


def test_harness_runs_a_groom_file_scene(tmp_path):
    """A scene whose groom names a HAIR file beside it: `harness run` passes the file, not the head
    flags the file decides, and the run's invariants hold."""
    from harness.cli.main import main as harness_main

    (tmp_path / "g.hair").write_bytes(hair_bytes(radial_strands((0, 0, 0), 10.0, [6.0] * 6, [7] * 6)))
    scene = tmp_path / "mine.toml"
    scene.write_text(
        'model = "dynamic"\nstages = ["init", "simulate"]\ngroom = "g.hair"\n[hair]\npoints = 8\n'
        "[dynamics]\nframes = 2\n[constraints]\nbend_compliance = 1e-6\n"
    )
    flags = scenes.load_scene(str(scene)).flags()
    assert "--head-radius" not in flags and flags[flags.index("--groom") + 1] == str(tmp_path / "g.hair")
    out = tmp_path / "mine.h5"
    assert harness_main(["run", str(scene), "--output", str(out)]) == 0
    with open_trajectory(out) as t:
        assert t.per_segment and t.n_strands == 6 and len(t.simulated) == 2
