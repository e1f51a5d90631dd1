"""The bad-input and fault probe's matrix (issue #24), kept so that no later change reopens a
row: numeric flags x bad values, resume files x damage, signals x moments (kill -9 at seeded
random moments), concurrent writers, paths, and the harness's own faults. The suite prints
the matrix's counts (tests/conftest.py)."""

import os
import random
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from harness.core import tempfiles

ROOT = Path(__file__).resolve().parents[2]
TINY = ["--strands", "4", "--points", "4", "--hair-length", "5", "--quiet"]
SIM = ["--stages", "init,simulate"]
# slow enough to be caught mid-run on a busy machine, small enough to write quickly
SLOW = ["--strands", "2000", "--points", "16", "--hair-length", "10", *SIM, "--frames", "40", "--substeps", "30"]
SLOW += ["--threads", "1", "--quiet"]


def run(binary, *args, timeout=60, **kw):
    return subprocess.run([str(binary), *map(str, args)], capture_output=True, text=True, timeout=timeout, **kw)


def harness(*args, timeout=120, **kw):
    return subprocess.run(
        [sys.executable, "-m", "harness", *map(str, args)],
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=timeout,
        **kw,
    )


def refused(p, text=None):
    """Exit 2 with one line on stderr (containing text)."""
    lines = p.stderr.strip().splitlines()
    assert p.returncode == 2 and len(lines) == 1, (p.returncode, p.stderr)
    assert text is None or text in lines[0], lines[0]
    return lines[0]


def temporaries(directory):
    return sorted(n for n in os.listdir(directory) if n.startswith(".hairsim-"))


# ---- numeric flags x bad values (row 10: one grammar, decimal only) ---------------------

NUMBER_FLAGS = ["--strands", "--seed", "--frames", "--head-radius", "--motion-frequency"]
BAD_NUMBERS = [" -10", "0x10", "0x1p3", "10 ", "1e999", "nan", "inf", "", "1..5", "+-1", "1e"]


@pytest.mark.parametrize("value", BAD_NUMBERS, ids=repr)
@pytest.mark.parametrize("flag", NUMBER_FLAGS)
def test_number_refused(cpu_bin, flag, value):
    refused(run(cpu_bin, *TINY, *SIM, flag, value), flag)


@pytest.mark.parametrize(
    "flag,value",
    [("--seed", "1e3"), ("--seed", "18446744073709551615"), ("--frames", "2e0"), ("--head-radius", ".5e1")],
)
def test_number_accepted(cpu_bin, flag, value):
    p = run(cpu_bin, *TINY, *SIM, "--frames", "1", flag, value)
    assert p.returncode == 0, p.stderr


def test_negative_seed_refused_with_or_without_space(cpu_bin):
    for v in ("-10", " -10"):
        refused(run(cpu_bin, *TINY, "--seed", v), "--seed")


# ---- products and derived constants (rows 1 and 4) -------------------------------------


def test_frames_times_repeat_refused_before_it_wraps(cpu_bin, tmp_path):
    p = run(
        cpu_bin,
        *["--strands", 1, "--points", 2, "--stages", "init,collide,simulate", "--quiet"],
        *["--frames", 9007199254740989, "--repeat", 2048, "--output", tmp_path / "o.h5"],
    )
    refused(p, "--repeat")
    assert os.listdir(tmp_path) == []


@pytest.mark.parametrize(
    "flags",
    [
        ["--head-motion", "nod", "--motion-frequency", "1e308"],
        ["--wind-speed", "100", "--drag", "1", "--gust-amplitude", "0.5", "--gust-frequency", "1e308"],
    ],
    ids=["motion", "gust"],
)
def test_frequency_overflow_refused(cpu_bin, tmp_path, flags):
    p = run(cpu_bin, *TINY, *SIM, "--frames", 120, "--precision", "fp64", *flags, "--output", tmp_path / "o.h5")
    refused(p, "frequency")
    assert os.listdir(tmp_path) == []


def test_checked_multiply_at_the_boundaries(tmp_path):
    cc = shutil.which(os.environ.get("CC", "cc")) or shutil.which("gcc")
    if not cc:
        pytest.skip("no C compiler")
    exe = tmp_path / "checked"
    subprocess.run(
        [
            cc,
            "-std=c11",
            "-Wall",
            "-Werror",
            "-I",
            ROOT / "c_ref",
            ROOT / "tests/cpu/c/checked_boundaries.c",
            "-o",
            exe,
        ],
        check=True,
    )
    p = subprocess.run([exe], capture_output=True, text=True)
    assert p.returncode == 0 and "0 misses" in p.stdout, p.stderr


