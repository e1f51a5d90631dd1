"""Bad input to the C reference (docs/interfaces.md: errors): one clear line naming the flag or
file, a non-zero exit, and no output file (nor a temporary one) left behind."""

import h5py
import numpy as np
import pytest

from support.statecheck import State, run, tmp_leftovers

SMALL = ["--strands", "50", "--points", "8", "--hair-length", "5"]

# (name, extra args, expected exit status, text the one-line message must contain)
CLI_CASES = [
    ("zero_strands", ["--strands", "0"], 2, "--strands must be at least 1"),
    ("negative_strands", ["--strands", "-5"], 2, "--strands must be at least 1"),
    ("non_numeric_strands", ["--strands", "many"], 2, "--strands needs a whole number"),
    ("fractional_points", ["--points", "2.5"], 2, "--points needs a whole number"),
    ("one_point", ["--points", "1"], 2, "--points must be at least 2"),
    ("nan_length", ["--hair-length", "nan"], 2, "--hair-length must be finite"),
    ("inf_radius", ["--head-radius", "inf"], 2, "--head-radius must be finite"),
    ("negative_offset", ["--hair-offset", "-0.1"], 2, "--hair-offset must be a finite number > 0"),
    ("wind_above_one", ["--wind-strength", "1.5"], 2, "--wind-strength must be in [0, 1]"),
    ("segment_shorter_than_offset", ["--points", "100", "--hair-length", "5"], 2, "is shorter than --hair-offset"),
    ("unknown_stage", ["--stages", "init,blow"], 2, "unknown stage 'blow'"),
    ("no_state_for_wind", ["--stages", "wind"], 2, "'wind' needs a state"),
    ("bad_precision", ["--precision", "fp16"], 2, "--precision must be fp32 or fp64"),
    ("unknown_flag", ["--colour", "red"], 2, "unknown flag '--colour'"),
    ("zero_threads", ["--threads", "0"], 2, "--threads must be at least 1"),
    ("block_size_on_cpu", ["--block-size", "64"], 2, "--block-size is a flag of hairsim-cuda"),
    ("unknown_variant", ["--variant", "turbo"], 2, "--variant turbo is not a cpu variant"),
    ("missing_value", ["--seed"], 2, "--seed needs a value"),
    (
        "state_too_big_for_memory",
        ["--strands", "1000000000000", "--points", "100", "--hair-length", "50"],
        3,
        "host memory",
    ),
]


@pytest.mark.parametrize("name,args,status,text", CLI_CASES, ids=[c[0] for c in CLI_CASES])
def test_bad_flags_are_refused_before_any_work(cpu_bin, tmp_path, name, args, status, text):
    out = tmp_path / "out.h5"
    p = run(cpu_bin, *SMALL, *args, "--output", out, check=False)
    assert p.returncode == status, p.stderr
    lines = p.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("hairsim-cpu: error: "), p.stderr
    assert text in lines[0]
    assert "Traceback" not in p.stderr
    assert not out.exists()
    assert tmp_leftovers(tmp_path) == []


@pytest.fixture
def good_state(cpu_bin, tmp_path):
    path = tmp_path / "good.h5"
    run(cpu_bin, *SMALL, "--stages", "init", "--output", path, "--quiet")
    return path


def _damage(kind, good, tmp_path):
    path = tmp_path / f"{kind}.h5"
    if kind == "missing":
        return path
    if kind == "not_hdf5":
        path.write_text("this is not an HDF5 file\n")
        return path
    data = good.read_bytes()
    if kind == "truncated":
        path.write_bytes(data[: len(data) // 3])
        return path
    path.write_bytes(data)
    with h5py.File(path, "r+") as f:
        v = f["particles/hair/position/value"]
        if kind == "nan_inside":
            a = v[:]
            a[0, 17, 1] = np.nan
            v[...] = a
        elif kind == "wrong_rows":
            del f["particles/hair/position/value"]
            f["particles/hair/position/value"] = np.zeros((1, 10, 3), np.float32)
        elif kind == "wrong_dtype":
            a = v[:]
            del f["particles/hair/position/value"]
            f["particles/hair/position/value"] = a.astype(np.float64)
        elif kind == "no_frames":
            del f["particles/hair/position/value"]
            f.create_dataset("particles/hair/position/value", shape=(0, 400, 3), dtype=np.float32)
        elif kind == "missing_parameter":
            del f["parameters"].attrs["hair_length"]
        elif kind == "other_layout":
            del f["particles"]
            f["positions"] = np.zeros((400, 3))
    return path


INPUT_CASES = [
    ("missing", 2, "no such file"),
    ("not_hdf5", 2, "is not an HDF5 file"),
    ("truncated", 2, "--input"),
    ("nan_inside", 2, "NaN or Inf"),
    ("wrong_rows", 2, "rows"),
    ("wrong_dtype", 2, "is not fp32 floating point"),
    ("no_frames", 2, "has no frames"),
    ("missing_parameter", 2, "lacks the attribute 'hair_length'"),
    ("other_layout", 2, "is not a hairbench state"),
]


@pytest.mark.parametrize("kind,status,text", INPUT_CASES, ids=[c[0] for c in INPUT_CASES])
def test_bad_input_files_are_refused(cpu_bin, tmp_path, good_state, kind, status, text):
    bad = _damage(kind, good_state, tmp_path)
    out = tmp_path / "out.h5"
    p = run(cpu_bin, "--input", bad, "--stages", "collide", "--output", out, check=False)
    assert p.returncode == status, p.stderr
    lines = p.stderr.strip().splitlines()
    assert len(lines) == 1 and text in lines[0], p.stderr
    assert not out.exists()
    assert tmp_leftovers(tmp_path) == []


def test_input_flags_that_disagree_with_the_file_are_refused(cpu_bin, tmp_path, good_state):
    p = run(cpu_bin, "--input", good_state, "--points", "9", "--stages", "collide", check=False)
    assert p.returncode == 2 and "--points 9 does not match the input file's 8" in p.stderr
    p = run(cpu_bin, "--input", good_state, "--precision", "fp64", "--stages", "collide", check=False)
    assert p.returncode == 2 and "--precision fp64 does not match" in p.stderr
    p = run(cpu_bin, "--input", good_state, "--stages", "init", check=False)
    assert p.returncode == 2 and "init cannot run on an --input state" in p.stderr


def test_existing_output_is_not_overwritten_without_force(cpu_bin, tmp_path):
    out = tmp_path / "mine.h5"
    out.write_text("precious\n")
    p = run(cpu_bin, *SMALL, "--output", out, check=False)
    assert p.returncode == 2 and "exists" in p.stderr and "--force" in p.stderr
    assert out.read_text() == "precious\n"
    run(cpu_bin, *SMALL, "--output", out, "--force", "--quiet")
    State(out)  # a state in the documented layout (harness.io.states raises otherwise)


def test_output_may_not_be_the_input(cpu_bin, tmp_path, good_state):
    before = good_state.read_bytes()
    p = run(cpu_bin, "--input", good_state, "--stages", "collide", "--output", good_state, "--force", check=False)
    assert p.returncode == 2 and "is the --input file" in p.stderr
    assert good_state.read_bytes() == before


def test_unwritable_output_directory_fails_cleanly(cpu_bin, tmp_path):
    p = run(cpu_bin, *SMALL, "--output", tmp_path / "no" / "such" / "dir" / "s.h5", check=False)
    assert p.returncode == 2 and "cannot create" in p.stderr
