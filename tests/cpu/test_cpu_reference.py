"""The C reference backend: the invariants of docs/model.md §2.7 on every output, thread-count
independence, resume equivalence, fp32 against fp64, the HDF5 layout of §4, the JSON
record, repeats and nil stages."""

import shutil
import subprocess

import numpy as np
import pytest

from harness.io.states import h5md_layout
from support.invariants_check import assert_invariants, assert_windy_runs_keep_invariants
from support.statecheck import State, assert_equivalent, assert_threads_change_no_bit, run, run_json

SEEDS = [1, 7, 123456789]


@pytest.mark.parametrize("precision", ["fp32", "fp64"])
@pytest.mark.parametrize("points", [2, 3, 16, 64, 251])
@pytest.mark.parametrize("seed", SEEDS)
def test_invariants_hold_on_every_frame(cpu_bin, tmp_path, precision, points, seed):
    out = tmp_path / "s.h5"
    run(
        cpu_bin,
        "--strands",
        400,
        "--points",
        points,
        "--seed",
        seed,
        "--precision",
        precision,
        "--output",
        out,
        "--quiet",
    )
    s = State(out)
    assert s.stages == ["init", "collide", "wind", "collide"]
    assert s.dtype == (np.float32 if precision == "fp32" else np.float64)
    assert_invariants(s)


@pytest.mark.parametrize("precision", ["fp32", "fp64"])
def test_strong_wind_and_other_angles_keep_invariants(cpu_bin, tmp_path, precision):
    flags = ("--strands", 300, "--points", 24, "--precision", precision)
    assert_windy_runs_keep_invariants(cpu_bin, tmp_path, (0.0, 1.0, -2.5, 7.0), *flags)


@pytest.mark.parametrize("precision", ["fp32", "fp64"])
def test_thread_count_does_not_change_a_bit(cpu_bin, tmp_path, precision):
    assert_threads_change_no_bit(cpu_bin, tmp_path, "--strands", 3001, "--points", 20, "--precision", precision)


def test_resume_from_a_file_gives_the_same_bits_as_one_run(cpu_bin, tmp_path):
    whole, first, rest = tmp_path / "whole.h5", tmp_path / "first.h5", tmp_path / "rest.h5"
    run(cpu_bin, "--strands", 2000, "--points", 32, "--output", whole, "--quiet")
    run(cpu_bin, "--strands", 2000, "--points", 32, "--stages", "init", "--output", first, "--quiet")
    run(cpu_bin, "--input", first, "--stages", "collide,wind,collide", "--output", rest, "--quiet")
    a, b = State(whole), State(rest)
    assert b.stages == a.stages
    assert np.array_equal(a.frames, b.frames)
    # one stage at a time, through three files
    f2, f3 = tmp_path / "f2.h5", tmp_path / "f3.h5"
    run(cpu_bin, "--input", first, "--stages", "collide", "--output", f2, "--quiet")
    run(cpu_bin, "--input", f2, "--stages", "wind,collide", "--output", f3, "--quiet")
    assert np.array_equal(State(f3).frames, a.frames)


def test_fp32_agrees_with_fp64_within_the_stated_tolerance(cpu_bin, tmp_path):
    # harness diff's fp32↔fp64 rule (tolerances.py; the measurements: docs/decisions.md)
    paths = {}
    for precision in ("fp32", "fp64"):
        paths[precision] = tmp_path / f"{precision}.h5"
        run(
            cpu_bin,
            "--strands",
            20000,
            "--points",
            32,
            "--precision",
            precision,
            "--output",
            paths[precision],
            "--quiet",
        )
    result = assert_equivalent(paths["fp32"], paths["fp64"], what="cpu fp32 vs fp64")
    assert max(f.max_abs for f in result.frames) > 0  # the precisions really differ


