"""The example groom the project ships (configs/grooms/example.hair) and the way back from its own
files to a groom: the example is what its recipe makes (the curly groom's init in fp64, exported
as HAIR: `harness export --hair-only --frame 0`), the binary reads it and simulates from it, the
harness's HAIR reader agrees with the published layout, and the project's own USD export reads
back as a groom (usd-core, optional): its first time sample, the same bits as the HAIR export."""

import struct

import numpy as np
import pytest
from test_grooms import POINTS, THICKNESS, hair_bytes

from conftest import ROOT
from harness.cli.main import main as harness_main
from harness.core import tolerances
from harness.core.ulp import ulp_distance
from harness.io import grooms
from harness.io.trajectory import open_trajectory
from support.statecheck import run

EXAMPLE = ROOT / "configs" / "grooms" / "example.hair"
STRANDS, P = 256, 24
# the recipe, as docs/user_scene.md gives it (the binary's flags, then the export)
RECIPE = ["--groom", "curly", "--strands", STRANDS, "--points", P, "--stages", "init", "--precision", "fp64"]


def test_the_example_is_what_its_recipe_makes(cpu_bin, tmp_path):
    run(cpu_bin, *RECIPE, "--output", tmp_path / "ex.h5", "--quiet")
    assert harness_main(["export", str(tmp_path / "ex.h5"), "--hair-only", "--frame", "0"]) == 0
    made, shipped = grooms.read_hair(tmp_path / "ex.h5.hair"), grooms.read_hair(EXAMPLE)
    assert len(shipped) == len(made) == STRANDS and all(s.shape == (P, 3) for s in shipped)
    worst = int(ulp_distance(np.concatenate(made), np.concatenate(shipped), np.float32).max())
    assert worst <= tolerances.GROOM_EXAMPLE_ULPS, worst


def test_the_binary_reads_the_example_and_simulates_from_it(cpu_bin, tmp_path):
    out = tmp_path / "g.h5"
    run(cpu_bin, "--groom", EXAMPLE, "--points", 16, "--stages", "init,simulate", "--frames", 3, "--output", out)
    with open_trajectory(out) as t:
        last = t.frame(t.n_frames - 1)
        assert t.n_strands == STRANDS and last.shape == (STRANDS, 16, 3) and np.isfinite(last).all()


def test_the_reader_follows_the_published_layout(tmp_path):
    """Strands of 2, 3 and 4 points with a segments array and a thickness array after the points;
    then three of 5 points without a segments array (the header's default count)."""
    strands = [[(i, j, 0.5 * j) for j in range(n)] for i, n in enumerate((2, 3, 4))]
    (tmp_path / "a.hair").write_bytes(hair_bytes(strands, thickness=True))
    got = grooms.read_hair(tmp_path / "a.hair")
    assert [s.tolist() for s in got] == [[list(p) for p in s] for s in strands]
    same = [[(i, j, 0.0) for j in range(5)] for i in range(3)]
    (tmp_path / "b.hair").write_bytes(hair_bytes(same, flags=POINTS | THICKNESS * 0, default_segments=4))
    assert [len(s) for s in grooms.read_hair(tmp_path / "b.hair")] == [5, 5, 5]
    short = hair_bytes(strands)[:-5]
    (tmp_path / "c.hair").write_bytes(short)
    with pytest.raises(Exception, match="shorter than its header says"):
        grooms.read_hair(tmp_path / "c.hair")
    (tmp_path / "d.hair").write_bytes(b"NOPE" + struct.pack("<I", 1) * 31)
    with pytest.raises(Exception, match="not a HAIR file"):
        grooms.read_hair(tmp_path / "d.hair")


def test_the_projects_usd_export_reads_back_as_a_groom(cpu_bin, tmp_path):
    pytest.importorskip("pxr", reason="usd-core is not installed (optional: USD export and grooms need it)")
    state = tmp_path / "d.h5"
    run(cpu_bin, "--strands", 40, "--points", 12, "--stages", "init,collide,simulate", "--frames", 4, "--output", state)
    assert harness_main(["export", str(state), "--usd-only"]) == 0
    assert harness_main(["export", str(state), "--hair-only", "--frame", "0", "--out", str(tmp_path / "f0")]) == 0
    assert harness_main(["groom", "convert", str(tmp_path / "d.h5.usdc"), str(tmp_path / "back.hair")]) == 0
    back, first = grooms.read_hair(tmp_path / "back.hair"), grooms.read_hair(tmp_path / "f0.hair")
    assert len(back) == 40 and np.array_equal(np.concatenate(back), np.concatenate(first))  # -0.0 == 0.0
    run(
        cpu_bin,
        "--groom",
        tmp_path / "back.hair",
        "--stages",
        "init,simulate",
        "--frames",
        2,
        "--output",
        tmp_path / "g.h5",
    )