# ---- resume files x damage (rows 3, 5, 11) -----------------------------------------------


@pytest.fixture(scope="module")
def dynamic_state(cpu_bin, tmp_path_factory):
    path = tmp_path_factory.mktemp("resume") / "dyn.h5"
    p = run(cpu_bin, *TINY, *SIM, "--frames", 2, "--shape-compliance", "1e-6", "--output", path)
    assert p.returncode == 0, p.stderr
    return path


DAMAGE = {
    "velocity NaN": ("particles/hair/velocity/value", np.nan),
    "velocity Inf": ("particles/hair/velocity/value", np.inf),
    "rest NaN": ("particles/hair/rest_position", np.nan),
    "position NaN": ("particles/hair/position/value", np.nan),
}


@pytest.mark.parametrize("damage", list(DAMAGE))
def test_damaged_resume_refused(cpu_bin, dynamic_state, tmp_path, damage):
    import h5py

    bad = tmp_path / "bad.h5"
    shutil.copy(dynamic_state, bad)
    name, value = DAMAGE[damage]
    with h5py.File(bad, "r+") as f:
        d = f[name]
        a = d[...]
        a.reshape(-1)[-1] = value
        d[...] = a
    p = run(cpu_bin, "--input", bad, "--stages", "simulate", "--frames", 1, "--quiet", "--output", tmp_path / "o.h5")
    refused(p, "NaN or Inf")
    assert not (tmp_path / "o.h5").exists() and temporaries(tmp_path) == []


@pytest.mark.parametrize("flag", ["--bend-compliance", "--drag", "--damping"])
def test_undeclared_feature_declared_on_resume_refused(cpu_bin, dynamic_state, flag):
    refused(run(cpu_bin, "--input", dynamic_state, "--stages", "simulate", "--frames", 1, flag, "0"), flag)


def test_resume_keeping_the_declarations_runs(cpu_bin, dynamic_state):
    p = run(cpu_bin, "--input", dynamic_state, "--stages", "simulate", "--frames", 1, "--shape-compliance", "1e-6")
    assert p.returncode == 0, p.stderr


def test_fifo_input_refused_without_hanging(cpu_bin, tmp_path):
    os.mkfifo(tmp_path / "fifo")
    refused(run(cpu_bin, "--input", tmp_path / "fifo", "--stages", "collide", timeout=20), "FIFO")


# ---- paths ------------------------------------------------------------------------------


def test_output_paths(cpu_bin, tmp_path):
    (tmp_path / "dir").mkdir()
    refused(run(cpu_bin, *TINY, "--output", tmp_path / "dir"), "directory")
    refused(run(cpu_bin, *TINY, "--output", tmp_path / "none" / "o.h5"))
    (tmp_path / "mine.h5").write_bytes(b"mine")
    refused(run(cpu_bin, *TINY, "--output", tmp_path / "mine.h5"), "exists")
    assert (tmp_path / "mine.h5").read_bytes() == b"mine"
    assert temporaries(tmp_path) == []


def test_written_file_is_hdf5_without_marker(cpu_bin, tmp_path):
    import h5py

    out = tmp_path / "o.h5"
    assert run(cpu_bin, *TINY, "--output", out).returncode == 0
    assert out.read_bytes()[: len(tempfiles.MARKER)] != tempfiles.MARKER
    with h5py.File(out) as f:
        assert f["particles/hair/position/value"].shape[0] >= 1


# ---- the clean-up touches only marked temporaries of dead runs ---------------------------


def dead_pid():
    p = subprocess.Popen(["true"])
    p.wait()
    return p.pid


