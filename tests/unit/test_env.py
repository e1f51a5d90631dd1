"""harness.core.env.git_revision: which code a result says it came from (docs/harness.md,
"Which code a result came from")."""

import os
import shutil
import subprocess
import sys

import pytest

from harness.core import env


def test_revision_file_wins_over_git(tmp_path, monkeypatch):
    # a copied tree with a stale .git would give git's HEAD; the REVISION file must win
    monkeypatch.setattr(env, "ROOT", tmp_path)
    (tmp_path / "REVISION").write_text("c0ba5d78c75c\n")
    assert env.git_revision() == "c0ba5d78c75c (REVISION file)"


def test_without_revision_file_or_git_the_revision_is_unknown(tmp_path, monkeypatch):
    monkeypatch.setattr(env, "ROOT", tmp_path)
    assert env.git_revision() == "unknown (no commit)"
    (tmp_path / "REVISION").write_text("  \n")  # an empty file says nothing
    assert env.git_revision() == "unknown (no commit)"


def test_in_this_checkout_git_gives_the_head():
    if (env.ROOT / "REVISION").exists():
        pytest.skip("a REVISION file is present in this tree (a copied tree on a GPU node)")
    if shutil.which("git") is None:
        pytest.skip("git is not installed here: the revision cannot come from git")
    head = subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=env.ROOT, capture_output=True, text=True)
    if head.returncode != 0:
        pytest.skip("this tree is not a git checkout")
    assert env.git_revision().removesuffix("-dirty") == head.stdout.strip()


def test_no_revision_file_is_committed():
    """REVISION is written beside a tree copied to a GPU node, never committed: a committed
    one would stamp every later commit's binaries and results with its revision."""
    if shutil.which("git") is None:
        pytest.skip("git is not installed here")
    tracked = subprocess.run(["git", "ls-files", "REVISION"], cwd=env.ROOT, capture_output=True, text=True)
    if tracked.returncode != 0:
        pytest.skip("this tree is not a git checkout")
    assert tracked.stdout.strip() == "", "REVISION is tracked: git rm --cached REVISION"


def test_usable_cores_follow_the_affinity_mask():
    # a scheduler or taskset gives the process a share of the host: threads and pools are sized by that
    # share (as OpenMP's default is), not by the host's core count
    if not hasattr(os, "sched_setaffinity"):
        pytest.skip("this platform has no affinity mask")
    code = (
        "import os; from harness.core import env; os.sched_setaffinity(0, {min(os.sched_getaffinity(0))}); "
        "print(env.usable_cores(), env.cpu_device())"
    )
    out = subprocess.run([sys.executable, "-c", code], cwd=env.ROOT, capture_output=True, text=True, check=True)
    cores, device = out.stdout.split(" ", 1)
    assert cores == "1" and device.strip().endswith("(1 cores)"), out.stdout
    assert env.usable_cores() == len(os.sched_getaffinity(0))
