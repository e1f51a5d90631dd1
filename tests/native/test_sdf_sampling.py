"""tools/sdf_sampling.cu (#43's SDF benchmark, docs/cuda.md) refuses bad input before it needs a GPU:
one `error:` line on stderr, exit 2, nothing on stdout, no JSON left and none the user had
overwritten. Skipped, with the reason, where nvcc is missing."""

import subprocess

import pytest
from test_cuda_port_host import ROOT, _tool

OBJ = ROOT / "configs" / "bodies" / "head.obj"


@pytest.fixture(scope="module")
def tool():
    nvcc = _tool("NVCC", "nvcc", "/usr/local/cuda/bin/nvcc")
    if nvcc is None:
        pytest.skip("nvcc not found (set NVCC or put it on PATH): tools/sdf_sampling.cu cannot be built")
    p = subprocess.run(
        ["make", "--no-print-directory", f"NVCC={nvcc}", "build/sdf-sampling"],
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=1800,
    )
    assert p.returncode == 0, f"make build/sdf-sampling exited {p.returncode}:\n{p.stdout[-4000:]}\n{p.stderr[-4000:]}"
    return ROOT / "build" / "sdf-sampling"


@pytest.mark.parametrize(
    "args, says",
    [
        (["--obj", "/nonexistent/head.obj", "--n", "64"], "no such file"),
        (["--obj", str(OBJ), "--n", "3"], "--n takes 8 to 512"),
        (["--obj", str(OBJ), "--n", "sixty"], "--n"),
        (["--obj", str(OBJ), "--points", "0"], "--points"),
        (["--obj", str(OBJ), "--frobnicate"], "--frobnicate"),
    ],
)
def test_bad_input_is_one_line_and_exit_2(tool, tmp_path, args, says):
    p = subprocess.run(
        [str(tool), *args, "--json", str(tmp_path / "out.json")], capture_output=True, text=True, timeout=120
    )
    lines = p.stderr.strip().splitlines()
    assert p.returncode == 2, (p.returncode, p.stderr)
    assert len(lines) == 1 and lines[0].startswith("error: ") and says in lines[0], p.stderr
    assert p.stdout == "" and not (tmp_path / "out.json").exists()


def test_an_existing_json_is_refused_and_kept(tool, tmp_path):
    out = tmp_path / "out.json"
    out.write_text("mine")
    p = subprocess.run([str(tool), "--obj", str(OBJ), "--json", str(out)], capture_output=True, text=True, timeout=120)
    assert p.returncode == 2 and p.stderr.startswith("error: --json ") and "exists" in p.stderr, p.stderr
    assert out.read_text() == "mine"
