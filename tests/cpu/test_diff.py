"""`harness diff`: exit codes on planted cases, frame selection, ULP distance, tolerances.

Most files are written with support.synthetic (the documented layout, no backend needed);
the last tests use the real build/hairsim-cpu and are skipped, with the reason, without it.
"""

import json
import subprocess
import sys

import h5py
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from conftest import CPU_BIN, ROOT
from harness.check.diff import compare
from harness.cli.main import main
from harness.core import tolerances
from harness.core.ulp import ulp_distance
from support.synthetic import radial_strands, write_state

STAGES = ["init", "collide", "wind", "collide"]
needs_cpu = pytest.mark.skipif(not CPU_BIN.exists(), reason=f"{CPU_BIN} is not built (run make)")


@pytest.fixture
def ref64():
    return radial_strands(50, 8, STAGES, dtype=np.float64)


def write(tmp_path, name, positions, stages=STAGES, **kw):
    return str(write_state(tmp_path / name, positions, stages, **kw))


def run_diff(capsys, *args):
    code = main(["diff", *map(str, args)])
    out = capsys.readouterr()
    return code, out.out, out.err


def test_identical_files_are_equivalent(tmp_path, ref64, capsys):
    a = write(tmp_path, "a.h5", ref64)
    b = write(tmp_path, "b.h5", ref64)
    code, out, _ = run_diff(capsys, a, b)
    assert code == 0
    assert "verdict: EQUIVALENT" in out


def test_one_moved_point_is_not_equivalent(tmp_path, ref64, capsys):
    moved = ref64.copy()
    moved[2, 17, 5, 1] += 1e-6  # far above fp64 rounding, far below a segment
    a = write(tmp_path, "a.h5", ref64)
    b = write(tmp_path, "b.h5", moved)
    code, out, _ = run_diff(capsys, a, b, "--json")
    assert code == 1
    r = json.loads(out)
    frames = {f["frame_a"]: f for f in r["frames"]}
    assert frames[2]["over"] == 1 and not frames[2]["ok"]
    assert frames[1]["over"] == 0 and frames[3]["over"] == 0
    assert frames[2]["max_abs"] == pytest.approx(1e-6, rel=1e-6)


def test_nan_never_passes(tmp_path, ref64, capsys):
    bad = ref64.copy()
    bad[3, 0, 7, 2] = np.nan
    a = write(tmp_path, "a.h5", ref64)
    b = write(tmp_path, "b.h5", bad)
    code, out, _ = run_diff(capsys, a, b, "--json")
    assert code == 1
    r = json.loads(out)
    assert r["frames"][3]["nonfinite"] == 1
    assert any(v["invariant"] == "finite" for v in r["invariants_b"]["violations"])
    # NaN in both files at the same place does not pass either
    code, _, _ = run_diff(capsys, b, b)
    assert code == 1


def test_missing_frame_cannot_compare(tmp_path, ref64, capsys):
    a = write(tmp_path, "a.h5", ref64)
    b = write(tmp_path, "b.h5", ref64[:3], stages=STAGES[:3])
    code, _, err = run_diff(capsys, a, b)
    assert code == 2
    assert err.startswith("harness: error: cannot compare:") and "frame counts differ" in err
    assert err.count("\n") == 1  # one line


@pytest.mark.parametrize(
    "change, message",
    [
        ("strands", "different sizes"),
        ("points", "different sizes"),
        ("shape", "expected [F][N·P][3]"),
        ("no_stage", "no /parameters/stage"),
        ("count_attr", "n_strands × points_per_strand"),
        ("precision_attr", "precision attribute says"),
        ("scene", "different scenes: hair_length"),
    ],
)
def test_layout_mismatch_cannot_compare(tmp_path, ref64, capsys, change, message):
    a = write(tmp_path, "a.h5", ref64)
    if change == "strands":
        b = write(tmp_path, "b.h5", ref64[:, :40])
    elif change == "points":
        b = write(tmp_path, "b.h5", radial_strands(50, 9, STAGES))
    elif change == "scene":
        b = write(tmp_path, "b.h5", ref64, params={"hair_length": 31.0})
    else:
        b = write(tmp_path, "b.h5", ref64)
        with h5py.File(b, "r+") as f:
            if change == "shape":
                del f["particles/hair/position/value"]
                f["particles/hair/position/value"] = np.zeros((4, 400, 2))
            elif change == "no_stage":
                del f["parameters/stage"]
            elif change == "count_attr":
                f["parameters"].attrs["n_strands"] = 49
            elif change == "precision_attr":
                f["parameters"].attrs["precision"] = "fp32"
    code, _, err = run_diff(capsys, a, b)
    assert code == 2, err
    assert message in err


