"""The host's load while a figure is measured (docs/decisions/honest-timings.md): the CPU time
other processes used meanwhile, in cores (/proc/stat's busy time less this process's and its
children's own), the 1-minute load average when it started, and for a GPU round the GPU's
utilisation just before it (nvidia-smi, through the runner, when there). core/timing.py
judges a figure by it; this module only measures (the renderers, which read timing, never
reach the runner through it)."""

import os
import resource
import shutil
import time


def _cpu_busy_seconds():
    """CPU seconds the whole host has been busy (all cores), from /proc/stat; None where absent."""
    try:
        with open("/proc/stat") as f:
            v = [int(x) for x in f.readline().split()[1:9]]
    except (OSError, ValueError):
        return None
    return (sum(v) - v[3] - v[4]) / os.sysconf("SC_CLK_TCK")  # all but idle and iowait


def _own_cpu_seconds():
    me, kids = resource.getrusage(resource.RUSAGE_SELF), resource.getrusage(resource.RUSAGE_CHILDREN)
    return me.ru_utime + me.ru_stime + kids.ru_utime + kids.ru_stime


def gpu_busy_pct(gpu=None):
    """The GPU's utilisation (%) as nvidia-smi reports it now (`gpu`: its index), or None."""
    smi = shutil.which("nvidia-smi")
    if smi is None:
        return None
    from harness.core import runner

    cmd = [smi, "--query-gpu=utilization.gpu", "--format=csv,noheader,nounits"]
    if gpu is not None:
        cmd += ["-i", str(gpu)]
    try:
        out = runner.run_command(cmd, timeout=10)
        return float(out.stdout.split()[0]) if out.returncode == 0 and out.stdout.split() else None
    except (OSError, runner.TimedOut, ValueError):
        return None


class LoadProbe:
    """Around a piece of work: others' CPU use (cores) over its wall time, the load average when
    it started and (`gpu`: a GPU round) the GPU's utilisation just before it."""

    def __init__(self, gpu=False, gpu_index=None):
        self.loadavg = os.getloadavg()[0] if hasattr(os, "getloadavg") else float("nan")
        self.gpu_pct = gpu_busy_pct(gpu_index) if gpu else None
        self.t0, self.busy0, self.own0 = time.monotonic(), _cpu_busy_seconds(), _own_cpu_seconds()

    def stop(self):
        wall = time.monotonic() - self.t0
        busy = _cpu_busy_seconds()
        if busy is None or self.busy0 is None or wall <= 0:
            others = float("nan")
        else:
            others = max(0.0, ((busy - self.busy0) - (_own_cpu_seconds() - self.own0)) / wall)
        return {"other_cores": others, "loadavg": self.loadavg, "gpu_busy_pct": self.gpu_pct, "wall_s": wall}


def host_load(seconds=2.0):
    """The host's load now, this process idle for `seconds`: others' CPU use (cores), the load
    average, the host's cores and (where nvidia-smi answers) the GPU's utilisation."""
    probe = LoadProbe(gpu=True)
    time.sleep(seconds)
    out = probe.stop()
    out["cpu_cores"] = os.cpu_count()
    return out


def worst_load(loads):
    """The worst of several rounds' loads (each a LoadProbe.stop() dict)."""

    def top(key):
        vals = [x[key] for x in loads if x.get(key) is not None and x[key] == x[key]]
        return max(vals) if vals else None

    return {"other_cores": top("other_cores"), "loadavg": top("loadavg"), "gpu_busy_pct": top("gpu_busy_pct")}
