"""The set-up that `make test` and `make bench` run first (harness/setup.sh): with the
packages importable it installs nothing (machines without a network), and with them
missing it installs requirements.lock — here into a throw-away copy, against a PyPI that
cannot be reached, so it must stop with one line saying what to run."""

import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

ROOT_DIR = Path(__file__).resolve().parents[2]
NO_NETWORK = {
    "PIP_INDEX_URL": "http://127.0.0.1:9/simple",
    "http_proxy": "http://127.0.0.1:9",
    "https_proxy": "http://127.0.0.1:9",
    "PIP_CONFIG_FILE": os.devnull,
}


def copy_of_repo(tmp_path):
    root = tmp_path / "repo"
    (root / "harness").mkdir(parents=True)
    shutil.copy(ROOT_DIR / "harness" / "setup.sh", root / "harness" / "setup.sh")
    for name in ("requirements.lock", "requirements-readers.lock"):
        shutil.copy(ROOT_DIR / name, root / name)
    return root


def setup(root, python, **env):
    e = {k: v for k, v in os.environ.items() if k != "HAIRBENCH_READERS"}
    e.update(NO_NETWORK, PYTHON=str(python), **env)
    return subprocess.run(
        ["bash", str(root / "harness" / "setup.sh"), "build/python"],
        cwd=root,
        env=e,
        capture_output=True,
        text=True,
        timeout=300,
    )


def test_lock_pins_exact_versions():
    for name in ("requirements.lock", "requirements-readers.lock"):
        lines = [ln for ln in (ROOT_DIR / name).read_text().splitlines() if ln and not ln.startswith("#")]
        assert lines and all("==" in ln for ln in lines), name


def test_nothing_is_installed_when_the_packages_import(tmp_path):
    """The lock is not installed where its packages import; the renderer, which the lock holds but
    nothing requires, is tried on its own where it does not (a GPU node's image without moderngl)."""
    root = copy_of_repo(tmp_path)
    p = setup(root, sys.executable)
    assert p.returncode == 0, p.stderr
    renderer = subprocess.run([sys.executable, "-c", "import moderngl"], capture_output=True).returncode == 0
    installs = [ln for ln in p.stderr.splitlines() if "installing" in ln]
    assert installs == ([] if renderer else [ln for ln in installs if "installing the renderer" in ln]), p.stderr
    assert renderer or len(installs) == 1, p.stderr
    assert not (root / ".venv").exists()
    assert Path((root / "build" / "python").read_text().strip()).exists()


def test_missing_packages_without_network_stop_in_one_line(tmp_path):
    bare = tmp_path / "bare"
    made = subprocess.run([sys.executable, "-m", "venv", str(bare)], capture_output=True, text=True)
    if made.returncode != 0:
        pytest.skip(f"cannot make a bare virtual environment here: {made.stderr.strip()[-200:]}")
    root = copy_of_repo(tmp_path)
    p = setup(root, bare / "bin" / "python")
    assert p.returncode != 0
    errors = [ln for ln in p.stderr.splitlines() if ln.startswith("error: ")]
    assert len(errors) == 1 and "pip install -r requirements.lock" in errors[0], p.stderr
    assert "installing requirements.lock" in p.stderr  # it did try: the packages were missing


def test_a_system_interpreter_is_never_installed_into(tmp_path):
    """An interpreter outside any virtual environment that lacks the packages (here the real
    one with its site-packages hidden, -S) gets the project environment .venv instead: pip is
    pointed at .venv, never at that interpreter (here it fails for want of a network)."""
    base = Path(getattr(sys, "_base_executable", sys.executable))
    system = tmp_path / "system-python"
    system.write_text(f'#!/bin/sh\nexec "{base}" -S "$@"\n')
    system.chmod(0o755)
    probe = subprocess.run([str(system), "-c", "import sys; print(sys.prefix != sys.base_prefix)"], capture_output=True)
    if probe.stdout.strip() != b"False":
        pytest.skip("no interpreter outside a virtual environment here")
    root = copy_of_repo(tmp_path)
    p = setup(root, system)
    assert p.returncode != 0
    assert "installing requirements.lock into the project environment .venv" in p.stderr, p.stderr
    errors = [ln for ln in p.stderr.splitlines() if ln.startswith("error: ")]
    assert len(errors) == 1 and ".venv" in errors[0] and "-S" not in errors[0], p.stderr