def test_hdf5_layout_is_h5md_shaped(cpu_bin, tmp_path):
    out = tmp_path / "s.h5"
    run(cpu_bin, "--strands", 100, "--points", 8, "--hair-length", 5, "--output", out, "--quiet")
    layout = h5md_layout(out)
    assert layout["version"] == [1, 1]
    assert "name" in layout["author"] and "version" in layout["creator"]
    assert layout["dimension"] == 3
    assert layout["shape"] == (4, 800, 3) and layout["dtype"] == np.float32
    assert layout["chunks"][0] == 1
    assert layout["step"] == [0, 1, 2, 3]
    assert layout["creator"]["name"] == "hairbench"
    p = layout["parameters"]
    # the /parameters attributes of docs/interfaces.md
    for key in (
        "head_radius",
        "hair_offset",
        "hair_length",
        "face_margin",
        "wind_strength",
        "wind_angle",
        "segment_length",
        "seed",
        "n_strands",
        "points_per_strand",
        "precision",
        "backend",
        "variant",
        "threads",
        "block_size",
        "repeat",
        "warmup",
        "git_revision",
        "compiler",
        "flags",
        "device",
        "driver",
        "version",
        "end_to_end_ms",
        "hdf5_write_ms",
    ):
        assert key in p, key
    assert p["backend"] == "cpu" and p["n_strands"] == 100 and p["points_per_strand"] == 8
    assert "-ffp-contract=off" in p["flags"]
    assert layout["parameter_datasets"]["stage_median_ms"] == 4
    if shutil.which("h5dump"):
        d = subprocess.run(["h5dump", "-H", str(out)], capture_output=True, text=True)
        assert d.returncode == 0 and 'DATASET "value"' in d.stdout


def test_json_record_describes_the_run(cpu_bin):
    rec = run_json(
        cpu_bin, "--strands", 500, "--points", 16, "--hair-length", 10, "--repeat", 3, "--threads", 2, "--end-to-end"
    )
    assert rec["backend"] == "cpu" and rec["variant"] == "ref" and rec["threads"] == 2
    assert [s["stage"] for s in rec["stages"]] == ["init", "collide", "wind", "collide"]
    for s in rec["stages"]:
        assert len(s["times_ms"]) == 3
        assert s["min_ms"] <= s["median_ms"] <= s["max_ms"]
    assert rec["stages"][1]["moved_points"] is not None and rec["stages"][2]["moved_points"] is None
    assert rec["end_to_end_ms"] > 0 and rec["hdf5_write_ms"] is None
    assert rec["state_bytes"] == 500 * 16 * 3 * 4


def test_repeats_do_not_change_the_result(cpu_bin, tmp_path):
    a, b = tmp_path / "a.h5", tmp_path / "b.h5"
    run(cpu_bin, "--strands", 700, "--points", 16, "--hair-length", 10, "--output", a, "--quiet")
    run(
        cpu_bin,
        "--strands",
        700,
        "--points",
        16,
        "--hair-length",
        10,
        "--repeat",
        4,
        "--warmup",
        2,
        "--output",
        b,
        "--quiet",
    )
    assert np.array_equal(State(a).frames, State(b).frames)


def test_wind_zero_is_not_run_and_changes_nothing(cpu_bin, tmp_path):
    out = tmp_path / "s.h5"
    rec = run_json(
        cpu_bin, "--strands", 300, "--points", 16, "--hair-length", 10, "--wind-strength", 0, "--output", out
    )
    wind = rec["stages"][2]
    assert wind["stage"] == "wind" and wind["skipped"] is True and wind["times_ms"] == []
    s = State(out)
    assert s.skipped.tolist() == [0, 0, 1, 0]
    assert np.array_equal(s.frames[2], s.frames[1])
    assert np.array_equal(s.frames[3], s.frames[1])  # collide after nothing moved changes nothing


def test_only_listed_stages_run(cpu_bin, tmp_path):
    out = tmp_path / "still.h5"
    rec = run_json(cpu_bin, "--strands", 200, "--points", 8, "--hair-length", 5, "--stages", "init", "--output", out)
    assert [s["stage"] for s in rec["stages"]] == ["init"]
    assert State(out).frames.shape[0] == 1


def test_collide_moves_points_out_of_the_shell(cpu_bin, tmp_path):
    """The draped state has points inside the shell (roots low on the back hang through
    it); collide must find and move them, and a second collide must find nothing."""
    out = tmp_path / "s.h5"
    run(cpu_bin, "--strands", 2000, "--points", 32, "--stages", "init,collide,collide", "--output", out, "--quiet")
    s = State(out)
    assert s.moved[1] > 0
    assert s.moved[2] == 0
    assert np.array_equal(s.frames[2], s.frames[1])