def test_cleanup_needs_name_and_marker(cpu_bin, tmp_path):
    pid = dead_pid()
    hdf5 = b"\x89HDF\r\n\x1a\n" + b"\0" * 64
    user = {
        "experiment.tmp.2024": hdf5,  # the old rule's victim
        "empty.tmp.99999": b"",
        f".hairsim-{pid}-0123456789abcdef.tmp": hdf5,  # our name, no marker
        f"hairsim-{pid}-0123456789abcdef.tmp": tempfiles.MARKER,  # the marker, not our name
    }
    for name, data in user.items():
        (tmp_path / name).write_bytes(data)
    stale = tmp_path / f".hairsim-{pid}-fedcba9876543210.tmp"
    stale.write_bytes(tempfiles.MARKER + b"\0" * 100)
    p = run(cpu_bin, *TINY, "--output", tmp_path / "o.h5")
    assert p.returncode == 0 and "removed 1 stale" in p.stderr, p.stderr
    assert not stale.exists()
    for name, data in user.items():
        assert (tmp_path / name).read_bytes() == data, name
    # the harness's rule is the same one
    stale.write_bytes(tempfiles.MARKER)
    assert tempfiles.remove_left_by(pid, [tmp_path]) == [stale]
    assert all((tmp_path / n).exists() for n in user)


# ---- signals x moments ------------------------------------------------------------------


def wait_for_child(proc, name, timeout=30, also=None):
    """Whether a child of proc whose command line names `name` (and `also`, where given) appears
    within timeout (Linux /proc)."""
    end = time.monotonic() + timeout
    while time.monotonic() < end and proc.poll() is None:
        for pid in filter(str.isdigit, os.listdir("/proc")):
            try:
                with open(f"/proc/{pid}/stat") as fh:
                    ppid = int(fh.read().rsplit(")", 1)[1].split()[1])
                with open(f"/proc/{pid}/cmdline", "rb") as fh:
                    cmd = fh.read()
            except (OSError, ValueError, IndexError):
                continue
            if ppid == proc.pid and name.encode() in cmd and (also is None or also.encode() in cmd):
                return True
        time.sleep(0.01)
    return False


def wait_for_temporary(directory, proc, timeout=30):
    end = time.monotonic() + timeout
    while time.monotonic() < end and proc.poll() is None:
        if temporaries(directory):
            return True
        time.sleep(0.005)
    return False


@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGTERM, signal.SIGHUP, signal.SIGQUIT], ids=lambda s: s.name)
def test_signal_keeps_the_old_output(cpu_bin, tmp_path, sig):
    out = tmp_path / "o.h5"
    out.write_bytes(b"old")
    proc = subprocess.Popen([str(cpu_bin), *SLOW, "--output", str(out), "--force"], stderr=subprocess.PIPE)
    assert wait_for_temporary(tmp_path, proc)
    proc.send_signal(sig)
    proc.communicate(timeout=60)
    assert proc.returncode == -sig
    assert out.read_bytes() == b"old" and temporaries(tmp_path) == []


@pytest.mark.parametrize("seed", range(6))
def test_kill9_at_random_moments(cpu_bin, tmp_path, seed):
    """SIGKILL at a seeded random moment; the next run's clean-up leaves nothing of it but
    the user's files, intact."""
    out, mine = tmp_path / "o.h5", tmp_path / "mine.tmp.1"
    out.write_bytes(b"old")
    mine.write_bytes(b"")
    delay = random.Random(seed).uniform(0.0, 0.4)
    proc = subprocess.Popen([str(cpu_bin), *SLOW, "--output", str(out), "--force"], stderr=subprocess.DEVNULL)
    time.sleep(delay)
    proc.kill()
    proc.wait()
    left = temporaries(tmp_path)
    assert all(tempfiles.owner_pid(n) == proc.pid and tempfiles.is_marked(tmp_path / n) for n in left), left
    assert out.read_bytes() == b"old"
    p = run(cpu_bin, *TINY, "--output", tmp_path / "next.h5")
    assert p.returncode == 0, p.stderr
    assert sorted(os.listdir(tmp_path)) == ["mine.tmp.1", "next.h5", "o.h5"]
    assert out.read_bytes() == b"old" and mine.read_bytes() == b""


# ---- concurrent writers (row 2) -----------------------------------------------------------


def test_file_appearing_during_the_run_is_not_replaced(cpu_bin, tmp_path):
    out = tmp_path / "o.h5"
    proc = subprocess.Popen([str(cpu_bin), *SLOW, "--output", str(out)], stderr=subprocess.PIPE, text=True)
    assert wait_for_temporary(tmp_path, proc)
    out.write_bytes(b"user")
    _, err = proc.communicate(timeout=120)
    assert proc.returncode == 2 and "during this run" in err, err
    assert out.read_bytes() == b"user" and temporaries(tmp_path) == []


