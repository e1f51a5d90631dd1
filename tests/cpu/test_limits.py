"""#47: the binaries export the limits they check (`--limits`, docs/interfaces.md) and the
harness reads them there (harness/core/limits.py): each printed bound is where the binary's
own check refuses, and the harness refuses a value past it with the binary's number."""

import json

import pytest

from harness import HarnessError
from harness.cli.main import main as harness_main
from harness.core import limits as limits_module
from harness.core.limits import limits
from harness.io.sweepfile import load_sweep
from support.statecheck import run

SIM = ["--stages", "init,simulate", "--strands", "1", "--points", "2", "--frames", "1"]


def test_the_binary_prints_one_json_object_and_the_harness_reads_it(cpu_bin):
    p = run(cpu_bin, "--limits")
    printed = json.loads(p.stdout)
    assert p.stdout.count("\n") == 1 and printed["backend"] == "cpu"
    got = limits()
    assert got.substeps_max == printed["substeps_max"] and got.iterations_max == printed["iterations_max"]
    assert got.substep_s == tuple(printed["substep_s"]) and got.grid_n == tuple(printed["grid_n"])
    assert got.collider_sweeps == tuple(printed["collider_sweeps"])
    assert got.block_size == (
        printed["block_size"]["min"],
        printed["block_size"]["max"],
        printed["block_size"]["multiple"],
    )
    assert "--limits" in run(cpu_bin, "--help").stdout


@pytest.mark.parametrize("flag", ["--substeps", "--iterations"])
def test_the_count_bound_is_where_the_binary_refuses(cpu_bin, tmp_path, flag):
    most = limits().substeps_max if flag == "--substeps" else limits().iterations_max
    out = tmp_path / "s.h5"
    at = run(cpu_bin, *SIM, flag, most, "--output", out, check=False)
    assert at.returncode == 0, at.stderr
    past = run(cpu_bin, *SIM, flag, most + 1, "--output", out, "--force", check=False)
    assert past.returncode == 2 and flag in past.stderr


def test_the_grid_and_substep_bounds_are_where_the_binary_refuses(cpu_bin, tmp_path):
    lim, out = limits(), tmp_path / "s.h5"
    for n in lim.grid_n:
        assert run(cpu_bin, *SIM, "--grid", n, "--output", out, "--force", check=False).returncode == 0
    for n in (lim.grid_n[0] - 1, lim.grid_n[1] + 1):
        p = run(cpu_bin, *SIM, "--grid", n, "--output", out, "--force", check=False)
        assert p.returncode == 2 and "--grid" in p.stderr
    shortest = lim.substep_s[0]
    p = run(cpu_bin, *SIM, "--frame-dt", shortest / 2, "--output", out, "--force", check=False)
    assert p.returncode == 2 and "substep" in p.stderr


def test_the_cuda_binary_refuses_a_block_size_the_limits_refuse(cuda_bin):
    if not cuda_bin.exists():
        pytest.skip(f"{cuda_bin} is not built")
    lo, hi, step = limits("cuda").block_size
    assert limits("cuda") == limits()  # one parser: both binaries print the same bounds
    for bad in (lo + 1, hi + step, lo - step):
        p = run(cuda_bin, "--block-size", bad, "--strands", "1", check=False)
        assert p.returncode == 2 and "--block-size" in p.stderr
        assert limits().block_size_error(bad)


def test_the_harness_refuses_what_the_limits_refuse(tmp_path, capsys):
    lo, hi, step = limits().block_size
    with pytest.raises(SystemExit) as e:
        harness_main(["run", "--backend", "cuda", "--block-size", str(lo + 1)])
    assert e.value.code == 2
    assert f"not a multiple of {step} in {lo}…{hi}" in capsys.readouterr().err
    sweep = tmp_path / "sw.toml"
    sweep.write_text(f'scene = "paper"\nrepeat = 9\n[cuda]\nblock_size = [{lo + 1}]\n')
    with pytest.raises(HarnessError, match=f"block_size {lo + 1} is not a multiple of {step}"):
        load_sweep(sweep)
    scene, out = tmp_path / "s.toml", tmp_path / "o.h5"
    scene.write_text(f'model = "dynamic"\n[dynamics]\nsubsteps = {limits().substeps_max + 1}\n')
    assert harness_main(["run", str(scene), "--output", str(out)]) == 2
    assert f"dynamics.substeps must lie in 1 … {limits().substeps_max}" in capsys.readouterr().err
    assert not out.exists()


def test_a_binary_that_prints_no_limits_is_refused_in_one_line(tmp_path):
    fake = tmp_path / "hairsim-cpu"
    fake.write_text("#!/bin/sh\necho '{\"substeps_max\": 1}'\n")
    fake.chmod(0o755)
    with pytest.raises(HarnessError, match="did not print the documented JSON object"):
        limits_module._read(str(fake))
