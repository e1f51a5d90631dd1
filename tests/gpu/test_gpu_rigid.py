"""The no-simulation solver (`--solver rigid`, docs/model.md §3.13) is the C reference's
alone: every cuda build declares, per simulating variant, the solvers it runs without it,
and refuses it in one line with exit 2 before any work."""

import json
import subprocess

import pytest

from conftest import CUDA_BIN, CUDA_FASTMATH_BIN, CUDA_STRICT_BIN

pytestmark = pytest.mark.gpu


@pytest.mark.parametrize("binary", [CUDA_BIN, CUDA_STRICT_BIN, CUDA_FASTMATH_BIN], ids=["normal", "strict", "fastmath"])
def test_cuda_declares_and_refuses_the_rigid_solver(binary, tmp_path):
    if not binary.exists():
        pytest.skip(f"{binary} is not built")
    listing = json.loads(subprocess.run([binary, "--list-variants"], capture_output=True, text=True).stdout)
    assert "rigid" not in listing["solvers"]
    simulating = [v for v in listing["variants"] if "simulate" in v["stages"]]
    assert simulating and all(v["solvers"] == ["xpbd", "ftl"] for v in simulating)
    for v in simulating:
        out = tmp_path / f"{v['name']}.h5"
        p = subprocess.run(
            [binary, "--stages", "init,collide,simulate", "--strands", "4", "--points", "8", "--frames", "1",
             "--solver", "rigid", "--variant", v["name"], "--output", out, "--quiet"],
            capture_output=True, text=True,
        )  # fmt: skip
        assert p.returncode == 2, p.stderr
        assert len(p.stderr.strip().splitlines()) == 1 and "does not run it" in p.stderr
        assert not out.exists()