def test_unreadable_files_cannot_compare(tmp_path, ref64, capsys):
    a = write(tmp_path, "a.h5", ref64)
    text = tmp_path / "notes.h5"
    text.write_text("this is not HDF5\n")
    code, _, err = run_diff(capsys, a, text)
    assert code == 2 and "not an HDF5 file" in err
    code, _, err = run_diff(capsys, a, tmp_path / "absent.h5")
    assert code == 2 and "no such file" in err
    empty = tmp_path / "empty.h5"
    h5py.File(empty, "w").close()
    code, _, err = run_diff(capsys, empty, a)
    assert code == 2 and "not a hairbench state" in err


def test_different_stages_cannot_compare(tmp_path, ref64, capsys):
    a = write(tmp_path, "a.h5", ref64)
    b = write(tmp_path, "b.h5", ref64, stages=["init", "collide", "collide", "collide"])
    code, _, err = run_diff(capsys, a, b)
    assert code == 2 and "frame 2 of A is 'wind'" in err


def test_cli_exit_status_and_no_traceback(tmp_path, ref64):
    """The real process: exit 2 and one line on stderr, never a traceback."""
    a = write(tmp_path, "a.h5", ref64)
    junk = tmp_path / "junk.h5"
    junk.write_bytes(b"\x89HDF\r\n\x1a\n" + b"\0" * 64)  # an HDF5 signature, then nothing
    p = subprocess.run(
        [sys.executable, "-m", "harness", "diff", a, str(junk)], cwd=ROOT, capture_output=True, text=True
    )
    assert p.returncode == 2
    assert "Traceback" not in p.stderr
    assert p.stderr.startswith("harness: error:") and p.stderr.count("\n") == 1


def test_frame_selection_for_a_resumed_file(tmp_path, ref64, capsys):
    """A GPU file resumed from a CPU state has its own frame count: compare chosen frames."""
    a = write(tmp_path, "a.h5", ref64)
    resumed = write(tmp_path, "r.h5", ref64[:3], stages=STAGES[:3])
    assert run_diff(capsys, a, resumed, "--frames", "last")[0] == 2  # frame 3 vs 2: stages differ
    assert run_diff(capsys, a, resumed, "--frame", "2")[0] == 0
    assert run_diff(capsys, a, resumed, "--frame", "3")[0] == 2  # B has no frame 3
    assert run_diff(capsys, resumed, a, "--frames", "0,1")[0] == 0
    # the last frames of files with different counts line up only when asked
    tail = write(tmp_path, "t.h5", ref64[1:], stages=STAGES[1:])
    assert run_diff(capsys, a, tail)[0] == 2
    code, out, _ = run_diff(capsys, a, tail, "--align-last", "--json")
    assert code == 0
    assert [(f["frame_a"], f["frame_b"]) for f in json.loads(out)["frames"]] == [(1, 0), (2, 1), (3, 2)]


def test_fp32_rounding_of_fp64_is_equivalent(tmp_path, ref64, capsys):
    a = write(tmp_path, "a.h5", ref64)
    b = write(tmp_path, "b.h5", ref64.astype(np.float32))
    code, out, _ = run_diff(capsys, a, b, "--json")
    r = json.loads(out)
    assert code == 0, r["failures"]
    assert r["pair"] == "fp64↔fp32"
    # a rounding to fp32 is at most half an ulp of fp32: ULPs are counted in fp32
    assert all(f["ulp_max"] == 0 for f in r["frames"])


