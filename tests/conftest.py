"""Shared pytest fixtures: where the binaries are, and the skipping of `gpu` tests (the
marker itself is declared in pyproject.toml).

GPU tests are marked `@pytest.mark.gpu`; they are skipped, with the reason, where no
usable NVIDIA GPU (or no built CUDA binary) is present.
"""

import os
from pathlib import Path

import pytest
from hypothesis.configuration import set_hypothesis_home_dir

# fixtures kept beside the helpers they use: `stubbed` (the dynamic bench's studies as recorders)
pytest_plugins = ["support.bench_stubs"]

ROOT = Path(__file__).resolve().parent.parent
BUILD = ROOT / "build"
# `make sanitize` points the CPU tests at the ASan/UBSan build through HAIRBENCH_CPU_BIN.
CPU_BIN = Path(os.environ.get("HAIRBENCH_CPU_BIN", BUILD / "hairsim-cpu")).resolve()
CUDA_BIN = BUILD / "hairsim-cuda"
CUDA_STRICT_BIN = BUILD / "hairsim-cuda-strict"
CUDA_FASTMATH_BIN = BUILD / "hairsim-cuda-fastmath"


def _gpu_reason():
    """Return None when a GPU is usable here, else the reason it is not (harness.core.env's
    detection, the one the harness uses, plus the built CUDA binary)."""
    from harness.core import env

    ok, why = env.gpu_status()
    if not ok:
        return why
    if not CUDA_BIN.exists():
        return f"{CUDA_BIN} is not built (run make)"
    return None


GPU_REASON = _gpu_reason()

# hypothesis's files (its example database) under build/, beside pytest's cache (pyproject.toml)
set_hypothesis_home_dir(str(BUILD / "hypothesis"))


def pytest_collection_modifyitems(config, items):
    if GPU_REASON is None:
        return
    skip = pytest.mark.skip(reason=f"GPU test skipped: {GPU_REASON}")
    for item in items:
        if "gpu" in item.keywords:
            item.add_marker(skip)


@pytest.fixture(scope="session")
def cpu_bin():
    if not CPU_BIN.exists():
        pytest.fail(f"{CPU_BIN} is not built: run `make` first")
    return CPU_BIN


@pytest.fixture(scope="session")
def cuda_bin():
    return CUDA_BIN


def pytest_terminal_summary(terminalreporter):
    """The fault matrices' counts (tests/cpu/test_fault_probe.py, listed; tests/cpu/test_fault_matrix.py,
    generated from the declared inputs): their cases by row, and outcomes."""
    for module, title in (("test_fault_probe.py", "fault probe"), ("test_fault_matrix.py", "generated fault matrix")):
        counts: dict[str, dict[str, int]] = {}
        for outcome in ("passed", "failed", "skipped", "error"):
            for rep in terminalreporter.stats.get(outcome, []):
                nodeid = getattr(rep, "nodeid", "")
                if f"{module}::" not in nodeid or getattr(rep, "when", "call") not in ("call", "setup"):
                    continue
                if outcome == "passed" and rep.when != "call":
                    continue
                name = nodeid.split("::", 1)[1].split("[", 1)[0]
                counts.setdefault(name, {}).setdefault(outcome, 0)
                counts[name][outcome] += 1
        if counts:
            total = {o: sum(c.get(o, 0) for c in counts.values()) for o in ("passed", "failed", "skipped", "error")}
            terminalreporter.write_line(
                f"{title}: {sum(total.values())} cases in {len(counts)} rows of the matrix: "
                + ", ".join(f"{n} {o}" for o, n in total.items() if n)
            )
