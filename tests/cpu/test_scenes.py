"""Scene and sweep files: the shipped ones load, bad ones are refused naming the key, and
`harness run` turns a scene into the backend's flags."""

import json
import subprocess
import sys

import pytest

from conftest import CPU_BIN, ROOT
from harness.core import scenes
from harness.core.paths import SWEEPS
from harness.io.sweepfile import load_sweep

needs_cpu = pytest.mark.skipif(not CPU_BIN.exists(), reason=f"{CPU_BIN} is not built (run make)")

GOOD = """
stages = ["init", "collide", "wind", "collide"]
precision = "fp64"
seed = 7
[head]
radius = 12.0
face_margin = 0.5
[hair]
strands = 300
points = 16
length = 20.0
offset = 0.2
[wind]
strength = 0.25
angle = 3.0
"""


def scene_file(tmp_path, text, name="s.toml"):
    p = tmp_path / name
    p.write_text(text)
    return p


def refused(tmp_path, text):
    with pytest.raises(scenes.SceneError) as e:
        scenes.load_scene(scene_file(tmp_path, text))
    return str(e.value)


def test_shipped_scenes():
    expected = {
        "paper": ("init", "collide", "wind", "collide"),
        "still": ("init",),
        "breeze": ("init", "collide", "wind", "collide"),
        "gale": ("init", "collide", "wind", "collide"),
    }
    for name, stages in expected.items():
        s = scenes.load_scene(name)
        assert s.stages == stages
    assert scenes.load_scene("gale").wind_strength == 1.0
    assert 0 < scenes.load_scene("breeze").wind_strength < 0.5


def test_flags_of_a_scene(tmp_path):
    s = scenes.load_scene(scene_file(tmp_path, GOOD))
    flags = s.flags()
    pairs = dict(zip(flags[::2], flags[1::2]))
    assert pairs["--strands"] == "300" and pairs["--points"] == "16" and pairs["--seed"] == "7"
    assert pairs["--head-radius"] == "12.0" and pairs["--hair-offset"] == "0.2"
    assert pairs["--hair-length"] == "20.0" and pairs["--face-margin"] == "0.5"
    assert pairs["--wind-strength"] == "0.25" and pairs["--wind-angle"] == "3.0"
    assert pairs["--stages"] == "init,collide,wind,collide" and pairs["--precision"] == "fp64"
    assert s.with_overrides(strands=5, points=None).strands == 5


@pytest.mark.parametrize(
    "text, words",
    [
        ("colour = 'red'\n" + GOOD, ["unknown key 'colour'"]),
        (GOOD + "colour = 'red'\n", ["unknown key 'wind.colour'"]),
        (GOOD.replace("length = 20.0", "lenght = 20.0"), ["unknown key 'hair.lenght'", "known in [hair]"]),
        (GOOD.replace("strands = 300", "strands = -5"), ["hair.strands", "≥ 1", "-5"]),
        (GOOD.replace("strands = 300", "strands = 0"), ["hair.strands", "≥ 1"]),
        (GOOD.replace("points = 16", "points = 1"), ["hair.points", "≥ 2"]),
        (GOOD.replace("strands = 300", "strands = 2.5"), ["hair.strands", "whole number"]),
        (GOOD.replace("strands = 300", "strands = true"), ["hair.strands"]),
        (GOOD.replace("strength = 0.25", "strength = nan"), ["wind.strength is NaN"]),
        (GOOD.replace("radius = 12.0", "radius = inf"), ["head.radius is infinite"]),
        (GOOD.replace("radius = 12.0", "radius = -1.0"), ["head.radius", "> 0"]),
        (GOOD.replace("strength = 0.25", "strength = 1.5"), ["wind.strength", "[0, 1]"]),
        (GOOD.replace('"wind", "collide"]', '"blow", "collide"]'), ["stages[2] 'blow' is not a stage"]),
        (GOOD.replace('["init", "collide", "wind", "collide"]', '["collide", "wind"]'), ["must start with init"]),
        (GOOD.replace('["init", "collide", "wind", "collide"]', "[]"), ["stages"]),
        (GOOD.replace('precision = "fp64"', 'precision = "fp16"'), ["precision 'fp16'"]),
        (GOOD.replace("points = 16", "points = 500"), ["ℓ ≥ h"]),
        (GOOD.replace("seed = 7", "seed = -1"), ["seed"]),
        (GOOD.replace('stages = ["init", "collide", "wind", "collide"]', ""), ["missing key 'stages'"]),
        (GOOD.replace("strands = 300", "strands = 100000000000"), ["hair.strands too large", "GiB"]),
        ("stages = [", ["not valid TOML"]),
    ],
)
def test_bad_scenes_are_refused_naming_the_key(tmp_path, text, words):
    message = refused(tmp_path, text)
    for w in words:
        assert w in message, message


