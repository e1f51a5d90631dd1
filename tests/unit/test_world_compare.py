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
    assert r.stderr.strip() == (
        "error: row 'sideways' is none of base, held, frame, substep, body, planes, headf (each with -once or not)"
    )
    assert not out.exists()


FAKE = """#!/bin/bash
echo "$0 $*" >> "$(dirname "$0")/calls.txt"
n=0; while [ $# -gt 0 ]; do [ "$1" = --strands ] && n=$2; shift; done
echo "{\\"strands\\": $n, \\"stages\\": [{\\"median_ms\\": 1.25, \\"min_ms\\": 1.0, \\"max_ms\\": 2.0}]}"
"""


def test_world_compare_runs_each_row_by_every_build_in_turn(tmp_path):
    bins = []
    for name in ("a", "b"):
        (tmp_path / name).mkdir()
        b = tmp_path / name / "hairsim-cuda"
        b.write_text(FAKE)
        b.chmod(0o755)
        bins.append(f"{name}={b}")
    out = tmp_path / "out"
    env = {"PATH": "/usr/bin:/bin", "ROWS": "held base", "SMALL": "10000", "LARGE": "", "ROUNDS": "2"}
    r = subprocess.run(["bash", str(TOOL), str(out), *bins], cwd=ROOT, capture_output=True, text=True, env=env)
    assert r.returncode == 0, r.stderr
    rows = [line.split()[:4] for line in (out / "bench.txt").read_text().splitlines()]
    assert rows == [[b, f"r{k}", w, "10000"] for k in (1, 2) for w in ("held", "base") for b in ("a", "b")]
    assert all(line.split()[4:7] == ["median", "1.2500", "ms"] for line in (out / "bench.txt").read_text().splitlines())
    held = (tmp_path / "a" / "calls.txt").read_text().splitlines()[0]
    assert "--grid 32 --grid-friction 0.05,0.01 --grid-volume 2000 --grid-rebuild held" in held
    assert "--variant lanes" in held and "--repeat 20" in held


def test_world_compare_runs_a_once_row_with_collide_once(tmp_path):
    b = tmp_path / "hairsim-cuda"
    b.write_text(FAKE)
    b.chmod(0o755)
    env = {"PATH": "/usr/bin:/bin", "ROWS": "headf headf-once", "SMALL": "10000", "LARGE": "", "ROUNDS": "1"}
    r = subprocess.run(["bash", str(TOOL), str(tmp_path / "out"), f"a={b}"], cwd=ROOT, capture_output=True, text=True,
                       env=env)  # fmt: skip
    assert r.returncode == 0, r.stderr
    every, once = (tmp_path / "calls.txt").read_text().splitlines()
    assert "--friction 0.3,0.2 --depenetration-speed 200" in every and "--collide-once" not in every
    assert once.replace(" --collide-once", "") == every and once.count("--collide-once") == 1
