"""tools/world_compare.sh refuses what it cannot time in one line, exit status 2, before it writes
anything (the GPU rows themselves run on a GPU node: results/reference-h200/world_timing.txt)."""

import subprocess

import pytest

from conftest import ROOT

TOOL = ROOT / "tools" / "world_compare.sh"


@pytest.mark.parametrize(
    "builds, says",
    [
        ([], "give at least one build as NAME=BINARY"),
        (["head"], "'head' is not NAME=BINARY"),
        (["head=/nonexistent/hairsim-cuda"], "/nonexistent/hairsim-cuda is not an executable binary"),
    ],
)
def test_world_compare_refuses_bad_builds_before_writing(tmp_path, builds, says):
    out = tmp_path / "out"
    r = subprocess.run(["bash", str(TOOL), str(out), *builds], cwd=ROOT, capture_output=True, text=True)
    assert r.returncode == 2
    assert r.stderr.strip() == f"error: {says}"
    assert not out.exists()


def test_world_compare_refuses_an_unknown_row(tmp_path):
    out = tmp_path / "out"
    env = {"PATH": "/usr/bin:/bin", "ROWS": "sideways", "SMALL": "10", "LARGE": ""}
    r = subprocess.run(["bash", str(TOOL), str(out), "t=/bin/true"], cwd=ROOT, capture_output=True, text=True, env=env)
    assert r.returncode == 2
    assert r.stderr.strip() == "error: row 'sideways' is none of base, held, frame, substep"
    assert not out.exists()
