"""Simulated-point LOD (docs/model.md §3.14, --render-points) in the C reference: known answers.
The rendered rows of a file recompute bit for bit from its simulated rows (harness/check/lod_dynamic.py);
the simulated rows are, bit for bit, the frames of the same run without --render-points (the
rendering changes nothing the simulation does); a spline through points on a straight line
stays on it; bad values are refused in one line (exit 2) and nothing is written. Tiny scenes
(≤ 30 strands, ≤ 8 simulated points, ≤ 4 frames)."""

import numpy as np
import pytest

from harness.check import lod_dynamic as lod
from harness.core import tolerances
from harness.io.trajectory import open_trajectory
from support.statecheck import run, run_json

TINY = ["--strands", "30", "--points", "8", "--hair-length", "20"]
SIM = ["--stages", "init,collide,simulate", "--frames", "4", "--velocities", "all"]
MOVING = ["--substeps", "2", "--iterations", "2", "--bend-compliance", "1e-6", "--head-motion", "nod",
          "--motion-frequency", "4"]  # fmt: skip


def bits(a):
    return np.ascontiguousarray(a).view(np.uint8)


@pytest.mark.parametrize("variant", ["ref", "simd"])
@pytest.mark.parametrize("precision", ["fp32", "fp64"])
def test_rendered_rows_recompute_bit_for_bit_and_keep_the_simulation(cpu_bin, tmp_path, precision, variant):
    common = [*SIM, *TINY, *MOVING, "--precision", precision, "--variant", variant, "--quiet"]
    plain, lodf = tmp_path / "plain.h5", tmp_path / "lod.h5"
    run(cpu_bin, *common, "--output", plain)
    rec = run_json(cpu_bin, *common, "--render-points", "22", "--output", lodf)
    sim = rec["stages"][-1]
    assert sim["render_points"] == 22 and sim["render_ms"] >= 0 and "lod" in sim["features"].split("+")
    assert sim["layout"] is None  # the cuda lanes kernel's shape alone
    with open_trajectory(plain) as a, open_trajectory(lodf) as b:
        assert (b.points, b.render_points, b.simulated_points) == (22, 22, 8)
        assert list(b.simulated_rows) == [0, 3, 6, 9, 12, 15, 18, 21]
        assert np.array_equal(bits(b.rest), bits(lod.render(a.rest, 22)))
        assert b.observables.equals(a.observables), "the observables are the simulation's"
        moved = False
        for f in range(b.n_frames):
            x = b.frame(f).reshape(b.n_strands, 22, 3)
            v = b.velocity_at_step(int(b.step[f]))
            want_x, want_v = lod.recompute(b, f, v)
            assert np.array_equal(bits(x), bits(want_x)), f"frame {f}: rendered rows differ from the spline"
            xs = a.frame(f).reshape(a.n_strands, 8, 3)
            assert np.array_equal(bits(x[:, b.simulated_rows]), bits(xs)), f"frame {f}: simulated rows changed"
            if v is not None:
                assert np.array_equal(bits(v), bits(want_v)), f"frame {f}: rendered velocities differ"
                assert np.array_equal(bits(v[:, b.simulated_rows]), bits(a.velocity_at_step(int(a.step[f]))))
            moved |= not np.array_equal(xs, a.rest)
            # the spline's own rows are not a copy of a neighbour: the curve is rendered
            assert not np.array_equal(x[:, 1], x[:, 0])
        assert moved, "the scene must move for the check to mean anything"


@pytest.mark.parametrize("dtype", [np.float32, np.float64])
def test_a_straight_strand_stays_straight_and_passes_its_points(dtype):
    rng = np.random.default_rng(7)
    base = rng.normal(size=(40, 1, 3)) * 10.0
    d = rng.normal(size=(40, 1, 3))
    d /= np.linalg.norm(d, axis=-1, keepdims=True)
    s = np.cumsum(rng.uniform(0.5, 1.5, size=(40, 9)), axis=1)  # uneven spacing
    x = (base + s[..., None] * d).astype(dtype)
    r = lod.render(x, 33)
    assert np.array_equal(bits(r[:, ::4]), bits(x)), "the spline passes through every simulated point"
    eps = float(np.finfo(dtype).eps)
    assert lod.straightness(r).max() <= tolerances.DYN_LOD_STRAIGHT_EPS * eps
    w = rng.normal(size=(40, 1, 3))  # a unit vector across each line
    w -= (w * d).sum(-1, keepdims=True) * d
    w /= np.linalg.norm(w, axis=-1, keepdims=True)
    bent = x.copy()
    bent[:, 4] += (0.3 * w[:, 0]).astype(dtype)
    assert lod.straightness(lod.render(bent, 33)).min() > 1e3 * tolerances.DYN_LOD_STRAIGHT_EPS * eps