def test_two_writers_one_wins(cpu_bin, tmp_path):
    out = tmp_path / "o.h5"
    cmd = [str(cpu_bin), *SLOW, "--output", str(out)]
    a = subprocess.Popen(cmd, stderr=subprocess.PIPE, text=True)
    assert wait_for_temporary(tmp_path, a)
    b = subprocess.Popen(cmd, stderr=subprocess.PIPE, text=True)
    codes = sorted([a.wait(timeout=120), b.wait(timeout=120)])
    assert codes == [0, 2], (a.stderr.read() if a.stderr else "", b.stderr.read() if b.stderr else "")
    assert temporaries(tmp_path) == []


def test_force_replaces_a_file_that_appeared(cpu_bin, tmp_path):
    out = tmp_path / "o.h5"
    proc = subprocess.Popen([str(cpu_bin), *SLOW, "--output", str(out), "--force"], stderr=subprocess.PIPE)
    assert wait_for_temporary(tmp_path, proc)
    out.write_bytes(b"user")
    proc.communicate(timeout=120)
    assert proc.returncode == 0 and out.read_bytes()[:4] != b"user"


# ---- the harness (rows 6, 7, 8, 9, 12, 13) -------------------------------------------------


def no_traceback(p):
    assert "Traceback" not in p.stderr, p.stderr


def test_stability_from_csv_not_text(tmp_path):
    h5 = tmp_path / "some.h5"
    h5.write_bytes(b"\x89HDF\r\n\x1a\n\xff\xfe" + bytes(range(256)))
    p = harness("stability", "--from-csv", h5, "--report-dir", tmp_path / "rep")
    no_traceback(p)
    assert p.returncode != 0 and len(p.stderr.strip().splitlines()) == 1, p.stderr


def test_accuracy_from_csv_names_the_file_and_creates_nothing(tmp_path):
    bad = tmp_path / "bad.csv"
    bad.write_text("a,b\n1,2\n")
    rep = tmp_path / "rep"
    p = harness("accuracy", "--model", "dynamic", "--from-csv", bad, "--report-dir", rep)
    no_traceback(p)
    assert p.returncode != 0 and "bad.csv" in p.stderr and "dynamic_accuracy.csv" not in p.stderr, p.stderr
    assert not rep.exists()


def test_run_without_output_claims_no_removed_path(cpu_bin):
    p = harness("run", "dynamic", "--strands", 20, "--frames", 2)
    assert p.returncode == 0, p.stderr
    for line in p.stdout.splitlines():
        if line.startswith("wrote "):
            assert Path(line[len("wrote ") :]).exists(), line


def test_run_into_a_closed_pipe_is_quiet(cpu_bin):
    p = subprocess.run(
        f"{sys.executable} -m harness run dynamic --strands 10 --frames 2 | head -1",
        shell=True,
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert p.stdout.count("\n") == 1 and p.stderr == "", p.stderr


def test_run_timeout_removes_the_childs_temporary(cpu_bin, tmp_path):
    out = tmp_path / "to.h5"
    p = harness("run", "dynamic", "--strands", 2000, "--frames", 400, "--timeout", 1, "--output", out)
    no_traceback(p)
    assert p.returncode != 0 and "did not finish" in p.stderr, p.stderr
    assert os.listdir(tmp_path) == []


def test_interrupted_run_says_so(cpu_bin, tmp_path):
    proc = subprocess.Popen(
        [sys.executable, "-m", "harness", "run", "dynamic", "--strands", "2000", "--frames", "4000"]
        + ["--output", str(tmp_path / "o.h5")],
        cwd=ROOT,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        # a shell's background job ignores SIGINT, and Python then never raises KeyboardInterrupt:
        # the harness gets Ctrl-C as a user's terminal delivers it
        preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL),
    )
    # the binary may create its temporary only when it writes, at the end: interrupt while it computes
    assert wait_for_child(proc, "hairsim-cpu", timeout=60)
    time.sleep(0.5)
    proc.send_signal(signal.SIGINT)  # Ctrl-C reaching Python only
    _, err = proc.communicate(timeout=60)
    assert proc.returncode == 130 and err.strip() == "harness: interrupted", err
    assert os.listdir(tmp_path) == []