def test_unknown_scene_name_lists_the_known_ones():
    with pytest.raises(scenes.SceneError) as e:
        scenes.load_scene("no-such-scene")
    assert "paper" in str(e.value) and "gale" in str(e.value)


def test_shipped_sweeps_load():
    for name in ("quick", "default", "full"):
        sweep = load_sweep(SWEEPS / f"{name}.toml")
        assert sweep.repeat >= 9
        cases = sweep.cases()
        assert len({c.case_id for c in cases}) == len(cases)
    full = load_sweep(SWEEPS / "full.toml")
    strands = {c.strands for c in full.cases()}
    assert min(strands) == 1000 and max(strands) == 10_000_000
    blocks = {c.block_size for c in full.cases() if c.backend == "cuda"}
    assert {32, 1024} <= blocks


@pytest.mark.parametrize(
    "extra, words",
    [
        ("speed = 1\n", ["unknown key 'speed'"]),
        ("[cpu]\nthreds = [1]\n", ["unknown key 'cpu.threds'"]),
        ("[cuda]\nblock_size = [48]\n", ["cuda.block_size 48"]),
        ("[cuda]\nblock_size = [2048]\n", ["cuda.block_size 2048"]),
        ("[cpu]\nthreads = [0]\n", ["cpu.threads values"]),
        ("[cpu]\nvariant = ['fast']\n", ["cpu.variant 'fast'"]),
        ("[axes]\nstrands = [0]\n", ["axes.strands values"]),
        ("[[cuda]]\nbuild = ['turbo']\n", ["cuda.build 'turbo'"]),
    ],
)
def test_bad_sweeps_are_refused(tmp_path, extra, words):
    p = tmp_path / "sw.toml"
    p.write_text(f'scene = "paper"\nrepeat = 9\n{extra}')
    if "[" not in extra:
        p.write_text(p.read_text() + "[cpu]\n")
    with pytest.raises(Exception) as e:
        load_sweep(p)
    for w in words:
        assert w in str(e.value)
    p.write_text('scene = "paper"\nrepeat = 3\n[cpu]\n')
    with pytest.raises(Exception) as e:
        load_sweep(p)
    assert "repeat must be a whole number ≥ 9" in str(e.value)


def test_run_refuses_a_bad_scene_in_one_line(tmp_path):
    bad = scene_file(tmp_path, GOOD.replace("strength = 0.25", "strength = nan"))
    p = subprocess.run([sys.executable, "-m", "harness", "run", str(bad)], cwd=ROOT, capture_output=True, text=True)
    assert p.returncode == 2
    assert p.stderr == f"harness: error: scene {bad}: wind.strength is NaN\n"


def test_every_command_has_help():
    for cmd in ("run", "diff", "sweep", "plot", "report", "bench", "calibrate"):
        p = subprocess.run([sys.executable, "-m", "harness", cmd, "--help"], cwd=ROOT, capture_output=True, text=True)
        assert p.returncode == 0 and "usage:" in p.stdout


@needs_cpu
def test_run_a_scene_on_the_cpu(tmp_path):
    out = tmp_path / "paper.h5"
    p = subprocess.run(
        [
            sys.executable,
            "-m",
            "harness",
            "run",
            "paper",
            "--backend",
            "cpu",
            "--strands",
            "200",
            "--precision",
            "fp64",
            "--repeat",
            "3",
            "--output",
            str(out),
            "--json",
        ],
        cwd=ROOT,
        capture_output=True,
        text=True,
    )
    assert p.returncode == 0, p.stderr
    record = json.loads(p.stdout)
    assert record["strands"] == 200 and record["precision"] == "fp64" and record["repeat"] == 3
    assert [s["stage"] for s in record["stages"]] == ["init", "collide", "wind", "collide"]
    assert out.exists()
    # never replaces a file silently
    p = subprocess.run(
        [sys.executable, "-m", "harness", "run", "still", "--output", str(out)],
        cwd=ROOT,
        capture_output=True,
        text=True,
    )
    assert p.returncode == 2 and p.stderr.startswith("harness: error:") and "Traceback" not in p.stderr
