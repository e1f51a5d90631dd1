"""The binaries' rows of the second fault probe (issue #46): integer flags parsed exactly, every
input file opened by one guarded path (a FIFO refused, not waited on), a groom's head fit and
sizes checked before anything is allocated, a groom's segments representable in the working
precision, and a batch whose lines run as they would alone. Each test failed before its fix."""

import json
import math
import os
import subprocess
import threading

import pytest
from test_grooms import hair_bytes, radial_strands

from harness.core import env
from support import fulldisk
from support.faults import make_fault
from support.statecheck import run, tmp_leftovers

SIM = ["--stages", "init,simulate"]
TINY = ["--strands", "4", "--points", "4", "--hair-length", "5", "--quiet"]

# issue #46's two files, byte for byte
D7_HAIR = bytes.fromhex(
    "48414952010000000200000003000000000000000000803f000000000000803f0000803f0000803f0000000000000000"
    "000000000000000000000000000000000000000000000000000000000000000000000000000000000000000000000000"
    "000000000000000000000000000000000000000000000000000000000000000001000000000000002041000000000000"
    "00000000f04100000000"
)
D4_HAIR = bytes.fromhex(
    "48414952030000000600000003000000000000000000803f000000000000803f0000803f0000803f0000000000000000"
    "000000000000000000000000000000000000000000000000000000000000000000000000000000000000000000000000"
    "00000000000000000000000000000000000000000000000000000000000000000100010001009083ee405555d5400000"
    "0000ace2b2410000a0410000000042f5ebc0000000002a28d840f2f7b0c100000000201ea2416ad1263f5555d5c0c599"
    "edc01e3afa3f0000a0c15433b2c1"
)
assert len(D7_HAIR) == 154 and len(D4_HAIR) == 206


def refused(p, words, code=2):
    lines = p.stderr.strip().splitlines()
    assert p.returncode == code and len(lines) == 1, (p.returncode, p.stderr)
    assert words in lines[0], lines[0]
    return lines[0]


def record(p):
    assert p.returncode == 0, p.stderr
    return json.loads(p.stdout)


# ---- D2: whole numbers exactly, or refused ------------------------------------------------


@pytest.mark.parametrize(
    "flag, value, words",
    [
        ("--seed", "9007199254740993.5", "whole number"),
        ("--seed", "1e-400", "whole number"),
        ("--points", "2.9999999999999999999", "whole number"),
        ("--seed", "18446744073709551616", "out of range"),
        ("--seed", "1.8446744073709551616e19", "out of range"),
        ("--strands", "9223372036854775808", "out of range"),
        ("--strands", "1e99999999999999999999", "out of range"),
    ],
)
def test_whole_number_not_exact_refused(cpu_bin, flag, value, words):
    refused(run(cpu_bin, *TINY, flag, value, check=False), flag)
    refused(run(cpu_bin, *TINY, flag, value, check=False), words)


@pytest.mark.parametrize(
    "value, seed",
    [
        ("9007199254740993.0", 9007199254740993),
        ("12345678901234567891e0", 12345678901234567891),
        ("1.8446744073709551615e19", 18446744073709551615),
        ("123456789012345678.90e1", 1234567890123456789),
        ("0.0e5", 0),
    ],
)
def test_seed_parsed_exactly(cpu_bin, value, seed):
    assert record(run(cpu_bin, *TINY, "--json", "--seed", value, check=False))["seed"] == seed


# ---- D3: every input through one guarded opener --------------------------------------------


@pytest.mark.parametrize("flag", ["--groom", "--batch", "--input"])
@pytest.mark.parametrize("kind", ["fifo", "directory", "missing", "empty"])
def test_input_kinds_refused_naming_the_file(cpu_bin, tmp_path, flag, kind):
    path = make_fault(tmp_path, kind)
    args = [flag, path] if flag == "--batch" else [flag, path, *SIM] if flag == "--groom" else [flag, path]
    if flag == "--input":
        args += ["--stages", "simulate"]
    p = run(cpu_bin, *args, check=False, timeout=20)
    words = {"fifo": "is a FIFO", "directory": "is a directory", "missing": "no such file", "empty": "is empty"}[kind]
    line = refused(p, words)
    assert f"{flag} {path}" in line, line