def test_exact_mode_and_fast_math_pair(tmp_path, ref64, capsys):
    nudged = ref64.copy()
    nudged[1, 3, 4, 2] = np.nextafter(nudged[1, 3, 4, 2], np.inf)
    a = write(tmp_path, "a.h5", ref64)
    b = write(tmp_path, "b.h5", nudged)
    assert run_diff(capsys, a, b)[0] == 0  # one ulp is within the fp64 tolerance
    assert run_diff(capsys, a, b, "--exact")[0] == 1
    fm = write(tmp_path, "fm.h5", ref64.astype(np.float32), params={"flags": "nvcc --use_fast_math"})
    r = compare(a, fm)
    assert r.pair == "fp64↔fp32-fastmath"
    assert r.tolerance == tolerances.pair_tolerance("fp32-fastmath", "fp64")


def test_tolerance_scales_with_root_conditioning():
    """u grows where the root draw cancels (x0 → 0) and is the step term for equal roots."""
    kw = dict(head_radius=10.0, hair_offset=0.1, hair_length=30.0, points=32, eps=2.0**-23)
    u = tolerances.point_unit(np.array([10.0, 1.0, 1e-2, 1e-3, 0.0]), np.zeros(5), **kw)
    assert np.all(np.diff(u[:3]) > 0)
    assert u[3] == u[4]  # below √ε·R the bound is the cancellation's worst case
    same = tolerances.point_unit(np.array([0.0]), np.array([0.0]), root_differs=np.array([False]), **kw)
    assert same[0] == pytest.approx(kw["eps"] * 32 * 40.1)


# ---- ULP distance ------------------------------------------------------------------------


def test_ulp_distance_basics():
    f = np.float32
    one = f(1.0)
    assert ulp_distance(np.array([one]), np.array([np.nextafter(one, f(2))]), np.float32)[0] == 1
    assert ulp_distance(np.array([0.0], f), np.array([-0.0], f), np.float32)[0] == 0
    tiny = np.nextafter(f(0), f(1))
    assert ulp_distance(np.array([tiny]), np.array([-tiny]), np.float32)[0] == 2
    big = np.finfo(np.float64).max
    d = ulp_distance(np.array([big]), np.array([-big]), np.float64)[0]
    assert d == 2 * 0x7FEFFFFFFFFFFFFF  # no overflow
    # mixed precision: counted in float32 after rounding both to it
    assert ulp_distance(np.array([1.0 + 2.0**-30]), np.array([1.0], np.float32), np.float32)[0] == 0


@settings(max_examples=200, deadline=None)
@given(st.floats(allow_nan=False, allow_infinity=False, width=32), st.integers(1, 1000))
def test_ulp_distance_counts_steps(x, k):
    a = np.array([x], np.float32)
    b = a.copy()
    with np.errstate(over="ignore"):
        for _ in range(k):
            b = np.nextafter(b, np.float32(np.inf))
    if np.isinf(b[0]):
        return
    assert ulp_distance(a, b, np.float32)[0] == k
    assert ulp_distance(b, a, np.float32)[0] == k


# ---- against the real C reference -------------------------------------------------------


@needs_cpu
def test_cpu_fp32_against_fp64_and_threads(tmp_path, capsys):
    files = {}
    for name, extra in (
        ("fp64", ["--precision", "fp64"]),
        ("fp32", ["--precision", "fp32"]),
        ("fp64t1", ["--precision", "fp64", "--threads", "1"]),
    ):
        files[name] = tmp_path / f"{name}.h5"
        subprocess.run(
            [str(CPU_BIN), "--strands", "3000", "--points", "32", "--quiet", "--output", str(files[name]), *extra],
            check=True,
        )
    code, out, _ = run_diff(capsys, files["fp32"], files["fp64"], "--json")
    r = json.loads(out)
    assert code == 0, r["failures"]
    assert 0 < max(f["max_k"] for f in r["frames"]) < r["tolerance"]["point_k"]
    assert run_diff(capsys, files["fp64"], files["fp64t1"], "--exact")[0] == 0
