"""The environment record of a sweep (results/<name>/env.json) and GPU detection.

Every probe is best effort: a tool that is missing gives null, never an error."""

import datetime
import os
import platform
import shutil
import sys

from harness.core.paths import ROOT


def _cmd(args, timeout=20):
    from harness.core import runner

    try:
        out = runner.run_command(args, timeout=timeout, cwd=ROOT)
    except (OSError, runner.TimedOut):
        return None
    return out.stdout.strip() if out.returncode == 0 else None


def gpu_status():
    """(usable, reason): whether an NVIDIA GPU answers here, else why not."""
    if os.environ.get("HAIRBENCH_NO_GPU"):
        return False, "HAIRBENCH_NO_GPU is set"
    smi = shutil.which("nvidia-smi")
    if smi is None:
        return False, "no nvidia-smi on PATH: this machine has no NVIDIA GPU"
    out = _cmd([smi, "-L"], timeout=30)
    if not out or "GPU" not in out:
        return False, "nvidia-smi lists no GPU"
    return True, out.splitlines()[0]


def cpu_model():
    try:
        with open("/proc/cpuinfo") as f:
            for line in f:
                if line.startswith("model name"):
                    return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or None


def usable_cores():
    """The cores this process may run on (its affinity mask: a scheduler's or taskset's share of the
    host), as OpenMP's default counts them; the harness sizes threads and worker pools by it."""
    if hasattr(os, "sched_getaffinity"):
        return len(os.sched_getaffinity(0)) or 1
    return os.cpu_count() or 1


def cpu_device():
    """This machine's CPU as the cpu binary's records name it (c_ref/backend_cpu.c cpu_describe): its
    model and the cores this process may run on."""
    return f"{cpu_model() or 'unknown CPU'} ({usable_cores()} cores)"


GPU_QUERY = ("name", "driver_version", "memory.total", "compute_cap")


def gpu_info():
    """Each GPU's name, driver, memory and compute capability (an older driver without
    compute_cap: the other three)."""
    if not shutil.which("nvidia-smi"):
        return None
    for fields in (GPU_QUERY, GPU_QUERY[:3]):
        out = _cmd(["nvidia-smi", f"--query-gpu={','.join(fields)}", "--format=csv,noheader"])
        if out:
            break
    else:
        return None
    gpus = []
    for line in out.splitlines():
        parts = [p.strip() for p in line.split(",")]
        if len(parts) == len(fields):
            gpu = {"name": parts[0], "driver": parts[1], "memory": parts[2]}
            if len(parts) == 4:
                gpu["compute_capability"] = parts[3]
            gpus.append(gpu)
    return gpus or None


def first_line(text):
    return text.splitlines()[0] if text else None


def nvcc_version():
    out = _cmd(["nvcc", "--version"])
    if not out:
        return None
    lines = [ln for ln in out.splitlines() if "release" in ln]
    return lines[-1].strip() if lines else first_line(out)


def git_revision():
    # A REVISION file wins (the Makefile's rule): it is written beside a tree copied to a
    # GPU node, whose own .git, if any, can be stale.
    try:
        written = (ROOT / "REVISION").read_text().strip()
    except OSError:
        written = ""
    if written:
        return written + " (REVISION file)"
    rev = _cmd(["git", "rev-parse", "--short", "HEAD"])
    if rev is None:
        return "unknown (no commit)"
    dirty = _cmd(["git", "status", "--porcelain", "--untracked-files=no"])
    return rev + ("-dirty" if dirty else "")


def now():
    return datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds")


def collect():
    """The environment of this machine, now."""
    gpus = gpu_info()
    return {
        "date": now(),
        "hostname": platform.node(),
        "os": platform.platform(),
        "python": sys.version.split()[0],
        "cpu_model": cpu_model(),
        "cpu_cores": os.cpu_count(),
        "usable_cores": usable_cores(),
        "gpus": gpus,
        "device": gpus[0]["name"] if gpus else None,
        "driver": gpus[0]["driver"] if gpus else None,
        "nvcc": nvcc_version(),
        "gcc": first_line(_cmd(["gcc", "--version"])),
        "git_revision": git_revision(),
    }