def test_repeated_points_fall_back_to_the_chord():
    x = np.zeros((1, 4, 3), dtype=np.float64)
    x[0, :, 1] = [0.0, 1.0, 1.0, 2.0]  # a zero-length segment between points 1 and 2
    r = lod.render(x, 10)
    assert np.all(np.isfinite(r)) and np.array_equal(r[0, 3:7], np.repeat(x[0, 1:2], 4, axis=0))


@pytest.mark.parametrize(
    "args, message",
    [
        (["--render-points", "10"], "--render-points 10 must exceed --points 8"),
        (["--render-points", "8"], "--render-points 8 must exceed"),
        (["--render-points", "0"], "--render-points must be at least 1"),
        (["--render-points", "1.5"], "--render-points needs a whole number"),
    ],
)
def test_bad_render_points_are_refused(cpu_bin, tmp_path, args, message):
    out = tmp_path / "o.h5"
    p = run(cpu_bin, *SIM, *TINY, *args, "--output", out, check=False)
    assert p.returncode == 2 and message in p.stderr and len(p.stderr.strip().splitlines()) == 1
    assert not out.exists()


def test_render_points_needs_simulate_and_a_rendered_file_is_no_input(cpu_bin, tmp_path):
    p = run(cpu_bin, "--stages", "init,collide", *TINY, "--render-points", "15", check=False)
    assert p.returncode == 2 and "belongs to the simulate stage" in p.stderr
    rendered, plain = tmp_path / "r.h5", tmp_path / "p.h5"
    run(cpu_bin, *SIM, *TINY, "--render-points", "15", "--output", rendered, "--quiet")
    run(cpu_bin, *SIM, *TINY, "--output", plain, "--quiet")
    out = tmp_path / "o.h5"
    p = run(cpu_bin, "--input", rendered, "--stages", "simulate", "--output", out, check=False)
    assert p.returncode == 2 and "written with --render-points" in p.stderr and not out.exists()
    p = run(cpu_bin, "--input", plain, "--stages", "simulate", "--render-points", "15", "--output", out, check=False)
    assert p.returncode == 2 and "--render-points does not match" in p.stderr and not out.exists()


def test_help_and_list_variants_declare_lod(cpu_bin):
    assert "--render-points" in run(cpu_bin, "--help").stdout
    assert '"lod"' in run(cpu_bin, "--list-variants").stdout


def test_diff_of_two_rendered_files_judges_their_simulated_rows_and_recomputes_the_rendered(cpu_bin, tmp_path):
    """`harness diff` of two --render-points files (ref and simd, fp32, sag-free: the issue's kind of
    pair) applies the paper and dynamic checks to the simulated rows only (no 'left their slice
    plane' for a rendered point) and recomputes each file's rendered rows: equivalent; a rendered row
    moved by a hair is a 'rendered' violation; a rendered file against a plain one is refused (exit 2)."""
    import h5py

    from harness.check import diff_dynamic

    common = [*SIM, *TINY, *MOVING, "--shape-compliance", "1e-4", "--sag-free", "--quiet"]
    a, b, plain = tmp_path / "a.h5", tmp_path / "b.h5", tmp_path / "plain.h5"
    run(cpu_bin, *common, "--render-points", "22", "--variant", "ref", "--output", a)
    run(cpu_bin, *common, "--render-points", "22", "--variant", "simd", "--output", b)
    run(cpu_bin, *common, "--output", plain)
    r = diff_dynamic.compare(a, b)
    assert r.equivalent, r.failures()[:3]
    assert r.invariants_a.ok and not r.invariants_a.paper.violations
    with h5py.File(b, "r+") as f:
        pos = f["particles/hair/position/value"]
        x = pos[-1]
        x[1] += np.float32(1e-3)  # strand 0, rendered row 1 (between simulated rows 0 and 3)
        pos[-1] = x
    r = diff_dynamic.compare(a, b)
    assert not r.equivalent and any(v.invariant == "rendered" for v in r.invariants_b.violations)
    with pytest.raises(diff_dynamic.StateError, match="compare files rendered alike"):
        diff_dynamic.compare(a, plain)
