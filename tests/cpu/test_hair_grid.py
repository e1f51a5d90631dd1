"""The hair–hair grid (docs/model.md §3.16) in the C reference: known answers.

- the per-point math (c_ref/dynamic/contact_impl.h, run by tests/cpu/c/grid_known.c on hand-made
  clouds): every point on one node with friction 1 takes the mean velocity and momentum is kept,
  to the fixed-point rounding bound; a uniform velocity field passes unchanged; adding a constant
  velocity commutes with friction; the volume term leaves hair at or below its target alone and
  pushes two overlapping clumps apart;
- the binary: the same bits on 1, 2 and 3 threads and when resumed (the sums are integers, so
  their order is free); hair bundled tightly spreads out with the volume term and stays bundled
  without it; bad grid flags are refused in one line.
"""

import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest

from harness.check.hair_volume_dynamic import hair_volume
from harness.core import tolerances
from harness.io.grooms import write_hair
from harness.io.trajectory import open_trajectory
from support.statecheck import run

ROOT = Path(__file__).resolve().parents[2]
SCENE = ["--strands", "120", "--points", "16", "--substeps", "4", "--iterations", "2", "--bend-compliance", "1e-6",
         "--head-motion", "nod", "--drag", "1", "--wind-speed", "150", "--gust-amplitude", "0.5"]  # fmt: skip
GRID = ["--grid", "12", "--grid-friction", "0.2,0.05", "--grid-volume", "3000"]


@pytest.fixture(scope="module")
def known(tmp_path_factory):
    cc = shutil.which("cc") or shutil.which("gcc")
    if cc is None:
        pytest.skip("no C compiler to build tests/cpu/c/grid_known.c")
    exe = tmp_path_factory.mktemp("grid") / "grid_known"
    subprocess.run([cc, "-std=c11", "-D_DEFAULT_SOURCE", "-O2", "-ffp-contract=off", f"-I{ROOT / 'c_ref'}",
                    str(ROOT / "tests/cpu/c/grid_known.c"), "-lm", "-o", str(exe)], check=True)  # fmt: skip
    out = subprocess.run([str(exe)], capture_output=True, text=True, check=True).stdout
    return {k: float(v) for k, v in (line.split() for line in out.splitlines())}


def test_one_node_takes_the_mean_and_keeps_momentum(known):
    bound = tolerances.GRID_FIXED_POINT_VELOCITY
    assert known["one_node_mean_error"] <= bound
    assert known["one_node_momentum_error"] <= 200 * bound  # 200 points


def test_cloud_keeps_its_momentum(known):
    # 2000 points, 8 corners each: a rounding of at most half a unit of 2^-10 cm/s a contribution
    assert known["cloud_momentum_error"] <= 2000 * 8 * tolerances.GRID_FIXED_POINT_VELOCITY


def test_uniform_field_and_galilean_invariance(known):
    assert known["uniform_change"] <= 2 * tolerances.GRID_FIXED_POINT_VELOCITY
    assert known["galilean_error"] <= 2 * tolerances.GRID_FIXED_POINT_VELOCITY


def test_volume_only_decompresses(known):
    assert known["below_target_change"] == 0.0
    assert known["clump_left_vx"] < -100.0 and known["clump_right_vx"] > 100.0


def _bits(path):
    with open_trajectory(path) as t:
        return np.concatenate([t.frame(f).ravel() for f in range(t.n_frames)]).view(np.uint8)


@pytest.mark.parametrize("rebuild", ["frame", "substep", "held"])
@pytest.mark.parametrize("precision", ["fp32", "fp64"])
def test_same_bits_on_any_thread_count_and_when_resumed(cpu_bin, tmp_path, rebuild, precision):
    args = ["--stages", "init,collide,simulate", *SCENE, *GRID, "--grid-rebuild", rebuild, "--precision", precision]
    outs = []
    for threads in (1, 2, 3):
        out = tmp_path / f"t{threads}.h5"
        run(cpu_bin, *args, "--frames", 4, "--threads", threads, "--velocities", "all", "--output", out, "--quiet")
        outs.append(_bits(out))
    assert all(np.array_equal(outs[0], o) for o in outs[1:])
    part, rest = tmp_path / "p.h5", tmp_path / "r.h5"
    run(cpu_bin, *args, "--frames", 2, "--output", part, "--quiet")
    run(cpu_bin, "--input", part, "--stages", "simulate", "--frames", 2, "--output", rest, "--quiet")
    with open_trajectory(tmp_path / "t1.h5") as a, open_trajectory(rest) as b:
        assert np.array_equal(a.frame(a.n_frames - 1).view(np.uint8), b.frame(b.n_frames - 1).view(np.uint8))


