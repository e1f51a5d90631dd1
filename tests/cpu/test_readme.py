"""The README's "Running one simulation" runs as written: its shell blocks, taken from
README.md itself, run in order in a scratch directory (with `build/` the repository's
binaries and `python3` this interpreter), each line must succeed. The block that needs a
GPU runs where there is one (marked `gpu`). Without usd-core, `export … --usd` runs without
`--usd` (the README says the USD sidecar needs usd-core)."""

import importlib.util
import os
import re
import subprocess
import sys
from pathlib import Path

from conftest import GPU_REASON

ROOT_DIR = Path(__file__).resolve().parents[2]
SECTION = "## Running one simulation"


def run_section_blocks():
    """The ```sh blocks of the README's run section, in order, as text."""
    text = (ROOT_DIR / "README.md").read_text()
    start = text.index(SECTION)
    end = text.find("\n## ", start + len(SECTION))
    return re.findall(r"```sh\n(.*?)```", text[start : end if end > 0 else None], re.S)


def scratch(tmp_path):
    """A directory where `build/…` and `python3 -m harness` mean what they mean at the root."""
    (tmp_path / "build").symlink_to(ROOT_DIR / "build")
    shims = tmp_path / ".bin"
    shims.mkdir()
    python3 = shims / "python3"  # a script, not a link: a virtual environment's python must see its own path
    python3.write_text(f'#!/bin/sh\nexec "{sys.executable}" "$@"\n')
    python3.chmod(0o755)
    env = dict(os.environ, PATH=f"{shims}{os.pathsep}{os.environ['PATH']}", PYTHONPATH=str(ROOT_DIR))
    return env


def run_block(block, cwd, env):
    if importlib.util.find_spec("pxr") is None:
        block = block.replace(" --usd ", " ").replace(" --usd\n", "\n")
    p = subprocess.run(
        ["bash", "-euo", "pipefail", "-x", "-c", block], cwd=cwd, env=env, capture_output=True, text=True, timeout=900
    )
    assert p.returncode == 0, f"README block failed (exit {p.returncode}):\n{p.stderr[-3000:]}"
    return p


def test_the_run_section_has_the_blocks_this_test_expects():
    blocks = run_section_blocks()
    assert len(blocks) == 3, blocks
    assert "hairsim-cuda" not in blocks[0] + blocks[2] and "hairsim-cuda" in blocks[1]


def test_readme_run_section_runs_as_written(tmp_path):
    blocks = run_section_blocks()
    env = scratch(tmp_path)
    run_block(blocks[0], tmp_path, env)
    assert (tmp_path / "c.h5.xdmf").is_file()
    if GPU_REASON is None:
        run_block(blocks[1], tmp_path, env)
    run_block(blocks[2], tmp_path, env)
    for name in ("paper.h5", "s.h5", "c.h5", "d.h5", "f.h5", "f2.h5"):
        assert (tmp_path / name).is_file(), name
