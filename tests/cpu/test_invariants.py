"""The invariants of docs/model.md §2.7 as harness/check/invariants.py checks them: each planted violation
is found and named, valid states pass, and the real C reference's outputs pass."""

import subprocess

import numpy as np
import pytest

from conftest import CPU_BIN
from harness.check import invariants
from harness.io.states import open_state
from support.synthetic import radial_strands, write_state

STAGES = ["init", "collide", "wind", "collide"]
needs_cpu = pytest.mark.skipif(not CPU_BIN.exists(), reason=f"{CPU_BIN} is not built (run make)")


def check(tmp_path, positions, stages=STAGES, **kw):
    path = write_state(tmp_path / "s.h5", positions, stages, **kw)
    with open_state(path) as s:
        return invariants.check(s)


def names(report):
    return {(v.frame, v.invariant) for v in report.violations}


@pytest.mark.parametrize("dtype", [np.float64, np.float32])
def test_valid_state_passes(tmp_path, dtype):
    rep = check(tmp_path, radial_strands(40, 16, STAGES, dtype=dtype))
    assert rep.ok, [v.message for v in rep.violations]
    assert rep.worst_segment_k < 1


def test_moved_root(tmp_path):
    x = radial_strands(10, 8, STAGES)
    x[2, 4, :, 1] += 1e-9  # the whole strand shifts: only its root is wrong
    assert names(check(tmp_path, x)) == {(2, "roots")}


def test_strand_leaves_its_plane(tmp_path):
    x = radial_strands(10, 8, STAGES)
    x[1, 3, 5, 0] = np.nextafter(x[1, 3, 5, 0], np.inf)  # one ulp is already a violation
    assert names(check(tmp_path, x)) == {(1, "x_constant")}


def test_stretched_segment(tmp_path):
    x = radial_strands(10, 8, STAGES)
    x[3, 7, 7, 1] += 1e-6  # the last segment grows by ~1e-6 ≫ 16 ε·E in fp64
    rep = check(tmp_path, x)
    assert names(rep) == {(3, "segments")}
    assert "segment length" in rep.violations[0].message


def test_point_inside_shell_only_matters_after_collide(tmp_path):
    x = radial_strands(10, 8, STAGES)
    root = x[0, 2, 0]
    radial = root[1:] / np.hypot(root[1], root[2])
    turn = np.radians(150)  # the strand points into the head: its points are inside the shell
    c, s = np.cos(turn), np.sin(turn)
    inward = np.array([c * radial[0] + s * radial[1], -s * radial[0] + c * radial[1]])
    ell = 30.0 / 7
    for k in range(8):
        x[:, 2, k, 1:] = root[1:] + k * ell * inward
    found = names(check(tmp_path, x))
    assert (1, "shell") in found and (3, "shell") in found
    assert (0, "shell") not in found and (2, "shell") not in found  # init and wind frames
    assert not any(name != "shell" for _, name in found)


def test_nan_and_inf(tmp_path):
    x = radial_strands(10, 8, STAGES)
    x[2, 1, 3, 2] = np.nan
    x[3, 1, 3, 2] = np.inf
    found = names(check(tmp_path, x))
    assert (2, "finite") in found and (3, "finite") in found


def test_skipped_stage_must_be_a_copy(tmp_path):
    x = radial_strands(10, 8, STAGES)
    x[2] = x[1]
    assert check(tmp_path, x, skipped=[0, 0, 1, 0]).ok
    x[2, 0, 3, 1] += 1e-3
    x[2, 0, 4:, 1] += 1e-3
    assert (2, "skipped") in names(check(tmp_path, x, skipped=[0, 0, 1, 0]))


@needs_cpu
@pytest.mark.parametrize("precision", ["fp32", "fp64"])
@pytest.mark.parametrize(
    "scene",
    [
        ["--wind-strength", "0.5"],
        ["--wind-strength", "1", "--points", "8"],
        ["--wind-strength", "0", "--points", "64"],
    ],
)
def test_real_cpu_output_holds_every_invariant(tmp_path, precision, scene):
    out = tmp_path / "cpu.h5"
    subprocess.run(
        [str(CPU_BIN), "--strands", "2000", "--precision", precision, "--quiet", "--output", str(out), *scene],
        check=True,
    )
    with open_state(out) as s:
        rep = invariants.check(s)
        if "0" in scene:
            assert s.skipped[2]
    assert rep.ok, [v.message for v in rep.violations]
