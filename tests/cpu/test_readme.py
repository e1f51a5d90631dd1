"""The README's "Running one simulation" runs as written: its shell blocks, taken from
README.md itself, run in order in a scratch directory (with `build/` the repository's
binaries and `python3` this interpreter), each line must succeed. The block that needs a
GPU runs where there is one (marked `gpu`). Without usd-core, `export … --usd` runs without
`--usd` (the README says the USD sidecar needs usd-core). Every file the examples write is
under results/ (ignored by git), the first screen (up to that section) stays one screen, and
its headline numbers are those of the committed results they name."""

import importlib.util
import json
import os
import re
import subprocess
import sys
from pathlib import Path

from conftest import GPU_REASON

ROOT_DIR = Path(__file__).resolve().parents[2]
SECTION = "## Running one simulation"
FIRST_SCREEN = 64  # lines before the examples: a screen, the picture one of them


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
    assert (tmp_path / "results/try/c.h5.xdmf").is_file()
    if GPU_REASON is None:
        run_block(blocks[1], tmp_path, env)
    run_block(blocks[2], tmp_path, env)
    for name in ("paper.h5", "s.h5", "c.h5", "d.h5", "f.h5", "f2.h5"):
        assert (tmp_path / "results/try" / name).is_file(), name
    written = {p.relative_to(tmp_path).parts[0] for p in tmp_path.iterdir()} - {"build", ".bin"}
    assert written == {"results"}, f"the examples wrote outside results/: {written}"


def test_every_file_the_examples_name_is_under_results():
    """Each --output and each state handed to export, diff or stepdiff lies under results/, which
    git ignores: the examples never write into the repository's root."""
    blocks = "\n".join(run_section_blocks())
    named = re.findall(r"--(?:output|input|reference) (\S+)", blocks) + re.findall(r"harness \w+ (\S+\.h5)", blocks)
    named += re.findall(r"harness diff \S+ (\S+)", blocks)
    assert len(named) >= 12 and all(n.startswith("results/try/") for n in named), named
    ignored = subprocess.run(["git", "check-ignore", "-q", "results/try/x.h5"], cwd=ROOT_DIR)
    assert ignored.returncode == 0, "results/try/ is not ignored by git"


def test_the_first_screen_is_one_screen():
    """What hairbench is, the headline, the commands, prerequisites and links come before the
    examples, in at most FIRST_SCREEN lines."""
    text = (ROOT_DIR / "README.md").read_text()
    first = text[: text.index(SECTION)].splitlines()
    assert len(first) <= FIRST_SCREEN, f"the README's first screen is {len(first)} lines"
    heads = [line for line in first if line.startswith("## ")]
    assert heads == ["## What it measured", "## Start", "## Prerequisites", "## Read on"], heads
    assert (
        "make test" in text[: text.index("## Prerequisites")] and "make bench" in text[: text.index("## Prerequisites")]
    )


def test_the_headline_is_the_committed_results():
    """The README's headline numbers, as printed, are the committed headline JSONs' values rounded."""
    text = (ROOT_DIR / "README.md").read_text()
    head = ROOT_DIR / "results/reference-h200/headline"
    paper = json.loads((head / "headline.json").read_text())
    dyn = json.loads((head / "headline_dynamic.json").read_text())
    rows = {r["label"]: r for r in paper["rows"]}
    lanes = next(r for r in dyn["default"] if r["label"] == "gpu lanes")
    simd = next(r for r in dyn["cpu"] if r["label"] == "cpu simd, all cores" and r["case"] == "default")
    printed = {
        f"{rows['gpu fused fp32']['wind_collide_ms']:.3f} ms": "the GPU's paper time",
        f"{100 * rows['gpu fused fp32']['wind_collide_fraction']:.1f}% of copy bandwidth": "its bandwidth",
        f"{rows['cpu simd, all cores']['wind_collide_ms']:.1f} ms": "the CPU's paper time",
        f"**{paper['speedups']['cpu simd, all cores']:.1f}×**": "the paper speed-up",
        f"{lanes['median_ms']:.1f} ms": "the GPU's dynamic time",
        f"{lanes['point_substeps_per_s']:.2e} point-substeps/s".replace("e+", "e"): "its throughput",
        f"{simd['median_ms']:.0f} ms at {simd['strands']:,} strands": "the CPU's dynamic time",
        f"**{dyn['summary']['speedups']['default']['cpu simd, all cores']:.0f}×**": "the dynamic speed-up",
        f"{dyn['summary']['realtime']['kernel_ms']:.3f} ms of GPU time": "10,000 strands",
    }
    missing = [f"{what}: {s}" for s, what in printed.items() if s not in text]
    assert not missing, missing
    assert paper["env"]["device"] == dyn["env"]["device"] == "NVIDIA H200" and "H200" in text
    assert paper["env"]["git_revision"].split()[0] in text
