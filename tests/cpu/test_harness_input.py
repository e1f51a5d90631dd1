"""Harness input (issue "front door"): every bad scene file and every bad flag is refused
in one line `harness: error: …` with exit status 2, never a traceback; the binary and the
harness agree on the stage-list rules; --seed is read in base 10; a sweep's name stays
under results/."""

import subprocess
import sys
from pathlib import Path

import pytest

from harness.core import scenes
from harness.core.scenes import SceneError
from harness.io import sweepfile
from support.statecheck import run

ROOT_DIR = Path(__file__).resolve().parents[2]


def tmp_leftovers(directory):
    return sorted(p.name for p in Path(directory).iterdir() if ".tmp." in p.name)


SCENES = {
    "not_utf8": b'stages = ["init"]\ndescription = "\xff\xfe"\n',
    "not_toml": b"stages = [\n",
    "points_top_level": b'points = 1\nstages = ["init"]\n',
    "points_one": b'stages = ["init"]\n[hair]\npoints = 1\n',
    "points_text": b'stages = ["init"]\n[hair]\npoints = "many"\n',
    "points_float": b'stages = ["init"]\n[hair]\npoints = 8.5\n',
    "points_bool": b'stages = ["init"]\n[hair]\npoints = true\n',
    "hair_not_table": b'stages = ["init"]\nhair = [1]\n',
    "stages_nested": b'stages = [["init"]]\n',
    "stages_number": b"stages = 3\n",
    "stages_empty_item": b'stages = "init,,wind"\n',
    "stages_init_later": b'stages = ["init", "wind", "init"]\n',
    "strands_inf": b'stages = ["init"]\n[hair]\nstrands = inf\n',
    "seed_negative": b'stages = ["init"]\nseed = -1\n',
    "description_number": b'stages = ["init"]\ndescription = 5\n',
}


def harness(*args):
    return subprocess.run(
        [sys.executable, "-m", "harness", *map(str, args)], cwd=ROOT_DIR, capture_output=True, text=True, timeout=120
    )


def one_line_refusal(p):
    assert p.returncode == 2, (p.returncode, p.stderr)
    lines = p.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("harness: error: "), p.stderr
    assert "Traceback" not in p.stderr


@pytest.mark.parametrize("name", sorted(SCENES))
def test_bad_scene_file_is_one_line(tmp_path, name, cpu_bin):
    path = tmp_path / f"{name}.toml"
    path.write_bytes(SCENES[name])
    one_line_refusal(harness("run", path))


FLAGS = [
    ("threads_zero", ["--threads", "0"]),
    ("repeat_zero", ["--repeat", "0"]),
    ("warmup_negative", ["--warmup", "-1"]),
    ("block_size_on_cpu", ["--block-size", "64"]),
    ("threads_on_cuda", ["--backend", "cuda", "--threads", "2"]),
    ("timeout_negative", ["--timeout", "-1"]),
    ("timeout_nan", ["--timeout", "nan"]),
    ("strands_zero", ["--strands", "0"]),
    ("strands_text", ["--strands", "x"]),
    ("points_one", ["--points", "1"]),
    ("stages_empty_item", ["--stages", "init,,wind"]),
    ("frames_zero", ["--frames", "0"]),
    ("every_zero", ["--every", "0"]),
    ("unknown_flag", ["--colour", "red"]),
]


@pytest.mark.parametrize("name,args", FLAGS, ids=[f[0] for f in FLAGS])
def test_bad_flag_is_one_line(name, args, cpu_bin):
    one_line_refusal(harness("run", "still", *args))


OTHER_COMMANDS = [
    ("stepdiff_timeout_negative", ["stepdiff", "--reference", "r.h5", "--binary", "b", "--timeout", "-1"]),
    ("stepdiff_timeout_nan", ["stepdiff", "--reference", "r.h5", "--binary", "b", "--timeout", "nan"]),
    ("sweep_out_a_device", ["sweep", "quick", "--out", "/dev/null"]),
    ("report_into_a_file", ["report", "results/reference-h200/sweep", "--report-dir", "{file}"]),
    ("plot_into_a_file", ["plot", "results/reference-h200/sweep", "--report-dir", "{file}"]),
    ("featurecost_strands_zero", ["featurecost", "--strands", "0"]),
]


@pytest.mark.parametrize("name,args", OTHER_COMMANDS, ids=[c[0] for c in OTHER_COMMANDS])
def test_bad_flag_of_other_commands_is_one_line(tmp_path, name, args):
    a_file = tmp_path / "a_file"
    a_file.write_text("keep")
    one_line_refusal(harness(*(a.format(file=a_file) for a in args)))
    assert a_file.read_text() == "keep"


def test_bad_command_is_one_line():
    one_line_refusal(harness("bogus"))
    one_line_refusal(harness())


STAGE_LISTS = [
    "init",
    "init,collide,wind,collide",
    "init,,wind",
    ",init",
    "init,",
    "",
    "init,wind,init",
    "init,blow",
    "init, wind",
    "init,wind,wind",
    ",".join(["init"] + ["wind"] * 63),
    ",".join(["init"] + ["wind"] * 64),
]


# a scene small enough that only the arguments under test matter
TINY = ("--strands", "2", "--points", "4", "--hair-length", "3")


@pytest.mark.parametrize("stages", STAGE_LISTS)
def test_binary_and_harness_agree_on_stage_lists(cpu_bin, stages):
    p = run(
        cpu_bin,
        *TINY,
        "--stages",
        stages,
        "--wind-strength",
        "0",
        "--quiet",
        check=False,
    )
    try:
        scenes.parse_stages(stages, "test", "--stages")
        harness_ok = True
    except SceneError:
        harness_ok = False
    assert (p.returncode == 0) == harness_ok, (stages, p.stderr)


def test_seed_is_base_ten(cpu_bin):
    p = run(
        cpu_bin,
        *TINY,
        "--stages",
        "init",
        "--seed",
        "010",
        "--json",
        "--quiet",
    )
    assert '"seed": 10' in p.stdout
    p = run(cpu_bin, "--seed", "0x10", check=False)
    assert p.returncode == 2 and "--seed needs a whole number" in p.stderr


@pytest.mark.parametrize("name", ["../escape", "/tmp/abs", "..", "a/b", "", ".hidden", 5])
def test_sweep_name_cannot_leave_results(tmp_path, name):
    path = tmp_path / "s.toml"
    value = f'"{name}"' if isinstance(name, str) else str(name)
    path.write_text(f'name = {value}\nscene = "still"\nrepeat = 9\n[cpu]\n')
    with pytest.raises(sweepfile.SweepError, match="name must be"):
        sweepfile.load_sweep(path)