# ---- D4, D7, M1, M3: the groom's head and sizes ---------------------------------------------


def test_three_strands_do_not_fit_a_sphere(cpu_bin, tmp_path):
    path = tmp_path / "d4.hair"
    path.write_bytes(D4_HAIR)
    refused(run(cpu_bin, "--groom", path, *SIM, "--quiet", check=False), "fewer than 4 strands")


def test_roots_on_one_circle_far_from_the_origin_refused(cpu_bin, tmp_path):
    """Eight roots on a circle of 10 cm, 1000 cm from the origin: coplanar, so no sphere; the
    normal equations in the file's coordinates are too ill-conditioned for an absolute test."""
    strands = []
    for k in range(8):
        a = 2 * math.pi * k / 8
        root = (1000.0 + 10 * math.cos(a), 1000.0 + 10 * math.sin(a), 1000.0)
        strands.append([root, (root[0], root[1], root[2] + 4.0)])
    path = tmp_path / "ring.hair"
    path.write_bytes(hair_bytes(strands))
    refused(run(cpu_bin, "--groom", path, *SIM, "--quiet", check=False), "do not determine a sphere")


def test_sphere_fitted_far_from_the_origin(cpu_bin, tmp_path):
    """The same conditioning, roots on a sphere: the fit finds its centre."""
    path = tmp_path / "far.hair"
    path.write_bytes(hair_bytes(radial_strands((1000.0, -500.0, 250.0), 10.0, [4.0] * 6, [5] * 6)))
    g = record(run(cpu_bin, "--groom", path, "--points", 5, *SIM, "--json", "--quiet", check=False))["groom"]
    assert g["head_center"] == pytest.approx([1000.0, -500.0, 250.0], abs=1e-6)


def test_points_whose_state_cannot_be_addressed_refused_before_allocating(cpu_bin, tmp_path):
    path = tmp_path / "d7.hair"
    path.write_bytes(D7_HAIR)
    p = run(cpu_bin, "--groom", path, "--head-center", "0,0,0", "--points", "2305843009213693952", *SIM, check=False)
    refused(p, "--points")


def test_points_whose_state_does_not_fit_memory_exit_3(cpu_bin, tmp_path):
    path = tmp_path / "d7.hair"
    path.write_bytes(D7_HAIR)
    p = run(cpu_bin, "--groom", path, "--head-center", "0,0,0", "--points", "1e12", *SIM, check=False)
    refused(p, "memory", code=3)


def test_head_centre_beyond_the_representable_lengths_refused(cpu_bin, tmp_path):
    path = tmp_path / "d7.hair"
    path.write_bytes(D7_HAIR)
    line = refused(run(cpu_bin, "--groom", path, "--head-center", "1e300,0,0", *SIM, check=False), "--head-center")
    assert "zero length" not in line


# ---- D5, D6: the groom's lengths ------------------------------------------------------------


def test_segments_that_round_to_zero_refused(cpu_bin, tmp_path):
    """Strands of 4 points 1e-6 cm apart, resampled to 32: segments of 3e-8 cm vanish in fp32."""
    strands = radial_strands((0, 0, 0), 10.0, [3e-6] * 6, [4] * 6)
    path = tmp_path / "tiny.hair"
    path.write_bytes(hair_bytes(strands))
    out = tmp_path / "o.h5"
    p = run(cpu_bin, "--groom", path, *SIM, "--output", out, check=False)
    refused(p, "fp32")
    assert not out.exists() and not tmp_leftovers(tmp_path)


