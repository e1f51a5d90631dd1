"""Writes that cannot hurt (docs/interfaces.md, "Writing the output"): an --output that is
not a regular file is refused even with --force, a signalled run leaves no temporary file
and exits non-zero, and the next run into a directory removes the temporaries of dead runs."""

import os
import shutil
import signal
import subprocess
import time
from pathlib import Path

import pytest

from harness.core import tempfiles
from support.statecheck import run

ROOT_DIR = Path(__file__).resolve().parents[2]


def tmp_leftovers(directory):
    return sorted(p.name for p in Path(directory).iterdir() if p.name.startswith(".hairsim-"))


SMALL = ["--strands", "20", "--points", "8", "--hair-length", "5", "--quiet"]
HDF5_SIGNATURE = b"\x89HDF\r\n\x1a\n"


def _refused(cpu_bin, output, text):
    for force in ([], ["--force"]):
        p = run(cpu_bin, *SMALL, "--output", output, *force, check=False)
        assert p.returncode == 2, p.stderr
        lines = p.stderr.strip().splitlines()
        assert len(lines) == 1 and text in lines[0], p.stderr


def test_device_is_refused(cpu_bin, tmp_path):
    before = os.stat("/dev/null")
    _refused(cpu_bin, "/dev/null", "is a device")
    after = os.stat("/dev/null")
    assert (before.st_mode, before.st_rdev) == (after.st_mode, after.st_rdev)


def test_directory_fifo_and_symlink_are_refused(cpu_bin, tmp_path):
    (tmp_path / "dir").mkdir()
    _refused(cpu_bin, tmp_path / "dir", "is a directory")
    os.mkfifo(tmp_path / "fifo")
    _refused(cpu_bin, tmp_path / "fifo", "is a FIFO")
    (tmp_path / "target.h5").write_bytes(b"keep")
    (tmp_path / "link.h5").symlink_to(tmp_path / "target.h5")
    _refused(cpu_bin, tmp_path / "link.h5", "is a symbolic link")
    assert (tmp_path / "target.h5").read_bytes() == b"keep"
    assert tmp_leftovers(tmp_path) == []


def test_force_replaces_a_regular_file(cpu_bin, tmp_path):
    out = tmp_path / "s.h5"
    out.write_bytes(b"old")
    run(cpu_bin, *SMALL, "--output", out, "--force")
    # the superblock follows the 512-byte user block that held the temporary's marker
    assert out.read_bytes()[512:520] == HDF5_SIGNATURE


def _wait_for_tmp(directory, proc, timeout=60):
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        if tmp_leftovers(directory):
            return True
        if proc.poll() is not None:
            return False
        time.sleep(0.02)
    return False


@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGTERM], ids=["SIGINT", "SIGTERM"])
def test_signal_removes_the_temporary(cpu_bin, tmp_path, sig):
    out = tmp_path / "big.h5"
    # large enough that the run is still writing frames when the signal comes
    proc = subprocess.Popen(
        [
            str(cpu_bin),
            "--strands",
            "2000000",
            "--points",
            "32",
            "--threads",
            "1",
            "--stages",
            "init,collide,wind,collide,wind,collide,wind,collide",
            "--output",
            str(out),
            "--quiet",
        ],
        stderr=subprocess.PIPE,
    )
    try:
        assert _wait_for_tmp(tmp_path, proc), "the run ended before its temporary file appeared"
        proc.send_signal(sig)
        rc = proc.wait(timeout=60)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
    assert rc != 0
    assert rc == -sig  # died of the signal, as a shell reports 128 + n
    assert tmp_leftovers(tmp_path) == []
    assert not out.exists()


def test_stale_temporaries_of_dead_runs_are_removed(cpu_bin, tmp_path):
    p = subprocess.Popen(["true"])
    p.wait()
    pid = p.pid
    marker = tempfiles.MARKER
    (tmp_path / f".hairsim-{pid}-00000000000000aa.tmp").write_bytes(marker + b"rest")
    (tmp_path / f".hairsim-{pid}-00000000000000bb.tmp").write_bytes(marker)
    (tmp_path / f".hairsim-{pid}-00000000000000cc.tmp").write_bytes(HDF5_SIGNATURE)  # no marker: kept
    (tmp_path / f".hairsim-{os.getpid()}-00000000000000dd.tmp").write_bytes(marker)  # live pid: kept
    (tmp_path / f"old.h5.tmp.{pid}").write_bytes(HDF5_SIGNATURE)  # not our name: kept
    r = run(cpu_bin, *SMALL, "--output", tmp_path / "new.h5")
    notes = [line for line in r.stderr.splitlines() if "stale temporary" in line]
    assert len(notes) == 1 and "removed 2 stale temporary files" in notes[0], r.stderr
    assert tmp_leftovers(tmp_path) == sorted(
        [f".hairsim-{os.getpid()}-00000000000000dd.tmp", f".hairsim-{pid}-00000000000000cc.tmp"]
    )
    assert (tmp_path / f"old.h5.tmp.{pid}").exists()


def test_fsync_before_the_rename(cpu_bin, tmp_path):
    """The system calls themselves, seen by strace: the temporary is fsynced, then renamed
    over the output, then the directory is fsynced."""
    if shutil.which("strace") is None:
        pytest.skip("strace not installed (apt-get install strace)")
    out = tmp_path / "s.h5"
    trace = tmp_path / "trace"
    p = subprocess.run(
        ["strace", "-f", "-y", "-o", str(trace), "-e", "trace=fsync,fdatasync,rename,renameat,renameat2"]
        + [str(cpu_bin), *SMALL, "--output", str(out)],
        capture_output=True,
        text=True,
        timeout=600,
    )
    if p.returncode != 0 and "ptrace" in p.stderr:
        pytest.skip(f"strace cannot trace here: {p.stderr.strip()[-200:]}")
    assert p.returncode == 0, p.stderr
    calls = [line.split(None, 1)[1] for line in trace.read_text().splitlines() if "(" in line and "---" not in line]
    synced = [
        i for i, c in enumerate(calls) if c.startswith(("fsync(", "fdatasync(")) and f"<{tmp_path}/.hairsim-" in c
    ]
    renamed = [i for i, c in enumerate(calls) if c.startswith("rename") and f'"{out}"' in c and c.endswith("= 0")]
    dir_synced = [i for i, c in enumerate(calls) if c.startswith("fsync(") and f"<{tmp_path}>)" in c]
    assert synced and renamed and dir_synced, calls
    assert synced[-1] < renamed[0] < dir_synced[-1], calls


def test_output_replaced_while_running_is_refused_and_the_temporary_removed(cpu_bin, tmp_path):
    """An error path with a real run: the --output becomes a directory while the run writes
    its temporary; the check before the rename refuses it, and nothing is left behind."""
    out = tmp_path / "s.h5"
    proc = subprocess.Popen(
        [str(cpu_bin), "--strands", "4000", "--points", "16", "--stages", "init,simulate", "--frames", "600"]
        + ["--threads", "1", "--output", str(out), "--quiet"],
        stderr=subprocess.PIPE,
        text=True,
    )
    try:
        assert _wait_for_tmp(tmp_path, proc), "the run ended before its temporary file appeared"
        out.mkdir()
        _, err = proc.communicate(timeout=600)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
    assert proc.returncode != 0 and "is a directory" in err, err
    assert err.strip().count("\n") == 0, err
    assert out.is_dir() and not any(out.iterdir())
    assert tmp_leftovers(tmp_path) == []
