"""The CUDA build's architectures (Makefile CUDA_ARCH; docs/cuda.md, "Building for your GPU"):
those of the GPUs nvidia-smi reports, a given list as one fat binary, sm_90 where no GPU is
found. Read from `make -n` (nothing is compiled; nvcc is stood in for by `true`)."""

import os
import subprocess
import time

import pytest

from conftest import ROOT


def nvcc_lines(tmp_path, smi_output=None, **make_vars):
    """The nvcc command lines `make -n` would run for build/hairsim-cuda, with a stand-in
    nvidia-smi printing `smi_output` (None: no nvidia-smi at all)."""
    smi = tmp_path / "nvidia-smi"
    if smi_output is not None:
        smi.write_text(f"#!/bin/sh\nprintf '{smi_output}'\n")
        smi.chmod(0o755)
    args = [f"{k}={v}" for k, v in make_vars.items()]
    cmd = ["make", "-n", "-C", str(ROOT), f"BUILD={tmp_path / 'build'}", "NVCC=true", f"NVIDIA_SMI={smi}", *args]
    p = subprocess.run([*cmd, str(tmp_path / "build" / "hairsim-cuda")], capture_output=True, text=True, timeout=120,
                       env={k: v for k, v in os.environ.items() if k != "CUDA_ARCH"})  # fmt: skip
    assert p.returncode == 0, p.stderr
    lines = [ln for ln in p.stdout.splitlines() if ln.startswith("true ")]
    assert lines, p.stdout[-2000:]
    return lines


def test_no_gpu_builds_sm_90_alone(tmp_path):
    for line in nvcc_lines(tmp_path):
        assert "-arch=sm_90 " in line and "-gencode" not in line


def test_the_gpus_present_choose_the_architectures(tmp_path):
    lines = nvcc_lines(tmp_path, "8.6\\n12.0\\n8.6\\n")
    for line in lines:
        assert "-gencode arch=compute_86,code=sm_86 -gencode arch=compute_120,code=sm_120" in line
        assert "arch=compute_120,code=compute_120" in line  # the newest's PTX for a later GPU
    one = nvcc_lines(tmp_path, "8.9\\n")
    assert all("-arch=sm_89 " in ln for ln in one)


@pytest.mark.parametrize("given,want", [("sm_80", ["-arch=sm_80 "]), ("sm_75 sm_80", ["code=sm_75", "code=sm_80"])])
def test_a_given_list_wins_over_the_gpus_present(tmp_path, given, want):
    for line in nvcc_lines(tmp_path, "9.0\\n", CUDA_ARCH=given):
        assert all(w in line for w in want) and "sm_90" not in line


def device_opt_lines(tmp_path, target, **make_vars):
    """`make -n` for one CUDA object in BUILD=tmp_path/build, CUDA_DEVICE_OPT taken from make_vars
    alone (not from the environment: CI sets it); returns (returncode, nvcc lines, stderr)."""
    args = [f"{k}={v}" for k, v in make_vars.items()]
    cmd = ["make", "-n", "-C", str(ROOT), f"BUILD={tmp_path / 'build'}", "NVCC=true", "CUDA_ARCH=sm_90", *args]
    env = {k: v for k, v in os.environ.items() if k not in ("CUDA_ARCH", "CUDA_DEVICE_OPT")}
    p = subprocess.run([*cmd, str(tmp_path / "build" / target)], capture_output=True, text=True, timeout=120, env=env)
    return p.returncode, [ln for ln in p.stdout.splitlines() if ln.startswith("true ")], p.stderr


OBJ = "obj/cuda-normal/dynamic/world.o"


def test_device_opt_check_compiles_unoptimised_and_says_so(tmp_path):
    rc, full, err = device_opt_lines(tmp_path, OBJ)
    assert rc == 0, err
    assert full and not any("-Xptxas" in ln or "HB_DEVICE_OPT_CHECK" in ln for ln in full)
    rc, check, err = device_opt_lines(tmp_path, OBJ, CUDA_DEVICE_OPT="check")
    assert rc == 0, err
    assert check and all("-Xcicc -O1 -Xptxas -O0 -DHB_DEVICE_OPT_CHECK=1" in ln for ln in check)
    assert all("-arch=sm_90 " in ln for ln in check)  # every phase still runs for the architecture


def test_device_opt_change_recompiles_the_cuda_objects(tmp_path):
    rc, _, err = device_opt_lines(tmp_path, OBJ)  # writes the stamp: full
    assert rc == 0, err
    stamp = tmp_path / "build" / "cuda-device-opt.stamp"
    assert stamp.read_text().strip() == "full"
    obj = tmp_path / "build" / OBJ
    obj.parent.mkdir(parents=True)
    obj.write_bytes(b"")
    t = time.time() - 5  # the object newer than its sources and the stamp: nothing to do
    os.utime(obj, (t, t))
    os.utime(stamp, (t - 10, t - 10))
    rc, lines, err = device_opt_lines(tmp_path, OBJ)
    assert rc == 0 and lines == [], (err, lines)
    rc, lines, err = device_opt_lines(tmp_path, OBJ, CUDA_DEVICE_OPT="check")  # the stamp changes: rebuilt
    assert rc == 0 and len(lines) == 1 and "HB_DEVICE_OPT_CHECK" in lines[0], (err, lines)
    assert stamp.read_text().strip() == "check"


def test_device_opt_refuses_an_unknown_setting(tmp_path):
    rc, lines, err = device_opt_lines(tmp_path, OBJ, CUDA_DEVICE_OPT="fast")
    assert rc != 0 and lines == []
    assert "CUDA_DEVICE_OPT is 'fast': give full or check" in err