def test_short_groom_strands_run_at_the_default_points(cpu_bin, tmp_path):
    """2 cm strands at P = 32: ℓ < h, a rule of the collide stage, which a groom does not run."""
    path = tmp_path / "short.hair"
    path.write_bytes(hair_bytes(radial_strands((0, 0, 0), 10.0, [2.0] * 6, [5] * 6)))
    assert record(run(cpu_bin, "--groom", path, *SIM, "--json", "--quiet", check=False))["points"] == 32


# ---- D10, D11, M7: batches ----------------------------------------------------------------


def batch(cpu_bin, tmp_path, lines, **kw):
    path = tmp_path / "runs.txt"
    path.write_bytes(b"\n".join(b"\t".join(w.encode() if isinstance(w, str) else w for w in ln) for ln in lines))
    return run(cpu_bin, "--batch", path, check=False, **kw)


def test_batch_line_without_threads_takes_every_core(cpu_bin, tmp_path):
    cores = env.usable_cores()  # the cores this process may run on (taskset), as the binary counts them
    if cores == 1:
        pytest.skip("one core: every run takes 1 thread")
    line = [*TINY, "--json"]
    p = batch(cpu_bin, tmp_path, [[*line, "--threads", "1"], line])
    assert p.returncode == 0, p.stderr
    threads = [json.loads(x)["threads"] for x in p.stdout.splitlines()]
    assert threads[0] == 1 and threads[1] == cores, threads


def test_batch_line_with_a_nul_byte_refused(cpu_bin, tmp_path):
    p = batch(cpu_bin, tmp_path, [[*TINY, "--json"], [b"--strands", b"4\x00--points", b"4", b"--quiet"]])
    refused(p, "line 2 holds a NUL byte")
    assert len(p.stdout.splitlines()) == 1


@pytest.mark.parametrize("word", ["--help", "--version", "--list-variants", "--limits"])
def test_batch_line_asking_for_help_refused(cpu_bin, tmp_path, word):
    p = batch(cpu_bin, tmp_path, [[*TINY, "--json"], [word]])
    refused(p, f"line 2 holds {word}")
    assert len(p.stdout.splitlines()) == 1


def test_fifo_batch_does_not_wait_for_a_writer(cpu_bin, tmp_path):
    fifo = tmp_path / "runs"
    os.mkfifo(fifo)
    result = {}

    def go():
        result["p"] = subprocess.run([str(cpu_bin), "--batch", str(fifo)], capture_output=True, text=True)

    t = threading.Thread(target=go, daemon=True)
    t.start()
    t.join(10)
    if t.is_alive():  # let it end before failing
        with open(fifo, "w"):
            pass
        t.join(10)
        pytest.fail("--batch FIFO waited for a writer")
    refused(result["p"], "is a FIFO")


# ---- D15, M2: a full disk ------------------------------------------------------------------


def test_full_disk_exit_4_old_output_kept(cpu_bin, tmp_path):
    p = fulldisk.run(
        tmp_path,
        f'printf old > "$D/o.h5"; "{cpu_bin}" --strands 20000 --points 32 --output "$D/o.h5" --force --quiet\n'
        'echo "rc=$?"; cat "$D/o.h5"; echo; ls -A "$D"',
    )
    assert p.stdout.split() == ["rc=4", "old", "o.h5"], (p.stdout, p.stderr)
    assert len(p.stderr.strip().splitlines()) == 1 and "disk full" in p.stderr, p.stderr


def test_full_disk_temporary_not_created_exit_4(cpu_bin, tmp_path):
    p = fulldisk.run(
        tmp_path,
        f'head -c 4M /dev/zero > "$D/fill" 2>/dev/null; "{cpu_bin}" {" ".join(TINY)} --output "$D/o.h5"\n'
        'echo "rc=$?"; ls -A "$D"',
    )
    assert p.stdout.split() == ["rc=4", "fill"], (p.stdout, p.stderr)
    assert len(p.stderr.strip().splitlines()) == 1 and "No space left" in p.stderr, p.stderr
