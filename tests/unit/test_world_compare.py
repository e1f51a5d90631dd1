"""tools/world_compare.sh refuses what it cannot time in one line, exit status 2, before it writes
anything (the GPU rows themselves run on a GPU node: results/reference-h200/world_timing.txt)."""

import shutil
import subprocess
import sys

import pytest

from conftest import ROOT

TOOL = ROOT / "tools" / "world_compare.sh"


@pytest.mark.parametrize(
    "builds, says",
    [
        ([], "give at least one build as NAME=BINARY"),
        (["head"], "'head' is not NAME=BINARY"),
        (["head=/nonexistent/hairsim-cuda"], "/nonexistent/hairsim-cuda is not an executable binary"),
        (["keep=HB_KEEP=1@/nonexistent/hairsim-cuda"], "/nonexistent/hairsim-cuda is not an executable binary"),
        (["keep=HB KEEP=1@/bin/true"], "'HB KEEP=1' in build 'keep' is not VAR=VALUE"),
        (["keep=HB_KEEP=1,=2@/bin/true"], "'=2' in build 'keep' is not VAR=VALUE"),
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


FAKE_ENV = """#!/bin/bash
echo "HB_FAKE=${HB_FAKE-unset} OTHER=${OTHER-unset}" >> "$(dirname "$0")/calls.txt"
echo "{\\"strands\\": 10000, \\"stages\\": [{\\"median_ms\\": 1.0, \\"min_ms\\": 1.0, \\"max_ms\\": 1.0}]}"
"""


def test_world_compare_runs_a_build_with_its_variables_alone(tmp_path):
    b = tmp_path / "hairsim-cuda"
    b.write_text(FAKE_ENV)
    b.chmod(0o755)
    env = {"PATH": "/usr/bin:/bin", "ROWS": "held", "SMALL": "10000", "LARGE": "", "ROUNDS": "1"}
    builds = [f"main={b}", f"probe=HB_FAKE=7,OTHER=x@{b}", f"again={b}"]
    r = subprocess.run(["bash", str(TOOL), str(tmp_path / "out"), *builds], cwd=ROOT, capture_output=True, text=True,
                       env=env)  # fmt: skip
    assert r.returncode == 0, r.stderr
    assert (tmp_path / "calls.txt").read_text().splitlines() == [
        "HB_FAKE=unset OTHER=unset",
        "HB_FAKE=7 OTHER=x",
        "HB_FAKE=unset OTHER=unset",
    ]
    assert [line.split()[0] for line in (tmp_path / "out" / "bench.txt").read_text().splitlines()] == [
        "main",
        "probe",
        "again",
    ]


# a build that writes one of two real states (HB_FAKE_ALT picks the other) wherever --output says
FAKE_STATE = """#!/bin/bash
src="$(dirname "$0")/a.h5"; [ -n "${HB_FAKE_ALT-}" ] && src="$(dirname "$0")/b.h5"
while [ $# -gt 0 ]; do [ "$1" = --output ] && cp "$src" "$2"; shift; done
echo "{\\"strands\\": 10000, \\"stages\\": [{\\"median_ms\\": 1.0, \\"min_ms\\": 1.0, \\"max_ms\\": 1.0}]}"
"""


def test_world_compare_bits_finds_the_build_whose_states_differ_before_timing(tmp_path, cpu_bin):
    run = [str(cpu_bin), "--stages", "init,collide,simulate", "--strands", "6", "--points", "8", "--frames", "2"]
    for name, gravity in (("a", "981"), ("b", "900")):
        subprocess.run([*run, "--gravity", gravity, "--output", str(tmp_path / f"{name}.h5"), "--quiet"], check=True)
    b = tmp_path / "hairsim-cuda"
    b.write_text(FAKE_STATE)
    b.chmod(0o755)
    env = {"PATH": "/usr/bin:/bin", "ROWS": "held", "SMALL": "10000", "LARGE": "", "BITS": "1",
           "PYTHON": sys.executable}  # fmt: skip
    out = tmp_path / "out"
    builds = [f"main={b}", f"copy={b}", f"other=HB_FAKE_ALT=1@{b}"]
    r = subprocess.run(["bash", str(TOOL), str(out), *builds], cwd=ROOT, capture_output=True, text=True, env=env)
    assert r.returncode == 1, r.stderr
    assert r.stderr.strip().splitlines()[-1] == "error: a build's states differ from main's (OUTDIR/bits.txt)"
    scenes = ("held", "substep", "body-once", "fp64-held")
    lines = (out / "bits.txt").read_text().splitlines()
    assert lines == [f"{n} {s} {v}" for n, v in (("main", "reference"), ("copy", "same"), ("other", "differs"))
                     for s in scenes]  # fmt: skip
    assert not (out / "bench.txt").exists()
    shutil.copy(tmp_path / "a.h5", tmp_path / "b.h5")  # now every build writes the same state: timed after
    shutil.rmtree(out)
    r = subprocess.run(["bash", str(TOOL), str(out), *builds], cwd=ROOT, capture_output=True, text=True, env=env)
    assert r.returncode == 0, r.stderr
    assert all(line.endswith((" reference", " same")) for line in (out / "bits.txt").read_text().splitlines())
    assert len((out / "bench.txt").read_text().splitlines()) == 3 * 2