def test_volume_spreads_a_tight_bundle(cpu_bin, tmp_path):
    """Two bundles of 60 strands hanging through the same place (every strand within 0.15 cm of
    one line): the volume term spreads them over more cells; without it they stay bundled."""
    rng = np.random.default_rng(5)
    strands = []
    for _ in range(120):
        off = rng.uniform(-0.15, 0.15, 2)
        top = np.array([off[0], 12.0, off[1]])
        strands.append(np.array([top + [0.0, -k * 1.0, 0.0] for k in range(16)]))
    groom = tmp_path / "bundle.hair"
    write_hair(groom, strands)
    base = ["--groom", groom, "--head-center", "0,30,0", "--head-radius", "1", "--stages", "init,simulate",
            "--bend-compliance", "1e-6", "--substeps", "4", "--iterations", "2", "--no-collider", "--frames", 30,
            "--grid", "16", "--grid-padding", "4", "--quiet"]  # fmt: skip
    volumes = {}
    for name, extra in (("off", []), ("on", ["--grid-volume", "20000"])):
        out = tmp_path / f"{name}.h5"
        run(cpu_bin, *base, *extra, "--output", out)
        with open_trajectory(out) as t:
            volumes[name] = (hair_volume(t.frame(0)), hair_volume(t.frame(t.n_frames - 1)))
    assert volumes["off"][1] <= 1.25 * volumes["off"][0], volumes
    assert volumes["on"][1] >= 2.0 * volumes["on"][0], volumes


@pytest.mark.parametrize(
    "flags,message",
    [
        (["--grid-friction", "0.1"], "--grid-friction needs --grid N"),
        (["--grid", "1"], "--grid must be from 2 to 512"),
        (["--grid", "600"], "--grid must be from 2 to 512"),
        (["--grid", "16", "--grid-friction", "1.5"], "--grid-friction must be in [0, 1]"),
        (["--grid", "16", "--grid-friction", "0.1,0.2,0.3"], "--grid-friction needs 1 to 2 numbers"),
        (["--grid", "16", "--grid-box", "0,0,0,1,1"], "--grid-box needs 6 numbers"),
        (["--grid", "16", "--grid-box", "0,0,0,1,-1,1"], "--grid-box needs X0 < X1"),
        (["--grid", "16", "--grid-rebuild", "always"], "--grid-rebuild must be frame, substep or held"),
        (["--grid", "16", "--grid-volume", "-1"], "--grid-volume must be a finite number >= 0"),
        (["--grid", "16", "--strands", "70000000", "--points", "32"], "must be at most 2^31 points"),
    ],
)
def test_bad_grid_flags_are_refused_in_one_line(cpu_bin, tmp_path, flags, message):
    out = tmp_path / "o.h5"
    p = run(cpu_bin, "--stages", "init,collide,simulate", *flags, "--output", out, check=False)
    assert p.returncode == 2 and message in p.stderr and len(p.stderr.strip().splitlines()) == 1, p.stderr
    assert not out.exists()


def test_held_equals_frame_with_one_substep_and_differs_with_more(cpu_bin, tmp_path):
    """`held` samples the grid at the frame's first substep, where `frame` samples it too: with
    one substep a frame the two are the same bits; with four, later substeps differ."""
    bits = {}
    for substeps in (1, 4):
        for rebuild in ("frame", "held"):
            out = tmp_path / f"{rebuild}{substeps}.h5"
            scene = [str(substeps) if i and SCENE[i - 1] == "--substeps" else a for i, a in enumerate(SCENE)]
            args = [*scene, *GRID, "--grid-rebuild", rebuild, "--frames", 3]
            run(cpu_bin, "--stages", "init,collide,simulate", *args, "--velocities", "all", "--output", out, "--quiet")
            bits[rebuild, substeps] = _bits(out)
    assert np.array_equal(bits["frame", 1], bits["held", 1])
    assert not np.array_equal(bits["frame", 4], bits["held", 4])
